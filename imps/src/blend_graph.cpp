// SPDX-License-Identifier: MIT
// The blend graph over twin classes and its maximal cliques (the field's blend sets).
#include "imps/blend_graph.h"

#include <algorithm>
#include <bit>

#include "imps/check.h"

namespace imps {

BlendGraph::BlendGraph(std::vector<uint32_t> classOf, size_t classCount)
    : classOf_(std::move(classOf)), adj_(classCount * classCount, 0), selfBlend_(classCount, 1) {
  memberOffsets_.assign(classCount + 1, 0);
  for (uint32_t c : classOf_) {
    IMPS_CHECK_LT(c, classCount);
    ++memberOffsets_[c + 1];
  }
  for (size_t c = 0; c < classCount; ++c) memberOffsets_[c + 1] += memberOffsets_[c];
  members_.resize(classOf_.size());
  std::vector<uint32_t> fill(memberOffsets_.begin(), memberOffsets_.end() - 1);
  for (size_t i = 0; i < classOf_.size(); ++i) members_[fill[classOf_[i]]++] = static_cast<uint32_t>(i);
}

std::span<const uint32_t> BlendGraph::members(uint32_t cls) const {
  return {members_.data() + memberOffsets_[cls], members_.data() + memberOffsets_[cls + 1]};
}

void BlendGraph::setBlend(uint32_t a, uint32_t b, bool blend) {
  if (a == b) return;
  adj_[a * classCount() + b] = adj_[b * classCount() + a] = blend ? 1 : 0;
}

void BlendGraph::setSelfBlend(uint32_t a, bool blend) { selfBlend_[a] = blend ? 1 : 0; }

bool BlendGraph::complete() const {
  for (uint32_t a = 0; a < classCount(); ++a) {
    if (members(a).empty()) continue;
    if (members(a).size() > 1 && !selfBlend_[a]) return false;
    for (uint32_t b = a + 1; b < classCount(); ++b)
      if (!members(b).empty() && !blends(a, b)) return false;
  }
  return true;
}

std::vector<uint32_t> BlendGraph::neighbours(size_t i) const {
  std::vector<uint32_t> out;
  const uint32_t a = classOf_[i];
  for (uint32_t b = 0; b < classCount(); ++b)
    if (blends(a, b))
      for (uint32_t m : members(b))
        if (m != i) out.push_back(m);
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

using Bits = std::vector<uint64_t>;

bool none(const Bits& s) {
  return std::all_of(s.begin(), s.end(), [](uint64_t w) { return w == 0; });
}

// Bron–Kerbosch with Tomita pivoting over vertex bit sets: every maximal clique containing R, extended from P and
// excluding X, is reported once. Vertices are visited in ascending order, so the output order is deterministic.
class CliqueSearch {
 public:
  CliqueSearch(const std::vector<Bits>& adj, size_t limit) : adj_(adj), limit_(limit) {}

  bool run(size_t n, std::vector<std::vector<uint32_t>>& out) {
    const size_t words = (n + 63) / 64;
    Bits p(words, 0), x(words, 0);
    for (size_t v = 0; v < n; ++v) p[v / 64] |= uint64_t{1} << (v % 64);
    out_ = &out;
    std::vector<uint32_t> r;
    expand(r, p, x);
    return !overflow_;
  }

 private:
  void expand(std::vector<uint32_t>& r, Bits& p, Bits& x) {
    if (overflow_) return;
    if (none(p)) {
      if (none(x)) {
        if (out_->size() >= limit_) overflow_ = true;
        else out_->push_back(r);
      }
      return;
    }
    const Bits& pivotNb = adj_[pivot(p, x)];
    for (size_t w = 0; w < p.size(); ++w) {
      uint64_t branches = p[w] & ~pivotNb[w];  // P minus the pivot's neighbours: one branch per vertex
      while (branches != 0) {
        const size_t v = w * 64 + static_cast<size_t>(std::countr_zero(branches));
        branches &= branches - 1;
        Bits p2(p.size()), x2(p.size());
        for (size_t k = 0; k < p.size(); ++k) {
          p2[k] = p[k] & adj_[v][k];
          x2[k] = x[k] & adj_[v][k];
        }
        r.push_back(static_cast<uint32_t>(v));
        expand(r, p2, x2);
        r.pop_back();
        p[v / 64] &= ~(uint64_t{1} << (v % 64));
        x[v / 64] |= uint64_t{1} << (v % 64);
      }
    }
  }

  // The vertex of P ∪ X with the most neighbours in P.
  size_t pivot(const Bits& p, const Bits& x) const {
    size_t best = 0;
    int bestCount = -1;
    for (size_t w = 0; w < p.size(); ++w) {
      uint64_t cand = p[w] | x[w];
      while (cand != 0) {
        const size_t u = w * 64 + static_cast<size_t>(std::countr_zero(cand));
        cand &= cand - 1;
        int count = 0;
        for (size_t k = 0; k < p.size(); ++k) count += std::popcount(p[k] & adj_[u][k]);
        if (count > bestCount) bestCount = count, best = u;
      }
    }
    return best;
  }

  const std::vector<Bits>& adj_;
  size_t limit_;
  std::vector<std::vector<uint32_t>>* out_ = nullptr;
  bool overflow_ = false;
};

}  // namespace

std::expected<std::vector<std::vector<uint32_t>>, size_t> BlendGraph::maximalCliques(size_t limit) const {
  // Vertices: a class whose members blend with each other is one vertex; a class whose members do not is one
  // vertex per member (they share neighbours but never a clique).
  std::vector<std::vector<uint32_t>> vertexMembers;
  std::vector<uint32_t> vertexClass;
  for (uint32_t c = 0; c < classCount(); ++c) {
    const auto m = members(c);
    if (m.empty()) continue;
    if (selfBlend_[c] || m.size() == 1) {
      vertexMembers.emplace_back(m.begin(), m.end());
      vertexClass.push_back(c);
    } else {
      for (uint32_t i : m) {
        vertexMembers.push_back({i});
        vertexClass.push_back(c);
      }
    }
  }
  const size_t n = vertexMembers.size();
  std::vector<Bits> adj(n, Bits((n + 63) / 64, 0));
  for (size_t u = 0; u < n; ++u)
    for (size_t v = 0; v < n; ++v)
      if (vertexClass[u] != vertexClass[v] && blends(vertexClass[u], vertexClass[v]))
        adj[u][v / 64] |= uint64_t{1} << (v % 64);

  std::vector<std::vector<uint32_t>> vertexCliques;
  const bool ok = CliqueSearch(adj, limit).run(n, vertexCliques);
  if (!ok) return std::unexpected(vertexCliques.size());
  std::vector<std::vector<uint32_t>> cliques;
  cliques.reserve(vertexCliques.size());
  for (const auto& vc : vertexCliques) {
    std::vector<uint32_t> set;
    for (uint32_t v : vc) set.insert(set.end(), vertexMembers[v].begin(), vertexMembers[v].end());
    std::sort(set.begin(), set.end());
    cliques.push_back(std::move(set));
  }
  std::sort(cliques.begin(), cliques.end());
  return cliques;
}

}  // namespace imps

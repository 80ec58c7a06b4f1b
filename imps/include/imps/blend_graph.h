// SPDX-License-Identifier: MIT
// The blend graph: which primitives may blend, and the blend sets the field takes its maximum over (field.h).
//
// Two primitives blend only if they are blend neighbours. The field is the maximum over the *maximal cliques* of the
// blend graph of each clique's blend. Within a clique every pair is a neighbour pair, so no term is ever summed with
// the term of a primitive that is not its neighbour; and since every blend is monotone in each term, the maximum
// over maximal cliques equals the maximum over all cliques (a brute-force reference, tested). For the unwanted-
// blending rule's tree (siblings, parent, children) the maximal cliques are the parent–child joint pairs, each with
// all the primitives of both joints.
//
// Primitives that blend with exactly the same primitives are *twins* (the primitives of one joint, before
// BlendGroups split them). The graph is kept over twin classes, so a joint with a thousand primitives costs one
// vertex, and building it is linear in the number of primitives plus the square of the number of classes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <vector>

namespace imps {

class BlendGraph {
 public:
  // `classOf[i]`: the twin class of primitive i, classes numbered 0..classCount-1. Initially no class blends with
  // any other and each class blends within itself.
  BlendGraph(std::vector<uint32_t> classOf, size_t classCount);

  size_t primitiveCount() const { return classOf_.size(); }
  size_t classCount() const { return selfBlend_.size(); }
  uint32_t classOf(size_t primitive) const { return classOf_[primitive]; }
  std::span<const uint32_t> members(uint32_t cls) const;

  // Every pair across classes a and b (a != b) blends, or not.
  void setBlend(uint32_t a, uint32_t b, bool blend);
  // Every pair of distinct members of class a blends, or not.
  void setSelfBlend(uint32_t a, bool blend);
  bool blends(uint32_t a, uint32_t b) const { return a == b ? selfBlend_[a] != 0 : adj_[a * classCount() + b] != 0; }

  // True when every primitive blends with every other (one clique: the flat scene's single set).
  bool complete() const;
  // Primitives that primitive i blends with, ascending, excluding i.
  std::vector<uint32_t> neighbours(size_t i) const;

  // The maximal cliques as sorted primitive lists, in a deterministic order (Bron–Kerbosch with Tomita pivoting
  // over the classes). Fails with the number found so far when there are more than `limit` (a pathological
  // BlendGroup pattern; the tree rule has at most one per joint).
  std::expected<std::vector<std::vector<uint32_t>>, size_t> maximalCliques(size_t limit) const;

 private:
  std::vector<uint32_t> classOf_;
  std::vector<uint32_t> memberOffsets_, members_;  // CSR: the primitives of each class, ascending
  std::vector<uint8_t> adj_;                       // classCount x classCount, symmetric, diagonal unused
  std::vector<uint8_t> selfBlend_;
};

}  // namespace imps

#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Streaming poses between processes over loopback OSC (docs/osc.md), as a stage would: one armature host (a stepped
# replay with two --osc-out targets) feeds two receiver processes (osc_receive_check: every frame arrives, in order,
# and the sender → receiver latency is printed) and a render host (`puppeteer live --device osc.udp://…`), which
# must end up showing exactly the armature host's last mesh. Malformed datagrams sent to a receiver and to the
# render host mid-stream are counted and survived.
# Usage: osc_stream_test.sh PUPPETEER SOURCE_DIR OSC_RECEIVE_CHECK XVFB_RUN
set -euo pipefail
puppeteer=$1 src=$2 check=$3 xvfb=$4
work=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM -- "-$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
scene=$src/examples/simple_biped.wrl
bvh=$src/tests/data/bvh/biped_wave.bvh
view=(--no-hud --width 160 --height 120 --polygonizer mc --mesh-hashes)

# 1. Two receivers, each in its own process, writing their (ephemeral) ports once bound.
setsid "$check" "$work/r1.port" 4000 2 >"$work/r1.txt" 2>&1 & pids+=($!)
setsid "$check" "$work/r2.port" 4000 >"$work/r2.txt" 2>&1 & pids+=($!)
for f in r1 r2; do
  for _ in $(seq 200); do [ -s "$work/$f.port" ] && break; sleep 0.05; done
  [ -s "$work/$f.port" ] || { echo "FAIL: receiver $f did not start"; exit 1; }
done
p1=$(cat "$work/r1.port") p2=$(cat "$work/r2.port")

# Usage errors: exit codes as docs/cli.md says.
expect_exit() {  # CODE PATTERN COMMAND…: the command exits with CODE and prints PATTERN on stderr
  local code=$1 pattern=$2 rc=0; shift 2
  "$@" >/dev/null 2>"$work/err" || rc=$?
  [ "$rc" -eq "$code" ] && grep -q -- "$pattern" "$work/err" \
    || { cat "$work/err"; echo "FAIL: expected exit $code and '$pattern' from: $*"; exit 1; }
}
expect_exit 2 "is an OSC pose stream" "$puppeteer" record --device "osc.udp://:$p1" -o "$work/x.session"
expect_exit 2 "osc:1:11: error: expected HOST:PORT" "$puppeteer" live "$scene" --device sim: --osc-out osc.udp://nohost
expect_exit 3 "cannot listen: Address already in use" "$puppeteer" live "$scene" --device "osc.udp://127.0.0.1:$p2"
expect_exit 2 "spec:1:12: error: expected a UDP port" "$puppeteer" live "$scene" --device "osc.udp://:99999"

# 2. The render host listens on a free port of its own; its stdout is line-buffered so its hashes can be followed.
for _ in $(seq 20); do
  p3=$((20000 + RANDOM % 20000))
  ss -Hlun "sport = :$p3" | grep -q . || break
done
setsid stdbuf -oL "$xvfb" -a "$puppeteer" live "$scene" --device "osc.udp://127.0.0.1:$p3" --frames 100000 \
  "${view[@]}" >"$work/render.txt" 2>&1 & pids+=($!)
for _ in $(seq 600); do ss -Hlun "sport = :$p3" | grep -q . && break; sleep 0.05; done
ss -Hlun "sport = :$p3" | grep -q . \
  || { cat "$work/render.txt"; echo "FAIL: the render host is not listening"; exit 1; }

# 3. The armature host streams every pose it shows to the three; garbage reaches r1 and the render host as it starts.
"$xvfb" -a "$puppeteer" replay "$bvh" "$scene" --stepped --frames 30 "${view[@]}" --osc-out "osc.udp://127.0.0.1:$p1" \
  --osc-out "osc.udp://127.0.0.1:$p2" --osc-out "osc.udp://127.0.0.1:$p3" >"$work/host.txt" 2>&1 &
host=$!
sleep 0.5
for p in "$p1" "$p3"; do
  printf 'garbage' >"/dev/udp/127.0.0.1/$p"                       # not a multiple of 4 bytes
  printf '/imps/joint/X\0\0\0,f\0\0' >"/dev/udp/127.0.0.1/$p"  # its argument missing
done
wait "$host" || { cat "$work/host.txt"; echo "FAIL: the armature host failed"; exit 1; }
cat "$work/host.txt" | grep -v '^frame '
clean='.*OSC out: \([0-9]*\) frames, \([0-9]*\) bundles sent, 0 dropped (queue full), 0 send errors to 3 target.*'
sent=$(sed -n "s/$clean/\1 \2/p" "$work/host.txt")
[ -n "$sent" ] || { echo "FAIL: the armature host did not report a clean stream"; exit 1; }
frames=${sent% *}
[ "${sent#* }" -eq $((3 * frames)) ] || { echo "FAIL: not every frame went to every target"; exit 1; }

# 4. Both receivers got frames 0 … frames-1, in order (their exit status), r1 counted exactly the two bad datagrams.
for i in 0 1; do
  wait "${pids[$i]}" || { cat "$work/r$((i + 1)).txt"; echo "FAIL: receiver $((i + 1))"; exit 1; }
  cat "$work/r$((i + 1)).txt"
  grep -q "^received $frames first 0 last $((frames - 1)) dropped 0 out_of_order 0 malformed $((i == 0 ? 2 : 0)) " \
    "$work/r$((i + 1)).txt" || { echo "FAIL: receiver $((i + 1)) did not get all $frames frames"; exit 1; }
done

# 5. The render host, garbage notwithstanding, shows the armature host's last mesh (same pose, bit for bit).
last=$(grep '^frame ' "$work/host.txt" | tail -n 1 | awk '{print $4}')
for _ in $(seq 600); do grep -q " hash $last " "$work/render.txt" && break; sleep 0.05; done
grep -q " hash $last " "$work/render.txt" \
  || { tail -n 5 "$work/render.txt"; echo "FAIL: the render host never showed the last pose"; exit 1; }
echo "PASS: $frames frames to 2 receivers in order; the render host reproduced the last mesh ($last)"

#!/usr/bin/env bash
# The live app run headless under Xvfb + Mesa llvmpipe, as a user would: screenshots of the biped at rest and with
# its left arm lowered (not blank, same size, different only where the arm moved), then a stepped replay of a
# BVH-derived session run twice must produce the same mesh sequence (hash per frame); finally the same session
# streamed at 1 kHz by a simulated armature through the binary protocol and a device session drives the app live.
# Usage: viewer_app_test.sh PUPPETEER SOURCE_DIR VIEWER_SHOT_CHECK XVFB_RUN
set -euo pipefail
puppeteer=$1 src=$2 checker=$3 xvfb=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$src/examples/simple_biped.wrl
run() { "$xvfb" -a "$puppeteer" "$@"; }

# 1. view: rest pose and posed, both polygonizers.
run view "$scene" --frames 30 --screenshot "$work/rest.png" --no-hud --width 640 --height 480
run view "$scene" --frames 30 --screenshot "$work/posed.png" --no-hud --width 640 --height 480 \
    --pose L_UpperArm=0,0,1,-1.2
"$checker" "$work/rest.png" "$work/posed.png" 0.1
run view "$scene" --frames 3 --polygonizer mc --screenshot "$work/rest_mc.png" --no-hud --width 640 --height 480
run view "$scene" --frames 3 --polygonizer mc --screenshot "$work/posed_mc.png" --no-hud --width 640 --height 480 \
    --pose L_UpperArm=0,0,1,-1.2
"$checker" "$work/rest_mc.png" "$work/posed_mc.png" 0.1

# 2. Bad input fails cleanly.
if run view "$scene" --frames 1 --pose NoSuchJoint=0,0,1,1 >/dev/null 2>"$work/err"; then
  echo "FAIL: unknown joint accepted"; exit 1
fi
grep -q "no joint of that name" "$work/err"

# 3. replay: the same BVH-derived session gives the same meshes every run.
bvh=$src/tests/data/bvh/biped_wave.bvh
run replay "$bvh" "$scene" --stepped --frames 40 --mesh-hashes --no-hud --width 320 --height 240 \
    | grep '^frame ' >"$work/hashes1"
run replay "$bvh" "$scene" --stepped --frames 40 --mesh-hashes --no-hud --width 320 --height 240 \
    | grep '^frame ' >"$work/hashes2"
[ "$(wc -l <"$work/hashes1")" -eq 40 ] || { echo "FAIL: expected 40 frame hashes"; exit 1; }
[ "$(awk '{print $4}' "$work/hashes1" | sort -u | wc -l)" -gt 10 ] || { echo "FAIL: the replayed meshes do not change"; exit 1; }
diff "$work/hashes1" "$work/hashes2" || { echo "FAIL: replay is not deterministic"; exit 1; }
# 4. live: sim armature → device session → pose mailbox → joints by channel name → screen.
run replay "$bvh" "$scene" --frames 1 --no-hud --width 320 --height 240 --export-session "$work/wave.session" >/dev/null
run live "$scene" --device "sim:$work/wave.session?rate=1000" --frames 60 --no-hud --width 640 --height 480 \
    --screenshot "$work/live.png" | tee "$work/live.txt"
grep -q "sample-to-screen latency over" "$work/live.txt" || { echo "FAIL: no samples reached the screen"; exit 1; }
[ -s "$work/live.png" ] || { echo "FAIL: no live screenshot"; exit 1; }
# 5. live through the serial path with the calibration library: `puppeteer sim` serves a simulated armature on a
#    pseudo-terminal; the app opens it as a serial port, streams at 1 kHz, calibrates and renders.
"$puppeteer" sim --pty --link "$work/arm" --device 'sim:?channels=32' >"$work/sim.log" 2>&1 &
sim_pid=$!
for _ in $(seq 100); do [ -e "$work/arm" ] && break; sleep 0.1; done
status=0
run live "$scene" --device "serial:$work/arm?rate=1000" --calibration "$src/examples/simple_biped.calibration.json" \
    --frames 150 --width 640 --height 480 --screenshot "$work/live_serial.png" >"$work/live_serial.txt" 2>&1 || status=$?
kill "$sim_pid" 2>/dev/null || true
wait "$sim_pid" 2>/dev/null || true
cat "$work/live_serial.txt"
[ "$status" -eq 0 ] || { echo "FAIL: live over the serial path exited with $status"; exit 1; }
grep -q "sample-to-screen latency over" "$work/live_serial.txt" || { echo "FAIL: no serial samples reached the screen"; exit 1; }
echo "viewer app test: ok"

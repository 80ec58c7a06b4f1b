#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The live app run headless under Xvfb + Mesa llvmpipe, as a user would: screenshots of the biped at rest and with
# its left arm lowered (not blank, same size, different only where the arm moved), then a stepped replay of a
# BVH-derived session run twice must produce the same mesh sequence (hash per frame); finally the same session
# streamed at 1 kHz by a simulated armature through the binary protocol and a device session drives the app live.
# Then the scripted-input features: a mouse drag on the left arm (the arcball manipulator) changes the picture where
# the arm moved; `--record` captures every sample the simulator sent, bit for bit, with the calibration in force;
# keys o (start/stop a take) and k (re-calibrate: saved, applied, recorded; a noisy window rejected).
# Usage: viewer_app_test.sh PUPPETEER SOURCE_DIR VIEWER_SHOT_CHECK XVFB_RUN SESSION_MATCH_CHECK
set -euo pipefail
source "$(dirname "$0")/xvfb_run.sh"
puppeteer=$1 src=$2 checker=$3 xvfb=$4 match=$5
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$src/examples/simple_biped.wrl
run() { xvfb_run "$xvfb" "$puppeteer" "$@"; }

# 1. view: rest pose and posed, both polygonizers.
run view "$scene" --frames 30 --screenshot "$work/rest.png" --no-hud --width 640 --height 480
run view "$scene" --frames 30 --screenshot "$work/posed.png" --no-hud --width 640 --height 480 \
    --pose L_UpperArm=0,0,1,-69
"$checker" "$work/rest.png" "$work/posed.png" 0.1
run view "$scene" --frames 3 --polygonizer mc --screenshot "$work/rest_mc.png" --no-hud --width 640 --height 480
run view "$scene" --frames 3 --polygonizer mc --screenshot "$work/posed_mc.png" --no-hud --width 640 --height 480 \
    --pose L_UpperArm=0,0,1,-69
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
#    --overlap polygonizes on a worker thread one frame ahead: the same meshes, each drawn one frame later.
run replay "$bvh" "$scene" --stepped --frames 41 --mesh-hashes --no-hud --width 320 --height 240 --overlap \
    | grep '^frame ' | tail -n 40 | awk '{print $4, $6}' >"$work/hashes_overlap"
awk '{print $4, $6}' "$work/hashes1" | diff - "$work/hashes_overlap" \
  || { echo "FAIL: --overlap changed the mesh sequence"; exit 1; }
# 4. live: sim armature → device session → pose mailbox → joints by channel name → screen.
run replay "$bvh" "$scene" --frames 1 --no-hud --width 320 --height 240 --export-session "$work/wave.session" >/dev/null
#    Recorded from launch (--record): the take holds every sample the simulator sent, bit for bit.
run live "$scene" --device "sim:$work/wave.session?rate=1000" --frames 60 --no-hud --width 640 --height 480 \
    --screenshot "$work/live.png" --record "$work/take.session" | tee "$work/live.txt"
grep -q "sample-to-screen latency over" "$work/live.txt" || { echo "FAIL: no samples reached the screen"; exit 1; }
[ -s "$work/live.png" ] || { echo "FAIL: no live screenshot"; exit 1; }
grep -q "recorded [0-9]* samples .* to $work/take.session" "$work/live.txt" || { echo "FAIL: no recording reported"; exit 1; }
"$puppeteer" info "$work/take.session" | tee "$work/take_info.txt"
grep -q "closed cleanly" "$work/take_info.txt" || { echo "FAIL: the take was not closed cleanly"; exit 1; }
"$match" "$work/take.session" "$work/wave.session" 100
if run live "$scene" --device "sim:$work/wave.session" --frames 1 --record "$work/take.session" >/dev/null 2>&1; then
  echo "FAIL: --record overwrote an existing file"; exit 1
fi
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

# 6. The manipulator, driven by a scripted drag: grabbing the left upper arm and dragging down picks L_UpperArm and
#    lowers the arm; the picture changes where the arm moved and not in the legs.
run view "$scene" --frames 30 --screenshot "$work/dragged.png" --no-hud --width 640 --height 480 \
    --drag 363,170,375,250@1 | tee "$work/drag.txt"
grep -q "drag 363,170 -> 375,250: arcball L_UpperArm" "$work/drag.txt" || { echo "FAIL: the drag did not pick L_UpperArm"; exit 1; }
"$checker" "$work/rest.png" "$work/dragged.png" 0.1

# 7. Keys o and k, scripted, on a still in-process armature (a sine period of a day) at 1 kHz with the example
#    calibration: o starts a take in --record-dir, k re-calibrates (no countdown, a 200 ms window), saves to
#    --calibration-out and applies it; the second o closes the take, which holds both calibrations.
still='sim:?channels=32&rate=1000&period_s=86400'
mkdir "$work/takes"
run live "$scene" --device "$still" --calibration "$src/examples/simple_biped.calibration.json" \
    --calibration-out "$work/recal.json" --calibrate-delay-ms 0 --window-ms 200 --record-dir "$work/takes" \
    --keys o@2,k@5,o@70 --frames 80 --width 640 --height 480 --screenshot "$work/keys.png" | tee "$work/keys.txt"
grep -q "recording to $work/takes/take-" "$work/keys.txt" || { echo "FAIL: o did not start a take"; exit 1; }
grep -q "calibrated 32 channels from [0-9]* samples .* saved $work/recal.json" "$work/keys.txt" \
  || { echo "FAIL: k did not calibrate"; exit 1; }
grep -q "recorded [0-9]* samples" "$work/keys.txt" || { echo "FAIL: the second o did not close the take"; exit 1; }
take=$(ls "$work"/takes/take-*.session)
"$puppeteer" info "$take" | tee "$work/keys_info.txt"
grep -q "calibrations: 2" "$work/keys_info.txt" || { echo "FAIL: the take should hold both calibrations"; exit 1; }
#    The saved calibration drives the app.
run live "$scene" --device "$still" --calibration "$work/recal.json" --frames 5 --no-hud --width 320 --height 240 >/dev/null
#    A noisy armature: the window is rejected with the reason and nothing is written.
run live "$scene" --device "$still&noise=60" --calibration "$src/examples/simple_biped.calibration.json" \
    --calibration-out "$work/noisy.json" --calibrate-delay-ms 0 --window-ms 200 --keys k@3 --frames 60 --no-hud \
    --width 320 --height 240 >"$work/noisy.txt"
grep -q "calibration rejected .* too noisy" "$work/noisy.txt" || { cat "$work/noisy.txt"; echo "FAIL: a noisy window was accepted"; exit 1; }
[ ! -e "$work/noisy.json" ] || { echo "FAIL: a rejected calibration was written"; exit 1; }

# 8. Issue 14 item 7: a device that cannot be opened is said on the terminal, and a run that never received a
#    sample exits 3 (docs/cli.md) with nothing recorded.
status=0
run live "$scene" --device serial:/dev/ttyNOPE --frames 5 --width 320 --height 240 --record "$work/nope.session" \
    >"$work/nope.txt" 2>&1 || status=$?
cat "$work/nope.txt"
[ "$status" -eq 3 ] || { echo "FAIL: live without a device exited with $status, expected 3"; exit 1; }
grep -q "ttyNOPE.*no such serial port" "$work/nope.txt" || { echo "FAIL: the device's error was not printed"; exit 1; }
[ ! -e "$work/nope.session" ] || { echo "FAIL: a take without samples was written"; exit 1; }

# 9. Issue 14 item 5: Ctrl-C (SIGINT) or SIGTERM during `live --record` closes the take (END record), prints the
#    summary and exits 0. The wrapper records puppeteer's own pid for the signal.
for sig in INT TERM; do
  rm -f "$work/pid"
  "$xvfb" -a bash -c '"$@" & echo $! >"'"$work"'/pid"; wait $!' _ "$puppeteer" live "$scene" --device "$still" \
      --record "$work/sig$sig.session" --no-hud --width 320 --height 240 >"$work/sig.txt" 2>&1 &
  wrapper=$!
  for _ in $(seq 600); do [ -s "$work/pid" ] && [ -s "$work/sig$sig.session" ] && break; sleep 0.1; done
  [ -s "$work/sig$sig.session" ] || { cat "$work/sig.txt"; echo "FAIL: live --record never created its take"; exit 1; }
  kill -"$sig" "$(cat "$work/pid")"
  for _ in $(seq 300); do kill -0 "$(cat "$work/pid")" 2>/dev/null || break; sleep 0.1; done
  if kill -0 "$(cat "$work/pid")" 2>/dev/null; then
    kill -KILL "$(cat "$work/pid")"; echo "FAIL: SIG$sig did not end live"; exit 1
  fi
  status=0
  wait "$wrapper" || status=$?
  cat "$work/sig.txt"
  [ "$status" -eq 0 ] || { echo "FAIL: live exited with $status after SIG$sig, expected 0"; exit 1; }
  grep -q "recorded [0-9]* samples .* to $work/sig$sig.session" "$work/sig.txt" \
    || { echo "FAIL: no take summary after SIG$sig"; exit 1; }
  "$puppeteer" info "$work/sig$sig.session" >"$work/sig_info.txt"
  grep -q "closed cleanly" "$work/sig_info.txt" || { cat "$work/sig_info.txt"; echo "FAIL: SIG$sig left the take open"; exit 1; }
done
echo "viewer app test: ok"

#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Bounded work on hostile inputs, run as a user would: sizes beyond the limits are refused with a message that says
# the limit and how to raise it (exit 1 for a file's value, 2 for the command line's), endless inputs are refused
# at their limit, and a file-size limit (ulimit -f) fails a save like a full disk: a message, exit 3, nothing left.
# Usage: limits_test.sh PUPPETEER SOURCE_DIR
set -u
puppeteer=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
passed=0
failed=0

expect() {  # expect NAME EXPECTED_EXIT COMMAND...
  local name=$1 want=$2
  shift 2
  "$@" >"$work/out" 2>"$work/err"
  local got=$?
  if [ "$got" -eq "$want" ]; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $name: exit $got, expected $want"
    sed 's/^/  stdout: /' "$work/out" | head -5
    sed 's/^/  stderr: /' "$work/err" | head -5
  fi
}
check() {  # check NAME CONDITION...
  local name=$1
  shift
  if "$@"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $name"; sed 's/^/  stderr: /' "$work/err" | head -5; fi
}

# Marching Cubes grids beyond --max-cells (was: an uncaught std::length_error, or gigabytes).
expect "mesh --cell 1e-9" 2 "$puppeteer" mesh "$src/examples/flubber.wrl" --cell 1e-9 -o "$work/x.ply"
check "the limit and how to raise it" grep -q "^puppeteer mesh: error: --cell 1e-09: a grid of .* is more than the limit of 268435456 cells; use larger cells, or raise the limit with --max-cells N" "$work/err"
check "no output" test ! -e "$work/x.ply"
printf '#VRML V2.0 utf8\nMarchingCubes {\n  cellSize 1e-7\n  sceneGraph Metaball { radius 0.2 }\n}\n' >"$work/tiny.wrl"
expect "scene cellSize 1e-7" 1 "$puppeteer" mesh "$work/tiny.wrl" -o "$work/x.ply"
check "the scene value's file:line:column" grep -q "tiny.wrl:3:12: the scene's MarchingCubes resolution: a grid of" "$work/err"
expect "a raised limit is honoured" 2 "$puppeteer" mesh "$src/examples/flubber.wrl" --res 64 --max-cells 1000 -o "$work/x.ply"
printf '#VRML V2.0 utf8\nMarchingCubes { numThreads 2147483647 sceneGraph Metaball { radius 0.2 } }\n' >"$work/threads.wrl"
expect "scene numThreads 2147483647" 1 "$puppeteer" mesh "$work/threads.wrl" -o "$work/x.ply"
check "threads range with location" grep -q "threads.wrl:2:28: error: field 'numThreads' of MarchingCubes must be between 0 and 1024" "$work/err"

# Particles: a tiny desiredRadius stops at --max-particles with a warning at the scene's value; 300 particles that far
# apart make no triangle, so the always-on particle check fails (exit 4).
printf '#VRML V2.0 utf8\nTesselator3MP {\n  desiredRadius 0.001\n  sceneGraph Metaball { radius 0.2 }\n}\n' >"$work/fine.wrl"
expect "particles at their limit" 4 "$puppeteer" mesh "$work/fine.wrl" --polygonizer particles --updates 2 \
  --max-particles 300 -o "$work/p.ply"
check "warning names the value and the option" grep -q "fine.wrl:3:17: warning: the particles reached their limit of 300 .*--max-particles N" "$work/err"

# Endless and huge inputs are refused at their limit (was: memory until the process died).
expect "info /dev/zero" 1 "$puppeteer" info /dev/zero
check "not a session" grep -q "/dev/zero: error: not a session file: bad magic" "$work/err"
ln -s /dev/zero "$work/endless.bvh"
expect "convert an endless BVH" 1 "$puppeteer" convert "$work/endless.bvh" "$work/endless.session"
check "the BVH limit" grep -q "endless.bvh: error: cannot read BVH file: larger than the 256 MiB limit" "$work/err"
expect "convert a 1e308 frame time" 1 "$puppeteer" convert "$src/tests/fuzz/seeds/bvh_session/error_frame_time_1e308.bvh" "$work/t.session"
check "frame time bound" grep -q "error_frame_time_1e308.bvh:9:13: error: frame time 1e308 s is longer than the 3600 s" "$work/err"
expect "calibrate --rig /dev/zero" 1 "$puppeteer" calibrate --rig /dev/zero --scene "$src/examples/simple_biped.wrl" \
  --session "$src/examples/simple_biped_wave.session" -o "$work/cal.json"
check "the rig map limit" grep -q "/dev/zero: error: cannot read rig map: larger than the 16 MiB limit" "$work/err"

# A file-size limit: the save fails like a full disk (was: killed by SIGXFSZ, leaving existing.glb.tmp-PID-0).
echo "precious" >"$work/existing.glb"
expect "mesh under ulimit -f" 3 bash -c "ulimit -f 1; exec \"\$0\" mesh \"\$1\" --res 48 -o \"\$2\"" "$puppeteer" \
  "$src/examples/flubber.wrl" "$work/existing.glb"
check "the write error is reported" grep -q "cannot save '$work/existing.glb': writing: File too large" "$work/err"
check "the existing file is untouched" grep -q "precious" "$work/existing.glb"
check "no temporary file left" test -z "$(ls "$work" | grep '\.tmp')"
expect "record under ulimit -f" 3 bash -c "ulimit -f 8; exec \"\$0\" record --device 'sim:?rate=1000&channels=32' -o \"\$1\" --seconds 2" \
  "$puppeteer" "$work/take.session"
check "record says why, once" test "$(grep -c 'File too large' "$work/err")" -eq 1

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]

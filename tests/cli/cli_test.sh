#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The command line as a user meets it: exit codes, messages, files written (and not clobbered on failure).
# Usage: cli_test.sh PUPPETEER SOURCE_DIR
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
  if "$@"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "FAIL: $name"; fi
}

expect "help" 0 "$puppeteer" --help
expect "no command" 2 "$puppeteer"
expect "unknown option" 2 "$puppeteer" mesh "$src/examples/flubber.wrl" -o "$work/x.ply" --bogus
expect "cell and res together" 2 "$puppeteer" mesh "$src/examples/flubber.wrl" -o "$work/x.ply" --cell 0.1 --res 10

# check: every example is valid and its listing names its joints.
for f in "$src"/examples/*.wrl; do expect "check $(basename "$f")" 0 "$puppeteer" check "$f"; done
"$puppeteer" check "$src/examples/simple_biped.wrl" >"$work/out"
check "check lists the biped's joints" grep -q "L_Forearm" "$work/out"
check "check lists 18 primitives" grep -q "primitives (18)" "$work/out"

# check: a broken scene gives file:line:column errors and exit 1.
printf '#VRML V2.0 utf8\nMetaball {\n  radius -2\n  centre 0 0 0\n}\n' >"$work/bad.wrl"
expect "check bad scene" 1 "$puppeteer" check "$work/bad.wrl"
check "error has file:line:column" grep -q "bad.wrl:3:[0-9]*: error:" "$work/err"
check "misspelt field gets a suggestion" grep -q "did you mean 'center'" "$work/err"

# mesh: each format is written, the mesh is reported closed.
for ext in obj ply glb; do
  expect "mesh to $ext" 0 "$puppeteer" mesh "$src/examples/flubber.wrl" --res 32 --check -o "$work/flubber.$ext"
  check "mesh reports a closed manifold ($ext)" grep -q "topology: closed 2-manifold" "$work/out"
  check "$ext file is not empty" test -s "$work/flubber.$ext"
done
check "glb magic" test "$(head -c 4 "$work/flubber.glb")" = "glTF"
check "ply header" test "$(head -c 3 "$work/flubber.ply")" = "ply"

# mesh: 1 thread and 2 threads write identical files.
"$puppeteer" mesh "$src/examples/simple_biped.wrl" --cell 0.03 --threads 1 -o "$work/one.ply" >/dev/null
"$puppeteer" mesh "$src/examples/simple_biped.wrl" --cell 0.03 --threads 2 -o "$work/two.ply" >/dev/null
check "1 and 2 threads give identical files" cmp -s "$work/one.ply" "$work/two.ply"

# mesh: a bad output is refused with exit 3 and the existing file is left alone.
echo "precious" >"$work/keep.txt"
expect "unknown output extension" 2 "$puppeteer" mesh "$src/examples/flubber.wrl" -o "$work/keep.txt"
check "existing file untouched" grep -q "precious" "$work/keep.txt"
expect "unwritable output directory" 3 "$puppeteer" mesh "$src/examples/flubber.wrl" -o "$work/no/such/dir/x.ply"
expect "mesh of a bad scene" 1 "$puppeteer" mesh "$work/bad.wrl" -o "$work/bad.ply"
check "no output for a bad scene" test ! -e "$work/bad.ply"

# render: a PNG.
expect "render" 0 "$puppeteer" render "$src/examples/beanito.wrl" --res 32 --width 64 --height 64 -o "$work/b.png"
check "png magic" test "$(head -c 4 "$work/b.png" | tail -c 3)" = "PNG"

# devices: lists what is attached (here: possibly nothing) and exits 0.
# mesh --check: a mesh that is not a closed 2-manifold is written, reported and exits 4 (issue 14 item 8); two
# tesselator updates leave the swarm's particles short of settled: holes remain and a component is missing (settled,
# at the spacing its feature size gives, it meshes closed with all of Marching Cubes' components; docs/tesselator.md).
expect "incomplete particle mesh fails --check" 4 "$puppeteer" mesh "$src/examples/swarm_1000.wrl" \
  --polygonizer particles --updates 2 --check -o "$work/swarm.ply"
check "incomplete mesh is reported" grep -Eq "not a closed 2-manifold|components where Marching Cubes finds" "$work/err"
check "incomplete mesh is still written" test -s "$work/swarm.ply"
# A particle mesh is always checked (issue 15): without --check too.
expect "particle mesh checked without --check" 4 "$puppeteer" mesh "$src/examples/swarm_1000.wrl" \
  --polygonizer particles --updates 2 -o "$work/swarm2.ply"

expect "devices" 0 "$puppeteer" devices

# record (issue 14 items 1, 4, 6): a line-protocol device whose boot banner is a number keeps its 8-channel layout
# and every sample; the summary and info show every counter of the link.
expect "record a line device with a numeric banner" 0 "$puppeteer" record \
  --device 'sim:?protocol=lines&banner=115200&channels=8&rate=200' -o "$work/banner.session" --seconds 0.5
check "no sample skipped" test -z "$(grep -i "skipped\|different device" "$work/out")"
check "record summary shows the link counters" grep -q "line parse errors: 0" "$work/out"
expect "info on the banner take" 0 "$puppeteer" info "$work/banner.session"
check "the take has the settled 8-channel layout" grep -q "1 device" "$work/out"
check "the take's device has 8 channels" grep -q ": 8 channels of" "$work/out"
check "info shows the stored counters" grep -q "device link counters (device 0):.*garbage bytes: 0" "$work/out"
#   --seconds counts from the first sample: a device that boots for 2 s still gives a take of about 1 s.
expect "record a slow-booting device" 0 "$puppeteer" record --device 'sim:?rate=200&boot_ms=2000' \
  -o "$work/slow.session" --seconds 1
"$puppeteer" info "$work/slow.session" >"$work/out"
check "a 1 s take of a slow-booting device spans most of 1 s" \
  awk '/samples over/ { if ($4 + 0 >= 0.5) ok = 1 } END { exit !ok }' "$work/out"
#   an unplugged and replugged device: info locates the outage and calls the reboot a reboot.
expect "record through an unplug" 0 "$puppeteer" record --device 'sim:?rate=200&unplug_ms=300&replug_ms=600' \
  -o "$work/unplug.session" --seconds 1.5
"$puppeteer" info "$work/unplug.session" >"$work/out"
check "info locates the outage" grep -q "1 outage" "$work/out"
check "info calls the restart a reboot" grep -q "1 restart of the numbering (device reboots)" "$work/out"

# record from the in-process simulated armature, then calibrate against it. The simulator's generated motion never
# holds still, so calibration must refuse the window as too noisy, say which channels, and write nothing.
expect "record a simulated armature" 0 "$puppeteer" record --device 'sim:?rate=200&channels=32' -o "$work/take.session" --seconds 0.5
check "session file written" test -s "$work/take.session"
expect "record never overwrites" 3 "$puppeteer" record --device 'sim:?rate=200&channels=32' -o "$work/take.session" --seconds 0.2
expect "calibrate rejects a moving armature" 1 "$puppeteer" calibrate --rig "$src/examples/simple_biped.rig.json" \
  --scene "$src/examples/simple_biped.wrl" --session "$work/take.session" -o "$work/cal.json"
check "noisy channels are named" grep -qi "noisy\|noise" "$work/err"
check "no calibration written" test ! -e "$work/cal.json"
printf '{\n  "version": 1,\n  "joints": [ { "joint": "L_Elbo" } ]\n}\n' >"$work/bad.rig.json"
expect "bad rig map" 1 "$puppeteer" calibrate --rig "$work/bad.rig.json" --scene "$src/examples/simple_biped.wrl" \
  --session "$work/take.session" -o "$work/cal.json"
check "rig map error has file:line:column" grep -q "bad.rig.json:[0-9]*:[0-9]*: error:" "$work/err"

# info and convert: a BVH clip becomes a session and back, and info describes it.
expect "convert bvh to session" 0 "$puppeteer" convert "$src/tests/data/bvh/biped_wave.bvh" "$work/wave.session"
expect "info" 0 "$puppeteer" info "$work/wave.session"
check "info reports the samples" grep -q "samples from 1 device" "$work/out"
check "info says the file is whole" grep -q "closed cleanly" "$work/out"
expect "convert session to bvh" 0 "$puppeteer" convert "$work/wave.session" "$work/wave.bvh"
check "bvh hierarchy written" grep -q "^HIERARCHY" "$work/wave.bvh"
expect "convert never overwrites" 3 "$puppeteer" convert "$work/wave.session" "$work/wave.bvh"
expect "convert to an unknown format" 2 "$puppeteer" convert "$work/wave.session" "$work/wave.txt"
head -c 100 "$work/wave.session" >"$work/cut.session"
expect "info on a truncated session still works" 0 "$puppeteer" info "$work/cut.session"
check "truncation is reported" grep -qi "not closed cleanly" "$work/out"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]

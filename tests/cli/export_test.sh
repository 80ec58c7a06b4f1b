#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `puppeteer export` as a user meets it: a BVH clip and a session on the biped as the character's skeleton (BVH),
# a skinned glTF and a numbered surface sequence; the old raw-channel BVH on request; exit codes for bad input.
# Usage: export_test.sh PUPPETEER SOURCE_DIR
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
  if [ "$got" -eq "$want" ]; then passed=$((passed + 1)); else
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
scene=$src/examples/simple_biped.wrl
clip=$src/tests/data/bvh/biped_wave.bvh

expect "clip to the character's skeleton" 0 "$puppeteer" export "$clip" "$scene" -o "$work/wave.bvh"
check "the report lists the mapping" grep -q "L_UpperArm -> L_UpperArm" "$work/out"
check "the skeleton is the character's" grep -q "JOINT L_Clavicle" "$work/wave.bvh"
check "the root moves" grep -q "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" "$work/wave.bvh"
check "quiet when piped (no progress line)" bash -c "! grep -q 'frames/s' '$work/err'"
expect "the exported skeleton reads back" 0 "$puppeteer" convert "$work/wave.bvh" "$work/wave_back.session"

expect "skinned glTF" 0 "$puppeteer" export "$clip" "$scene" -o "$work/wave.glb" --fps 10 --cell 0.05
check "a GLB container" bash -c "head -c 4 '$work/wave.glb' | grep -q glTF"
expect "surface sequence" 0 "$puppeteer" export "$clip" "$scene" -o "$work/seq/s_###.ply" --frames 0:2 --cell 0.06
check "three numbered PLY files" test -f "$work/seq/s_000.ply" -a -f "$work/seq/s_002.ply" -a ! -f "$work/seq/s_003.ply"

expect "session made from a clip" 0 "$puppeteer" convert "$clip" "$work/wave.session"
expect "session to the character's skeleton" 0 "$puppeteer" export "$work/wave.session" "$scene" -o "$work/s.bvh"
expect "raw channels on request" 0 "$puppeteer" export "$work/wave.session" "$scene" -o "$work/raw.bvh" --raw-channels
check "raw channels say what they are" grep -q "raw channels" "$work/out"

expect "unknown output kind" 2 "$puppeteer" export "$clip" "$scene" -o "$work/x.txt"
expect "frames outside the take" 2 "$puppeteer" export "$clip" "$scene" -o "$work/y.bvh" --frames 5:100000
expect "bad frame range text" 2 "$puppeteer" export "$clip" "$scene" -o "$work/y.bvh" --frames five
printf '{"version": 1, "joints": {\n  "L_UpperArn": "L_UpperArm"\n}}\n' >"$work/map.json"
expect "joint map errors" 1 "$puppeteer" export "$clip" "$scene" -o "$work/z.bvh" --map "$work/map.json"
check "joint map error has a location" grep -q "map.json:2:3: error: unknown clip joint 'L_UpperArn'; did you mean 'L_UpperArm'?" "$work/err"
expect "unwritable output" 3 "$puppeteer" export "$clip" "$scene" -o "/nonexistent-dir/w.bvh"
check "nothing written on errors" test ! -e "$work/y.bvh" -a ! -e "$work/z.bvh"

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]

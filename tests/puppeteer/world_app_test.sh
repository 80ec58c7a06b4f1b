#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The live app on a world (examples/two_bipeds.wrl), headless under Xvfb: both characters polygonized by Marching
# Cubes, each driven by its own source (the clip inlined beside it; `--drive` with a clip, a session, or `rest`);
# a different source for one character changes the picture, the same run twice gives the same picture (fixed 1/60 s
# steps), and a --drive naming no character is a usage error before any window opens.
# Usage: world_app_test.sh PUPPETEER SOURCE_DIR XVFB_RUN
set -euo pipefail
source "$(dirname "$0")/xvfb_run.sh"
puppeteer=$1 src=$2 xvfb=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
world=$src/examples/two_bipeds.wrl
run() { xvfb_run "$xvfb" "$puppeteer" view "$world" --polygonizer mc --no-hud --width 480 --height 320 "$@"; }

run --frames 20 --screenshot "$work/a.png" >"$work/a.log"
grep -q "world .*two_bipeds.wrl: 2 characters, 1 props" "$work/a.log" || { cat "$work/a.log"; echo "FAIL: world summary"; exit 1; }
grep -q "WALKER: playing clip WALK" "$work/a.log" || { cat "$work/a.log"; echo "FAIL: WALKER's inlined clip"; exit 1; }
grep -q "WAVER: playing clip WAVE" "$work/a.log" || { cat "$work/a.log"; echo "FAIL: WAVER's inlined clip"; exit 1; }
run --frames 20 --screenshot "$work/b.png" >/dev/null
cmp -s "$work/a.png" "$work/b.png" || { echo "FAIL: two runs of the same world differ"; exit 1; }
run --frames 20 --screenshot "$work/rest.png" --drive WAVER=rest >/dev/null
if cmp -s "$work/a.png" "$work/rest.png"; then echo "FAIL: WAVER at rest looks like WAVER waving"; exit 1; fi
run --frames 20 --screenshot "$work/walk.png" --drive "WAVER=$src/examples/simple_biped_moves.wrl#WALK" >"$work/walk.log"
grep -q "WAVER: playing clip WALK" "$work/walk.log" || { cat "$work/walk.log"; echo "FAIL: --drive clip"; exit 1; }
if cmp -s "$work/a.png" "$work/walk.png"; then echo "FAIL: --drive did not change WAVER"; exit 1; fi
run --frames 10 --drive "WAVER=$src/examples/simple_biped_wave.session" >"$work/session.log"
grep -q "replaying .* samples of simple_biped_wave.session" "$work/session.log" || { cat "$work/session.log"; echo "FAIL: session drive"; exit 1; }

set +e
run --frames 1 --drive WAVR=rest >/dev/null 2>"$work/err"
code=$?
set -e
[ "$code" -eq 2 ] || { echo "FAIL: --drive naming no character exited $code"; exit 1; }
grep -q "the world places no character 'WAVR' (did you mean 'WAVER'?)" "$work/err" || { cat "$work/err"; exit 1; }
echo "world app: OK"

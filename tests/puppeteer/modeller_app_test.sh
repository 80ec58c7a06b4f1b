#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The interactive modeller in the real app, headless under Xvfb, driven by scripted drags and keys as a user would:
# a translate handle dragged moves its metaball to where it was dropped (checked against the scene files by
# modeller_check, from the app's own first camera); a scale handle sets a metaball's radius; a joint handle of an
# unnamed RigidTransform moves it and `s` saves it (as does a --pose on an unnamed joint); Ctrl+Z / Ctrl+Shift+Z undo
# and redo; a saved file re-opens and saves byte for byte the same; --no-manipulators makes the drag orbit; view
# uses the polygonizer the scene file names.
# Usage: modeller_app_test.sh PUPPETEER SOURCE_DIR MODELLER_CHECK XVFB_RUN
set -euo pipefail
source "$(dirname "$0")/xvfb_run.sh"
puppeteer=$1 src=$2 check=$3 xvfb=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
run() { xvfb_run "$xvfb" "$puppeteer" "$@"; }
W=640 H=480
view() { run view "$@" --no-hud --width $W --height $H; }
fail() { echo "FAIL: $*"; exit 1; }
blobs=$src/examples/textured_blobs.wrl

# 1. Translate: drag LEFT's handle 60 px right and 30 px up; save; LEFT is under the cursor where it was dropped.
read -r centre tip < <("$check" handle "$blobs" $W $H LEFT)
cx=${centre%,*} cy=${centre#*,} tx=${tip%,*} ty=${tip#*,}
x1=$(awk "BEGIN{print $cx + 60}") y1=$(awk "BEGIN{print $cy - 30}")
view "$blobs" --frames 4 --drag "$cx,$cy,$x1,$y1@1" --keys s@2 --save-as "$work/moved.wrl" | tee "$work/moved.txt"
grep -q "drag .*: translate LEFT$" "$work/moved.txt" || fail "the drag did not grab LEFT's translate handle"
grep -q "translate LEFT by " "$work/moved.txt" || fail "no edit reported"
"$check" moved "$blobs" "$work/moved.wrl" $W $H LEFT "$x1" "$y1"
"$check" moved "$blobs" "$work/moved.wrl" $W $H RIGHT 0 0 >/dev/null 2>&1 && fail "RIGHT moved too"
#    The saved file re-opens identically: saved again unchanged, it is the same bytes.
view "$work/moved.wrl" --frames 2 --keys s@1 --save-as "$work/moved2.wrl" >/dev/null
cmp "$work/moved.wrl" "$work/moved2.wrl" || fail "a saved scene does not re-open identically"

# 2. Undo and redo: the drag undone saves the untouched document; redone, the moved one.
view "$blobs" --frames 2 --keys s@1 --save-as "$work/orig.wrl" >/dev/null
view "$blobs" --frames 5 --drag "$cx,$cy,$x1,$y1@1" --keys ctrl+z@2,s@3 --save-as "$work/undone.wrl" >/dev/null
cmp "$work/orig.wrl" "$work/undone.wrl" || fail "Ctrl+Z did not restore the document"
view "$blobs" --frames 6 --drag "$cx,$cy,$x1,$y1@1" --keys ctrl+z@2,ctrl+shift+z@3,s@4 \
    --save-as "$work/redone.wrl" >/dev/null
cmp "$work/moved.wrl" "$work/redone.wrl" || fail "Ctrl+Shift+Z did not redo the drag"

# 3. Scale: click LEFT (select), x (scale mode), drag its x-axis tip to 1.5 times its distance: radius 1 → 1.5.
sx=$(awk "BEGIN{print $cx + 1.5 * ($tx - $cx)}") sy=$(awk "BEGIN{print $cy + 1.5 * ($ty - $cy)}")
view "$blobs" --frames 6 --drag "$cx,$cy,$cx,$cy@1" --keys x@2,s@4 --drag "$tx,$ty,$sx,$sy@3" \
    --save-as "$work/scaled.wrl" --screenshot "$work/scaled.png" | tee "$work/scaled.txt"
grep -q "drag .*: scale LEFT x$" "$work/scaled.txt" || fail "the drag did not grab LEFT's scale handle"
"$check" radius "$work/scaled.wrl" LEFT 1.5

# 4. A hierarchical scene whose RigidTransforms have no DEF names (thesis figure A-1): w (translate mode), drag
#    the child transform's handle; saved, the transform is where it was dropped.
tblobs=$src/examples/transformed_blobs.wrl
read -r centre tip < <("$check" handle "$tblobs" $W $H joint:1)
jx=${centre%,*} jy=${centre#*,}
j1=$(awk "BEGIN{print $jx - 40}") k1=$(awk "BEGIN{print $jy + 25}")
view "$tblobs" --frames 4 --polygonizer mc --keys w@0,s@2 --drag "$jx,$jy,$j1,$k1@1" --save-as "$work/joint.wrl" \
    | tee "$work/joint.txt"
grep -q "drag .*: translate joint1$" "$work/joint.txt" || fail "the drag did not grab joint1's handle"
"$check" moved "$tblobs" "$work/joint.wrl" $W $H joint:1 "$j1" "$k1"
#    A --pose on an unnamed joint is saved too (it used to be lost).
view "$tblobs" --frames 2 --polygonizer mc --pose joint1=0,0,1,0.5rad --keys s@1 --save-as "$work/posed.wrl" >/dev/null
grep -q "rotation 0 0 1 0.5$" "$work/posed.wrl" || fail "the pose of an unnamed RigidTransform was not saved"

# 5. --no-manipulators (the thesis's -n): the same drag orbits and the document is unchanged.
view "$blobs" --frames 4 --no-manipulators --drag "$cx,$cy,$x1,$y1@1" --keys s@2 --save-as "$work/n.wrl" \
    | tee "$work/n.txt"
grep -q "drag .*: orbit$" "$work/n.txt" || fail "--no-manipulators still grabbed a handle"
cmp "$work/orig.wrl" "$work/n.wrl" || fail "--no-manipulators changed the document"
# 6. view uses the polygonizer the file names: textured_blobs.wrl is a MarchingCubes scene, so its default meshes
#    are exactly those of --polygonizer mc, and not the particles'.
hashes() { xvfb_run "$xvfb" "$puppeteer" view "$blobs" --frames 3 --mesh-hashes --no-hud --width 320 --height 240 "$@" \
    | grep '^frame '; }
hashes >"$work/default.hashes"
hashes --polygonizer mc >"$work/mc.hashes"
hashes --polygonizer particles >"$work/particles.hashes"
[ "$(wc -l <"$work/default.hashes")" -eq 3 ] || fail "expected 3 frame hashes"
cmp "$work/default.hashes" "$work/mc.hashes" || fail "view did not use the scene file's MarchingCubes"
cmp -s "$work/default.hashes" "$work/particles.hashes" && fail "the particle meshes equal Marching Cubes'"
# 7. Bad flags fail cleanly with the command line's exit code (2).
set +e
"$puppeteer" view "$blobs" --frames 1 --point-size 0 >/dev/null 2>"$work/err"; code=$?
set -e
[ $code -eq 2 ] || fail "--point-size 0: exit $code, expected 2"
grep -q "point-size" "$work/err" || fail "--point-size 0: the message does not name the option"
set +e
"$puppeteer" view "$blobs" --frames 1 --keys alt+z@1 >/dev/null 2>"$work/err"; code=$?
set -e
[ $code -eq 2 ] || fail "--keys alt+z@1: exit $code, expected 2"
grep -q "expected \[ctrl+\]\[shift+\]KEY@FRAME" "$work/err" || fail "--keys alt+z@1: unclear message"
echo "modeller app test passed"

#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# 3D painting in the live app, headless under Xvfb (docs/app.md, "3D painting"): `t` turns paint mode on, a scripted
# drag paints a stroke on the left blob of textured_blobs.wrl, `s` saves the scene and the painted texture under a
# new name beside it; paint_check then reloads the saved scene and checks the stroke (changed texels in one small
# region, the rest as it was, the original image untouched). Both polygonizers.
# Usage: paint_app_test.sh PUPPETEER SOURCE_DIR PAINT_CHECK XVFB_RUN
set -euo pipefail
source "$(dirname "$0")/xvfb_run.sh"
puppeteer=$1 src=$2 check=$3 xvfb=$4
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$src/examples/textured_blobs.wrl" "$src"/examples/textured_blobs_*.png "$work/"
before=$(sha256sum "$work/textured_blobs_checker.png")
for polygonizer in mc particles; do
  xvfb_run "$xvfb" "$puppeteer" view "$work/textured_blobs.wrl" --polygonizer "$polygonizer" --no-hud --width 640 \
      --height 480 --keys t@2,6@3,s@8 --drag 230,210,280,230@4 --frames 10 --save-as "$work/painted_$polygonizer.wrl" \
      >"$work/out" 2>&1 || { cat "$work/out"; exit 1; }
  grep -q "paint mode" "$work/out" || { cat "$work/out"; echo "FAIL: no paint mode"; exit 1; }
  grep -q "with its painted textures" "$work/out" || { cat "$work/out"; echo "FAIL: nothing painted"; exit 1; }
  [ -f "$work/painted_${polygonizer}_textured_blobs_checker.png" ] || { ls "$work"; echo "FAIL: no painted texture"; exit 1; }
  # Brush size 6 (key 6): radius 10 texels; the default colour 200,30,40.
  "$check" "$work/painted_$polygonizer.wrl" "$work/textured_blobs_checker.png" 0 200,30,40 10
done
[ "$before" = "$(sha256sum "$work/textured_blobs_checker.png")" ] || { echo "FAIL: the original changed"; exit 1; }
echo "paint_app: ok"

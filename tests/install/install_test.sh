#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `cmake --install` gives a usable package: the CLI runs from the prefix (its PNG plugin found there), and another
# CMake project finds the libraries with find_package(imps COMPONENTS drivers calibration sim), meshes a bundled
# example through the core and calls into each of the other libraries (tests/install/consumer.cpp).
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$work/prefix" >/dev/null
[ -x "$work/prefix/bin/puppeteer" ] || fail "no bin/puppeteer"
for header in imps/field.h imps/diagnostic.h drivers/serial_transport.h calibration/joint_map.h sim/bvh.h; do
  [ -f "$work/prefix/include/$header" ] || fail "no header $header"
done
for lib in imps imps_base imps_drivers imps_calibration imps_sim; do
  [ -f "$work/prefix/lib/lib$lib.a" ] || fail "no lib$lib.a"
done
[ -f "$work/prefix/lib/cmake/imps/impsConfig.cmake" ] || fail "no package config"
IMPS_NO_HUGEPAGES=1 "$work/prefix/bin/puppeteer" render "$src/examples/transformed_blobs.wrl" --res 16 \
    --width 64 --height 64 -o "$work/shot.png" >/dev/null || fail "the installed CLI cannot render a PNG"
[ -s "$work/shot.png" ] || fail "no PNG written"

cmake -S "$src/tests/install" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release \
    >/dev/null || fail "find_package(imps) failed"
cmake --build "$work/consumer" >/dev/null || fail "the consumer does not build against the installed libraries"
out=$("$work/consumer/consumer" "$src/examples/simple_biped.wrl") || fail "the consumer failed: $out"
case $out in closed\ *\ 2) ;; *) fail "unexpected consumer output: $out" ;; esac
echo "install: ok ($out)"

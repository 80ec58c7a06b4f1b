#!/usr/bin/env bash
# `cmake --install` gives a usable package: the CLI runs from the prefix (its PNG plugin found there), and another
# CMake project finds the core with find_package(imps) and meshes a bundled example through it.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$work/prefix" >/dev/null
[ -x "$work/prefix/bin/puppeteer" ] || fail "no bin/puppeteer"
[ -f "$work/prefix/include/imps/field.h" ] || fail "no headers"
[ -f "$work/prefix/lib/cmake/imps/impsConfig.cmake" ] || fail "no package config"
IMPS_NO_HUGEPAGES=1 "$work/prefix/bin/puppeteer" render "$src/examples/transformed_blobs.wrl" --res 16 \
    --width 64 --height 64 -o "$work/shot.png" >/dev/null || fail "the installed CLI cannot render a PNG"
[ -s "$work/shot.png" ] || fail "no PNG written"

cmake -S "$src/tests/install" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release \
    >/dev/null || fail "find_package(imps) failed"
cmake --build "$work/consumer" >/dev/null || fail "the consumer does not build against the installed core"
out=$("$work/consumer/consumer" "$src/examples/simple_biped.wrl") || fail "the consumer failed: $out"
case $out in closed\ *) ;; *) fail "unexpected consumer output: $out" ;; esac
echo "install: ok ($out)"

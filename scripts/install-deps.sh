#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs every Debian package the project needs to build, test and run. The one place that knows them.
# Usage: scripts/install-deps.sh [fuzz]   (as root, or with sudo available; skips what is already installed)
#   fuzz: also the clang that builds the libFuzzer targets (make fuzz)
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  # core libraries
  libglm-dev libtbb-dev libcli11-dev nlohmann-json3-dev
  # gzip-compressed VRML worlds (.wrl served compressed)
  zlib1g-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev libtinygltf-dev
  # devices
  libserialport-dev libhidapi-dev libusb-1.0-0-dev umockdev libumockdev-dev
  # pose streaming (OSC over UDP)
  liblo-dev
  # app, pictures and headless rendering
  libglfw3-dev libgl-dev libegl-dev libopenimageio-dev libimgui-dev xvfb xauth libgl1-mesa-dri
)
if [ "${1:-}" = "fuzz" ]; then
  packages+=(clang-16 libclang-rt-16-dev)
fi

# The Khronos glTF validator, from the npm registry, for the export tests (they skip without it). Optional: a machine
# without npm, or without the registry, still builds and tests.
install_gltf_validator() {
  command -v npm >/dev/null || return 0
  npm ls -g gltf-validator >/dev/null 2>&1 && return 0
  echo "install-deps: installing gltf-validator (npm)"
  npm install -g --no-fund --no-audit gltf-validator >/dev/null 2>&1 || echo "install-deps: gltf-validator not installed" >&2
}
install_gltf_validator

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo=sudo
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"

#!/usr/bin/env bash
# Installs everything Gaitkeeper needs on a fresh Debian 12 machine (one apt-get call),
# then configures and builds the project into build/.
# Usage: scripts/setup.sh [--no-build]
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libglm-dev libtinygltf-dev nlohmann-json3-dev libstb-dev
  libglfw3-dev libimgui-dev libgl-dev libopengl-dev libegl-dev libgl1-mesa-dri libegl-mesa0 libgles-dev
  libcli11-dev libtbb-dev librecast-dev libmeshoptimizer-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth ffmpeg jq gnuplot-nox
  clang libclang-rt-14-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${PACKAGES[@]}"
else
  echo "setup: all Debian packages already installed"
fi

if [[ "${1:-}" == "--no-build" ]]; then exit 0; fi

cmake --preset release
cmake --build --preset release -j"$(nproc)"

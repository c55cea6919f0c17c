#!/usr/bin/env bash
# Installs the Debian packages hsr needs to build and test, plus any packages named as arguments,
# skipping those already present. Idempotent; run as root (or with sudo available). Used by the
# README's two commands, CI and scripts/bench-peer.sh.
set -euo pipefail
packages=(build-essential cmake ninja-build pkg-config
  libglm-dev nlohmann-json3-dev libfmt-dev libcli11-dev libassimp-dev libopenexr-dev
  libpng-dev libstb-dev libssl-dev libgtest-dev libbenchmark-dev libhwy-dev
  libjs-chart.js chromium fonts-dejavu-core python3-jsonschema
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest
  python3-opengl libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6
  librsvg2-bin openmpi-bin libopenmpi-dev python3-distributed python3-open3d "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

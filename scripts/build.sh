#!/usr/bin/env bash
# Configures (CMakePresets.json's release preset) and builds hsr into ./build. Usage: scripts/build.sh [extra cmake args]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset release "$@" >/dev/null
cmake --build build -j"$(nproc)"

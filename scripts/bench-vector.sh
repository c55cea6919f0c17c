#!/usr/bin/env bash
# The vector-output peer (bench/peer/vector_peer.py): installs matplotlib and librsvg (Debian
# packages, skipping those present), builds hsr, and prints the table of docs/vector-output.md:
# per scene, hsr's and matplotlib's SVG time, size and wrong pixels against raycast.
# Usage: scripts/bench-vector.sh [OUT_DIR, default build/vector-peer] [WIDTH HEIGHT, default 640 480]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-build/vector-peer}"
scripts/install-deps.sh python3-matplotlib python3-numpy librsvg2-bin
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target hsr_cli
/usr/bin/python3 bench/peer/vector_peer.py build/hsr "$out" "${2:-640}" "${3:-480}"

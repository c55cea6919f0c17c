#!/usr/bin/env bash
# The main job: builds hsr, then renders every built-in scene with the z-buffer into ./out
# (colour, depth picture, face ids, depth, statistics) and prints their statistics.
# Usage: scripts/main.sh [SIZE, default 1280x720]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
size="${1:-1280x720}"
mkdir -p out
for scene in $(build/hsr scenes --names); do
  echo "== builtin:$scene"
  build/hsr render "builtin:$scene" --size "$size" --algorithm zbuffer \
    --out "out/$scene.png" --depth-image "out/$scene-depth.png" --ids "out/$scene-ids.png" \
    --depth "out/$scene-depth.npy" --stats "out/$scene-stats.json"
done
echo "images and statistics in $(pwd)/out"

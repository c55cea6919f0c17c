#!/usr/bin/env bash
# The z-buffer's clearing saver measured: frames of an orbit rendered into one Frame by the
# textbook loop with a buffer cleared every frame (zbuffer-regions with the whole image as one
# region) against the half-range buffer (zbuffer-half-range) that is never cleared (docs/memory.md), and the regional buffer's cost. One
# thread; the medians of `hsr bench` frames: the whole frame, and its clear + resolve stages
# (what the trick changes; the drawing between them is the same loop). Prints Markdown.
# Usage: scripts/bench-memory.sh [SIZE, default 1920x1080] [FRAMES, default 20]
#        environment: SCENES (space-separated), HSR (the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
frames="${2:-20}"
hsr="${HSR:-build/hsr}"
scenes=${SCENES-"builtin:cubes builtin:layers builtin:city"}

# "frame ms / clear + resolve ms" of one configuration.
timed() {
  "$hsr" bench "$1" --size "$size" --frames "$frames" --threads 1 --orbit --json "${@:2}" |
    /usr/bin/python3 -c 'import json, sys
j = json.load(sys.stdin); st = j["stage_median_ms"]
print("%.2f / %.2f" % (j["median_ms"], st.get("clear", 0) + st.get("resolve", 0)))'
}

echo "| scene ($size, $frames frames, 1 thread), frame / clear + resolve, ms | cleared every frame | half-range | region=64x64 |"
echo "|---|---|---|---|"
for scene in $scenes; do
  echo "| \`$scene\` | $(timed "$scene" --algorithm zbuffer-regions --param "region=$size") |" \
    "$(timed "$scene" --algorithm zbuffer-half-range) |" \
    "$(timed "$scene" --algorithm zbuffer-regions --param region=64x64) |"
done

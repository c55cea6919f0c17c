#!/usr/bin/env bash
# The z-buffer's clearing saver measured: frames of an orbit rendered into one Frame by the
# textbook loop with a buffer cleared every frame (the whole image as one region) against the
# half-range buffer that is never cleared (docs/memory.md), and the regional buffer's cost. One
# thread, the median of `hsr bench` frames. Prints Markdown.
# Usage: scripts/bench-memory.sh [SIZE, default 1920x1080] [FRAMES, default 20]
#        environment: SCENES (space-separated), HSR (the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
frames="${2:-20}"
hsr="${HSR:-build/hsr}"
scenes=${SCENES-"builtin:cubes builtin:layers builtin:city"}

median_ms() {
  "$hsr" bench "$1" --size "$size" --frames "$frames" --threads 1 --orbit --json "${@:2}" |
    /usr/bin/python3 -c 'import json, sys; print("%.2f" % json.load(sys.stdin)["median_ms"])'
}

echo "| scene ($size, $frames frames, 1 thread) | cleared every frame, ms | half-range, ms | saved | region=64x64, ms |"
echo "|---|---|---|---|---|"
for scene in $scenes; do
  cleared="$(median_ms "$scene" --param "region=$size")"
  half="$(median_ms "$scene" --param clear=half-range)"
  regions="$(median_ms "$scene" --param region=64x64)"
  saved="$(/usr/bin/python3 -c "print('%.1f %%' % (100 * (1 - $half / $cleared)))")"
  echo "| \`$scene\` | $cleared | $half | $saved | $regions |"
done

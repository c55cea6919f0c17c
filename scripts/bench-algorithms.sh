#!/usr/bin/env bash
# The algorithms side by side on built-in scenes: per scene and algorithm, the median frame time
# (hsr bench) and the counts of one verified frame (hsr render --verify): colour writes, covered
# pixels, overdraw, z comparisons and wrong pixels against the exact reference. Prints a Markdown
# table: a quick side-by-side on chosen scenes (hsr compare runs the whole study).
# Usage: scripts/bench-algorithms.sh [SIZE, default 1920x1080] [FRAMES, default 5] [THREADS, default 2]
#        environment: SCENES (space-separated), ALGORITHMS (space-separated NAME[:key=value,...])
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
frames="${2:-5}"
threads="${3:-2}"
hsr="${HSR:-build/hsr}"
scenes=${SCENES:-"builtin:cubes builtin:painter-midpoint builtin:painter-cycle builtin:interpenetrate builtin:random?n=50 builtin:random?n=10000 builtin:city"}
algorithms=${ALGORITHMS:-"zbuffer zbuffer:raster=halfspace painter reverse-painter sorted-zbuffer"}
echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown); size $size; $frames frames; --threads $threads"
echo
echo "| scene | algorithm | faces | median ms | colour writes | covered px | overdraw | z tests | wrong px |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
for scene in $scenes; do
  for spec in $algorithms; do
    name="${spec%%:*}"
    args=(--algorithm "$name")
    if [[ "$spec" == *:* ]]; then
      IFS=',' read -ra kvs <<<"${spec#*:}"
      for kv in "${kvs[@]}"; do args+=(--param "$kv"); done
    fi
    bench="$("$hsr" bench "$scene" --size "$size" --frames "$frames" --threads "$threads" --json "${args[@]}")"
    render="$("$hsr" render "$scene" --size "$size" --threads "$threads" --verify --json "${args[@]}")"
    python3 - "$scene" "$spec" "$bench" "$render" <<'PY'
import json, sys
scene, spec, bench, render = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
print(f"| {scene} | {spec} | {render['faces']} | {bench['median_ms']:.2f} | {render['color_writes']} | "
      f"{render['covered_pixels']} | {render['overdraw']:.2f} | {render['depth_tests']} | {render['wrong_pixels']} |")
PY
  done
done

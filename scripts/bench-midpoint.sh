#!/usr/bin/env bash
# The Ukrainian paper's table 1 reproduced on hsr's built-in scenes: z comparisons and frame time
# of the hierarchical z-buffer (hzb) against the z-buffer with midpoint subdivision (midpoint,
# two initial splits), with the textbook z-buffer beside them and each one's wrong pixels against
# the exact reference; then a sweep of midpoint's initial-splits and max-depth (error against
# comparisons and time). Prints Markdown. docs/algorithms/midpoint.md discusses the figures.
#
# z comparisons, as the paper counts them: zbuffer one per fragment; hzb one per pixel tested
# plus one per pyramid entry tested; midpoint one per vertex or midpoint tested plus one per
# pixel tested at the limit. Times: the median of `hsr bench` frames, one thread (all three draw
# on one thread).
# Usage: scripts/bench-midpoint.sh [SIZE, default 800x600] [FRAMES, default 5]
#        environment: SCENES (table, space-separated), SWEEP_SCENES, HSR (the binary)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-800x600}"
frames="${2:-5}"
hsr="${HSR:-build/hsr}"
scenes=${SCENES-"builtin:cubes builtin:random?n=400&seed=3 builtin:sphere?n=20000 builtin:layers builtin:clutter builtin:city"}
sweep_scenes=${SWEEP_SCENES-"builtin:random?n=400&seed=3 builtin:city"}

# One row: scene, label, then hsr's flags. Prints "| ... |" with the counts of a verified render
# and the median of a bench run.
row() {
  local scene="$1" label="$2"
  shift 2
  local bench render
  bench="$("$hsr" bench "$scene" --size "$size" --frames "$frames" --threads 1 --json "$@")"
  render="$("$hsr" render "$scene" --size "$size" --threads 1 --verify --json "$@")"
  /usr/bin/python3 - "$scene" "$label" "$bench" "$render" <<'PY'
import json, sys
scene, label, bench, render = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
own = render.get(render["algorithm"], {})
if render["algorithm"] == "midpoint":
    first, pixels = own["point_comparisons"], own["pixel_tests"]
else:  # hzb: pyramid entries tested; zbuffer: none
    first = sum(v for k, v in own.items() if k.startswith("level") and k.endswith("_tested"))
    pixels = render["depth_tests"]
print(f"| {scene} | {label} | {first + pixels} | {first} | {pixels} | {bench['median_ms']:.2f} | "
      f"{render['wrong_pixels']} | {render['covered_pixels']} |")
PY
}

echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown); size $size; $frames frames; --threads 1"
echo
echo "## Table 1, on hsr's scenes"
echo
echo "| scene | algorithm | z comparisons | of which entries / points | of which pixels | median ms | wrong px | covered px |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
for scene in $scenes; do
  row "$scene" "zbuffer (textbook)" --algorithm zbuffer --param raster=halfspace
  row "$scene" "hzb" --algorithm hzb
  row "$scene" "hzb order=submission" --algorithm hzb --param order=submission
  row "$scene" "midpoint initial-splits=2" --algorithm midpoint --param initial-splits=2
done
echo
echo "## Sweep of midpoint's parameters"
echo
echo "| scene | algorithm | z comparisons | of which entries / points | of which pixels | median ms | wrong px | covered px |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
for scene in $sweep_scenes; do
  for splits in 0 1 2 3 4; do
    for depth in 2 4 6 8; do
      ((depth >= splits)) || continue
      row "$scene" "midpoint initial-splits=$splits max-depth=$depth" --algorithm midpoint \
        --param initial-splits=$splits --param max-depth=$depth
    done
  done
done

#!/usr/bin/env bash
# Shadow maps against shadow rays (docs/shadows.md): for each built-in scene and map size, the
# pixels where `hsr render --shadows` disagrees with the exact shadow rays — in all, away from the
# view's shadow edges, away from its shadow and face edges, and unexplained (away from texel-scale
# edges too) — with the time of the map, of the per-pixel test and the map's memory. Prints Markdown.
# Usage: scripts/bench-shadows.sh [SIZE, default 1920x1080] [MAP SIZES, default "512 1024 2048 4096 8192"]
#        environment: HSR (the binary), THREADS (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
maps="${2:-512 1024 2048 4096 8192}"
hsr="${HSR:-build/hsr}"
threads="${THREADS:-2}"
# scene and the direction its light travels
cases=("builtin:city 0.6,-1,0.4" "builtin:cubes 0.5,-1,-0.3" "builtin:clutter -0.4,-1,0.3"
       "builtin:painter-cycle 0.3,-0.4,-1")

echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown); size $size; --threads $threads; bias 1 texel (default)"
echo
echo "| scene | light travels | map | shadowed px | wrong px | away from shadow edges | away from all edges | unexplained | map ms | test ms | map MB |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for c in "${cases[@]}"; do
  read -r scene light <<<"$c"
  for n in $maps; do
    json="$("$hsr" render "$scene" --size "$size" --threads "$threads" --shadows --light-dir="$light" \
            --shadow-map-size "$n" --verify --json)"
    /usr/bin/python3 - "$scene" "$light" "$n" "$json" <<'PY'
import json, sys
scene, light, n, s = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
d, t = s[s["algorithm"]], s["time_ms"]
print(f"| {scene} | {light} | {n} | {d['shadow_shadowed_pixels']} | {d['shadow_wrong_pixels']} | "
      f"{d['shadow_wrong_away_from_shadow_edges']} | {d['shadow_wrong_away_from_edges']} | "
      f"{d['shadow_wrong_unexplained']} | {t['shadow_map']:.1f} | {t['shadow_test']:.1f} | "
      f"{s['memory']['shadow_map'] / 1e6:.1f} |")
PY
  done
done

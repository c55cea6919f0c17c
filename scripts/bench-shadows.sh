#!/usr/bin/env bash
# Shadow maps against shadow rays (docs/shadows.md): for each built-in scene, method and map size,
# the pixels where `hsr render --shadows` disagrees with the exact shadow rays — in all, away from
# the view's shadow edges, away from its shadow and face edges, and unexplained (away from
# texel-scale edges too) — with the time of the fit, the maps, the per-pixel test and the largest
# map's memory. Prints Markdown.
# Usage: scripts/bench-shadows.sh [SIZE, default 1920x1080] [CONFIGS] [SCENES]
#   CONFIGS: METHOD:MAPSIZE or cascaded:K:MAPSIZE words, default: single and 4 cascades at 1024 to
#   8192, plus 1 and 16 cascades at the texels of one 4096 map (1 of 4096, 16 of 1024)
#   SCENES: "scene light-direction" entries separated by ';', default: city, cubes, clutter, painter-cycle
#   environment: HSR (the binary), THREADS (default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
configs="${2:-single:1024 single:2048 single:4096 single:8192 cascaded:4:1024 cascaded:4:2048 cascaded:4:4096 cascaded:4:8192 cascaded:1:4096 cascaded:16:1024}"
scenes="${3:-builtin:city 0.6,-1,0.4;builtin:cubes 0.5,-1,-0.3;builtin:clutter -0.4,-1,0.3;builtin:painter-cycle 0.3,-0.4,-1}"
hsr="${HSR:-build/hsr}"
threads="${THREADS:-2}"

echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown); size $size; --threads $threads; bias 1 texel (default)"
echo
echo "| scene | light travels | method | maps x side | texels (M) | shadowed px | wrong px | away from shadow edges | away from all edges | unexplained | fit ms | map ms | test ms | largest map MB |"
echo "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
IFS=';' read -r -a cases <<<"$scenes"
for c in "${cases[@]}"; do
  read -r scene light <<<"$c"
  for config in $configs; do
    IFS=':' read -r method k n <<<"$config"
    if [[ "$method" == single ]]; then n="$k"; k=1; flags=(--shadow-method single); else flags=(--shadow-method cascaded --shadow-cascades "$k"); fi
    json="$("$hsr" render "$scene" --size "$size" --threads "$threads" --shadows --light-dir="$light" \
            "${flags[@]}" --shadow-map-size "$n" --verify --json)"
    /usr/bin/python3 - "$scene" "$light" "$method" "$k" "$n" "$json" <<'PY'
import json, sys
scene, light, method, k, n, s = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), json.loads(sys.argv[6])
d, t = s[s["algorithm"]], s["time_ms"]
print(f"| {scene} | {light} | {method} | {d['shadow_maps']} x {n} | {k * n * n / 2**20:.0f} | {d['shadow_shadowed_pixels']} | "
      f"{d['shadow_wrong_pixels']} | {d['shadow_wrong_away_from_shadow_edges']} | {d['shadow_wrong_away_from_edges']} | "
      f"{d['shadow_wrong_unexplained']} | {t.get('shadow_fit', 0):.1f} | {t['shadow_map']:.1f} | {t['shadow_test']:.1f} | "
      f"{s['memory']['shadow_map'] / 1e6:.1f} |")
PY
  done
done

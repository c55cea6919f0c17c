#!/usr/bin/env bash
# The depth-only benchmark of the performance issue: the four larger peer scenes at 1920x1080,
# timed three ways in alternating runs of `hsr bench` (medians of each run's median):
#   - depth image: `--depth-only` render() calls (a depth frame written, eye depth per pixel);
#   - occlusion buffer: `--occlusion`, hsr::OcclusionBuffer::render calls (depth kept in tiles,
#     no image: what an occlusion culler pays per frame, and what Masked Occlusion Culling times);
#   - the same with `--cull back`: MOC's RenderTriangles culls back faces unless told otherwise
#     (its bfWinding parameter defaults to BACKFACE_CW), so this column is the like-for-like one
#     (hsr draws both sides by default, as its conventions ask);
# next to the MOC figures the issue quotes (approximate depth, 1 thread, measured elsewhere —
# MOC is not packaged in Debian, so it is not run here).
# Usage: scripts/bench-depth.sh [ROUNDS, default 5] [FRAMES, default 15]; THREADS (default 2),
#        HSR (default build/hsr; built by scripts/build.sh when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-5}"
frames="${2:-15}"
threads="${THREADS:-2}"
source scripts/bench-common.sh  # hsr (HSR, built when missing), python3, bench_header

bench_header
echo "size 1920x1080, $rounds alternating rounds of $frames frames (after at least 2 warm-up frames and 1 s), --threads $threads, depth f32:reversed"
echo
echo "| scene | triangles | depth image ms | occlusion buffer ms | occlusion buffer, back faces culled, ms | MOC ms (issue's figure, 1 thread) | target ms |"
echo "|---|---:|---:|---:|---:|---:|---:|"
median_of() {  # hsr bench ... --json -> median_ms
  "$hsr" bench "$@" --size 1920x1080 --frames "$frames" --warmup 2 --threads "$threads" --json |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["median_ms"])'
}
while read -r scene triangles moc target; do
  image=(); occl=(); back=()
  for _ in $(seq "$rounds"); do
    image+=("$(median_of "$scene" --depth-only)")
    occl+=("$(median_of "$scene" --occlusion)")
    back+=("$(median_of "$scene" --occlusion --cull back)")
  done
  python3 - "$scene" "$triangles" "$moc" "$target" "${image[*]}" "${occl[*]}" "${back[*]}" <<'PY'
import statistics, sys
scene, triangles, moc, target, image, occl, back = sys.argv[1:]
med = lambda s: statistics.median(float(x) for x in s.split())
print(f"| `{scene}` | {triangles} | {med(image):.2f} | {med(occl):.2f} | {med(back):.2f} | {moc} | {target} |")
PY
done <<'SCENES'
builtin:sphere 1003520 17.8 18
builtin:city 43202 1.0 1
builtin:random?n=10000 10000 0.98 1
builtin:layers?n=64 128 0.85 0.9
SCENES

#!/usr/bin/env bash
# Small scenes and more threads: the performance issue asks that a frame too small to split does
# not get slower with a second thread (hsr falls back to one where the work is too small). For
# each small built-in scene, at each size, in each mode (a frame with all buffers, the occlusion
# buffer, a depth-only frame): `hsr bench` medians with 1 thread and with THREADS threads,
# alternating, ROUNDS rounds each; the table gives the lower median of each and their ratio
# (above 1: slower with more threads).
# Usage: scripts/bench-threads.sh [ROUNDS, default 2] [FRAMES, default 1500]; THREADS (default 2),
#        SIZES (default "64x48 160x120"), HSR (default build/hsr; built by scripts/build.sh when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-2}"
frames="${2:-1500}"
threads="${THREADS:-2}"
sizes="${SIZES:-64x48 160x120}"
source scripts/bench-common.sh  # hsr (HSR, built when missing), python3, bench_header

bench_header
echo "$rounds alternating rounds of $frames frames (after at least 1 s of warm-up); microseconds, the lower median of the rounds"
echo
echo "| scene | size | mode | 1 thread | $threads threads | ratio |"
echo "|---|---|---|---:|---:|---:|"
median_us() {  # hsr bench ... --json -> median in microseconds
  "$hsr" bench "$@" --frames "$frames" --json | python3 -c 'import json,sys; print(json.load(sys.stdin)["median_ms"] * 1000)'
}
for scene in builtin:cubes builtin:painter-cycle builtin:interpenetrate builtin:zfight "builtin:random?n=200" \
  "builtin:city?blocks=2" "builtin:clutter?n=4&detail=3" "builtin:layers?n=8"; do
  for size in $sizes; do
    for mode in frame occlusion depth-only; do
      flags=()
      [ "$mode" = frame ] || flags=("--$mode")
      one=(); more=()
      for _ in $(seq "$rounds"); do
        one+=("$(median_us "$scene" --size "$size" --threads 1 "${flags[@]}")")
        more+=("$(median_us "$scene" --size "$size" --threads "$threads" "${flags[@]}")")
      done
      python3 - "$scene" "$size" "$mode" "${one[*]}" "${more[*]}" <<'PY'
import sys
scene, size, mode, one, more = sys.argv[1:]
a = min(float(x) for x in one.split())
b = min(float(x) for x in more.split())
print(f"| `{scene}` | {size} | {mode} | {a:.2f} | {b:.2f} | {b / a:.3f} |")
PY
    done
  done
done

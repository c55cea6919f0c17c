#!/usr/bin/env bash
# A/B timing of two hsr builds on one scene, alternating their runs so that both see the same
# machine load (on a shared VM the speed drifts by tens of percent within minutes: compare two
# builds only this way). Each round runs `hsr bench` once per build; prints every round's medians,
# then the median and minimum of each build and the ratio B / A of the medians. (Builds before
# commit 36075ce warm up for 2 frames only, not also 1 s: pass --warmup 50 or so to compare one.)
# Usage: scripts/bench-ab.sh HSR_A HSR_B SCENE [THREADS, default 2] [ROUNDS, default 5] [extra hsr bench flags...]
#   e.g. git worktree add /tmp/old HEAD~1 && cmake -S /tmp/old -B /tmp/old/build -G Ninja
#        -DCMAKE_BUILD_TYPE=Release && cmake --build /tmp/old/build --target hsr_cli
#        scripts/bench-ab.sh /tmp/old/build/hsr build/hsr builtin:city 2 6 --shading flat
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
a="$1" b="$2" scene="$3" threads="${4:-2}" rounds="${5:-5}"
shift $(( $# < 5 ? $# : 5 ))
for bin in "$a" "$b"; do
  [ -x "$bin" ] || { echo "bench-ab: $bin is not an executable hsr" >&2; exit 2; }
done
median() { "$1" bench "$scene" --size 1920x1080 --frames 7 --warmup 2 --threads "$threads" --json "${@:2}" |
  python3 -c 'import json, sys; print(json.load(sys.stdin)["median_ms"])'; }
ra=() rb=()
for i in $(seq "$rounds"); do
  ra+=("$(median "$a" "$@")")
  rb+=("$(median "$b" "$@")")
  echo "round $i: A ${ra[-1]} ms, B ${rb[-1]} ms"
done
python3 - "${ra[*]}" "${rb[*]}" <<'PY'
import statistics, sys
a = [float(x) for x in sys.argv[1].split()]
b = [float(x) for x in sys.argv[2].split()]
print(f"A median {statistics.median(a):.2f} min {min(a):.2f} | B median {statistics.median(b):.2f} "
      f"min {min(b):.2f} | B/A {statistics.median(b) / statistics.median(a):.3f}")
PY

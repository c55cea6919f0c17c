#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang 16, ASan + UBSan, the SIMD kernel for the baseline
# target only) into BUILD_DIR (./build-fuzz) and runs each for SECONDS (default 60), one after
# the other.
# Corpora grow in BUILD_DIR/corpus/NAME, seeded from fuzz/seeds, fuzz/regressions and Debian's
# assimp-testmodels; a crash is saved in BUILD_DIR/crashes/NAME/ and makes the script fail.
# Usage: scripts/fuzz.sh [SECONDS] [NAME ...]   (names: obj ply stl off assimp scene_json ...)
#        environment: BUILD_DIR (default build-fuzz; build-ci is scripts/sanitize.sh quick's build)
#                     FUZZ_RUNS=N: instead of SECONDS, N inputs per target from the fixed seed 1
#                     (the same inputs every time: CI's bounded, repeatable run)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
scripts/install-deps.sh clang-16 libclang-rt-16-dev llvm-16 assimp-testmodels
build=${BUILD_DIR:-build-fuzz}
preset=asan
[ "$build" = build-ci ] && preset=asan-quick
scripts/configure-checked.sh $preset -B "$build"
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  for f in fuzz/*_fuzz.cpp; do n=$(basename "$f" _fuzz.cpp); names+=("$n"); done
fi
cmake --build "$build" -j"$(nproc)" --target "${names[@]/#/fuzz_}"

export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-16/bin/llvm-symbolizer  # stacks with names
models=/usr/share/assimp/models
declare -A patterns=([obj]='*.obj' [ply]='*.ply' [stl]='*.stl' [off]='*.off' [assimp]='*.gl[tb]*')
failed=()
for name in "${names[@]}"; do
  corpus=$build/corpus/$name crashes=$build/crashes/$name
  mkdir -p "$corpus" "$crashes"
  for d in fuzz/seeds/$name fuzz/regressions/$name; do [ -d "$d" ] && cp -n "$d"/* "$corpus"/ 2>/dev/null || true; done
  if [ -n "${patterns[$name]:-}" ] && [ -d "$models" ]; then
    find "$models" -iname "${patterns[$name]}" -size -64k -type f -print0 |
      while IFS= read -r -d '' f; do cp -n "$f" "$corpus/$(echo "${f#$models/}" | tr / _)"; done
  fi
  maxlen=65536
  [ "$name" = render ] && maxlen=4096
  [ "$name" = builtin ] && maxlen=256
  budget=(-max_total_time="$seconds")
  [ -n "${FUZZ_RUNS:-}" ] && budget=(-runs="$FUZZ_RUNS" -seed=1)
  echo "fuzz: $name for ${budget[*]}"
  # Leaks are checked; a run slower than 20 s or above 2 GB is a finding too.
  if ! ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1 \
      LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan.supp \
      "$build/fuzz/fuzz_$name" "$corpus" "${budget[@]}" -max_len=$maxlen -timeout=20 \
      -rss_limit_mb=2048 -artifact_prefix="$crashes/" -print_final_stats=1 > "$build/fuzz-$name.log" 2>&1; then
    failed+=("$name")
    echo "fuzz: $name FAILED, see $build/fuzz-$name.log and $crashes/"
    tail -n 30 "$build/fuzz-$name.log"
  fi
  grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb' "$build/fuzz-$name.log" | tr '\n' ' ' && echo
done
if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz: failed: ${failed[*]}"
  exit 1
fi
echo "fuzz: all ${#names[@]} targets ran (${budget[*]}) without a finding"

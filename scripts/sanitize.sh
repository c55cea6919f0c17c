#!/usr/bin/env bash
# The test suite under sanitizers (clang 16, the SIMD kernel for the baseline target only; the
# builds and test selections are CMakePresets.json's asan, asan-quick and tsan presets).
#   scripts/sanitize.sh          AddressSanitizer + UndefinedBehaviorSanitizer, every ctest test
#                                (in ./build-fuzz, the build that also holds the fuzz targets)
#   scripts/sanitize.sh quick    the same with the SIMD kernel (src/raster/tiled.cpp) uninstrumented,
#                                which builds in a third of the time (./build-ci)
#   scripts/sanitize.sh thread   ThreadSanitizer over the threaded tests (./build-tsan)
# Extra arguments go to ctest (e.g. -R Loader).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-address}
[ $# -gt 0 ] && shift
case "$mode" in
  address) preset=asan ;;
  quick) preset=asan-quick ;;
  thread) preset=tsan ;;
  *) echo "usage: scripts/sanitize.sh [address|quick|thread] [ctest args]" >&2; exit 2 ;;
esac
scripts/install-deps.sh clang-16 libclang-rt-16-dev llvm-16
# The test presets hold the sanitizer options, the leak suppressions and each mode's tests.
scripts/configure-checked.sh "$preset"
cmake --build --preset "$preset" -j"$(nproc)"
jobs=(-j"$(nproc)")
[ "$preset" = tsan ] && jobs=()
ctest --preset "$preset" "${jobs[@]}" "$@"

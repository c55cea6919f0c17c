#!/usr/bin/env bash
# The test suite under sanitizers (clang 16, the SIMD kernel for the baseline target only; the
# builds are CMakePresets.json's asan, asan-quick and tsan presets).
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
scripts/install-deps.sh clang-16 libclang-rt-16-dev llvm-16
export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-16/bin/llvm-symbolizer  # stacks with names
case "$mode" in
  address|quick)
    dir=build-fuzz preset=asan
    [ "$mode" = quick ] && dir=build-ci preset=asan-quick
    scripts/configure-checked.sh $preset
    cmake --build "$dir" -j"$(nproc)"
    # The install test builds an outside project against the installed package, which carries no
    # sanitizer flags: it cannot link against a sanitized library, so it is left out here.
    export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:check_initialization_order=1
    export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
    export LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan.supp
    ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" -E '^install_and_consume$' "$@"
    ;;
  thread)
    dir=build-tsan
    scripts/configure-checked.sh tsan
    cmake --build "$dir" -j"$(nproc)" --target hsr_tests hsr_cli
    export TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1
    ctest --test-dir "$dir" --output-on-failure -j1 \
      -R 'Parallel\.|WorkQueue\.|RenderViews\.|Determinism|Concurrent|Conformance' "$@"
    ;;
  *)
    echo "usage: scripts/sanitize.sh [address|quick|thread] [ctest args]" >&2
    exit 2
    ;;
esac

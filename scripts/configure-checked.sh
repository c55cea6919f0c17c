#!/usr/bin/env bash
# Configures a checking build of hsr from one of CMakePresets.json's presets (asan, asan-quick,
# tsan: clang 16 at -O1 with line tables, the SIMD kernel for the baseline target only), with
# ccache when it is there. Used by scripts/sanitize.sh and scripts/fuzz.sh.
# Usage: scripts/configure-checked.sh PRESET [extra cmake args, e.g. -B DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
preset=$1
shift
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake --preset "$preset" "${launcher[@]}" "$@" > /dev/null

#!/usr/bin/env bash
# Configures a checking build of hsr with clang 16 (scripts/sanitize.sh, scripts/fuzz.sh): -O1
# with line tables (file:line in every sanitizer stack, without full debug information), the SIMD
# kernel for the baseline target only, no Python module or benchmarks.
# Usage: scripts/configure-checked.sh BUILD_DIR [extra cmake args]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$1
shift
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B "$dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++-16 -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" -DHSR_BASELINE_SIMD_ONLY=ON -DHSR_BUILD_PYTHON=OFF \
  -DHSR_BUILD_BENCH=OFF "${launcher[@]}" "$@" > /dev/null

#!/usr/bin/env bash
# Builds hsr and runs the whole test suite with ctest. Called by .ci/run.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
ctest --test-dir build --output-on-failure -j"$(nproc)"

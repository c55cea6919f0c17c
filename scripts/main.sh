#!/usr/bin/env bash
# The main job: builds hsr, then runs `hsr compare`'s default study — the source documents'
# comparisons on built-in scenes, every algorithm checked against the exact reference — into
# out/study/ (results.json and the report index.html), and prints its table and claims.
# Usage: scripts/main.sh [extra hsr compare flags, e.g. --frames 5]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
build/hsr compare --out out/study "$@"
echo "open $(pwd)/out/study/index.html"

#!/usr/bin/env bash
# The Python module's peer benchmark (docs/benchmarks.md, "The Python module against OpenGL from
# Python"): installs hsr's packages and the CAD model of Debian's assimp-testmodels, builds, and
# runs bench/python_peer.py with Debian's python3. Extra arguments go to the script (e.g. --json).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh assimp-testmodels
scripts/build.sh ${CMAKE_ARGS:-} >/dev/null  # CMAKE_ARGS: extra CMake arguments, e.g. the ccache launcher
echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) cores; load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
PYTHONPATH=build/python /usr/bin/python3 bench/python_peer.py --markdown --threads "${THREADS:-2}" "$@"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

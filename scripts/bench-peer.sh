#!/usr/bin/env bash
# The llvmpipe peer benchmark: installs hsr's and Mesa's EGL/OpenGL Debian packages (skipping
# those present), builds hsr_peer_llvmpipe, runs it on the five benchmark scenes and prints the
# Markdown table quoted in docs/benchmarks.md. Run as root (or with sudo) on Debian 12.
# Usage: scripts/bench-peer.sh [SIZE, default 1920x1080] [FRAMES, default 15]
#        environment: THREADS (default 2: hsr --threads and LP_NUM_THREADS), RASTER (hsr's z-buffer
#        rasterizer: default, or halfspace = the scalar reference, or scanline), OUTPUTS (hsr's buffers,
#        default depth,face,color = the GL framebuffer's attachments; every frame is also timed with all
#        four of hsr's buffers), BUILD_DIR (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1920x1080}"
frames="${2:-15}"
threads="${THREADS:-2}"
raster="${RASTER:-default}"
outputs="${OUTPUTS:-depth,face,color}"
build="${BUILD_DIR:-build}"

# Set-up: hsr's own packages, then the GL side — headers and libOpenGL/libEGL (GLVND) to build,
# Mesa's EGL vendor library and its DRI drivers (llvmpipe) to run.
scripts/install-deps.sh libopengl-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
peer="$build/bench/peer/hsr_peer_llvmpipe"
if ! cmake --build "$build" --target help | grep -q hsr_peer_llvmpipe; then
  echo "bench-peer: CMake skipped the llvmpipe peer (OpenGL/EGL development files not found); see its configure output" >&2
  exit 1
fi
cmake --build "$build" --target hsr_peer_llvmpipe

# Run conditions travel with the figures.
echo
echo "date: $(date -u '+%Y-%m-%d %H:%M UTC'); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) cores; load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "size $size, $frames frames interleaved after at least 2 warm-up frames and 1 s, hsr --threads $threads --raster $raster --outputs $outputs (each frame also with all four buffers), LP_NUM_THREADS=$threads"

log="$(mktemp)"
trap 'rm -f "$log"' EXIT
header_done=0
rows=""
for scene in builtin:sphere builtin:city "builtin:random?n=10000" "builtin:layers?n=64" builtin:cubes; do
  if ! row="$("$peer" "$scene" --size "$size" --frames "$frames" --threads "$threads" --raster "$raster" --outputs "$outputs" --markdown-row 2>"$log")"; then
    cat "$log" >&2
    echo "bench-peer: the peer failed on $scene (the line above says why). Without an llvmpipe context, check" \
      "that Mesa's libegl-mesa0 and libgl1-mesa-dri are installed: llvmpipe runs through their EGL surfaceless platform." >&2
    exit 1
  fi
  if [ "$header_done" -eq 0 ]; then
    grep '^GL_' "$log"  # GL_RENDERER and GL_VERSION: the proof that it is llvmpipe
    echo
    echo "| scene | triangles | hsr ms median | hsr ms min | llvmpipe ms median | llvmpipe ms min | ratio llvmpipe/hsr (medians) | writing hsr's frame once, ms median | hsr ms median, all four buffers | ratio, all four buffers | face ids equal (% of covered) | non-edge mismatches |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    header_done=1
  fi
  echo "$row"
  rows+="$row"$'\n'
done
# The issue's first target is on the geometric mean of the five ratios (columns 8 and 11 of the
# rows: depth + face + colour, and all four buffers).
echo
printf '%s' "$rows" | awk -F'|' '
  { n++; a += log($8 + 0); b += log($11 + 0) }
  END { if (n) printf "geometric mean of the %d ratios: %.2fx (all four buffers: %.2fx)\n", n, exp(a / n), exp(b / n) }'
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

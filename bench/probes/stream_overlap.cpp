// A stand-alone probe (not built by CMake): do a core's streaming stores overlap with its
// arithmetic? The background pump (raster/tiled.hpp, BackgroundPump) streams a frame's
// background between the tile kernel's blocks, which pays only as far as the two overlap.
// Each "frame": `rows` rows of kernel-like work (load 8 doubles of a working set of `bytes`,
// multiply-add, compare, blend, store back: a block row of the depth test) and 12 MiB of
// streaming stores (a worker's share of a 1920x1080 frame's three buffers), `lines` cache lines
// after every `per` rows. Mode 1: the arithmetic only, 2: the stores only, 0: both interleaved.
// Prints the median of 40 frames. If the two overlapped, mode 0 would take the larger of modes 1
// and 2; if not at all, their sum.
//   g++ -O2 -mavx512f -o /tmp/stream_overlap bench/probes/stream_overlap.cpp
//   /tmp/stream_overlap BYTES LINES PER MODE ROWS     (e.g. 16384 4 8 0 150000)
#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: stream_overlap BYTES LINES PER MODE ROWS\n");
    return 2;
  }
  const size_t bytes = std::max<size_t>(64, size_t(std::atol(argv[1])) / 64 * 64);
  const int lines = std::max(1, std::atoi(argv[2])), per = std::max(1, std::atoi(argv[3]));
  const int mode = std::atoi(argv[4]);
  const size_t rows = size_t(std::atol(argv[5]));
  const size_t frameBytes = size_t(12) << 20;
  double* work = static_cast<double*>(std::aligned_alloc(64, bytes));
  for (size_t i = 0; i < bytes / 8; ++i) work[i] = double(i);
  char* frame = static_cast<char*>(std::aligned_alloc(size_t(1) << 21, frameBytes));
  std::memset(frame, 1, frameBytes);
  const size_t workRows = bytes / 64;
  std::vector<double> us;
  double sink = 0;
  for (int rep = 0; rep < 40; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    char* dst = frame;
    char* const end = frame + frameBytes;
    __m512d acc = _mm512_set1_pd(1.0);
    const __m512i value = _mm512_set1_epi32(7);
    size_t r = 0, row = 0;
    while ((mode != 2 && r < rows) || (mode != 1 && dst < end)) {
      if (mode != 2)
        for (int k = 0; k < per && r < rows; ++k, ++r, row += 67) {  // rows visited out of order
          double* p = work + (row % workRows) * 8;
          const __m512d stored = _mm512_load_pd(p);
          const __m512d z = _mm512_add_pd(_mm512_mul_pd(stored, acc), _mm512_set1_pd(0.5));
          const __mmask8 win = _mm512_cmp_pd_mask(z, stored, _CMP_LT_OQ);
          _mm512_store_pd(p, _mm512_mask_blend_pd(win, stored, z));
          acc = _mm512_add_pd(acc, _mm512_set1_pd(1e-9));
        }
      if (mode != 1)
        for (int l = 0; l < lines && dst < end; ++l, dst += 64) _mm512_stream_si512(reinterpret_cast<__m512i*>(dst), value);
    }
    _mm_sfence();
    us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    sink += _mm512_reduce_add_pd(acc);
  }
  std::sort(us.begin(), us.end());
  volatile double keep = sink;  // (the arithmetic's result used: not optimized away)
  (void)keep;
  std::printf("bytes %zu, %d lines per %d rows, mode %d: median %.0f us\n", bytes, lines, per, mode, us[us.size() / 2]);
  std::free(work);
  std::free(frame);
}

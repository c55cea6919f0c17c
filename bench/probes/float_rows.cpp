// A stand-alone probe (not built by CMake): what would the tile kernel's pixel rows cost with
// a float tile buffer for the f32 formats instead of the double one? Each "row" is the
// kernel's unclamped row with two crossing edges (raster/tile_kernel-inl.h, drawRows): edge
// functions stepped and compared, the affine depth p = (pX + pY) + c rounded to float, compared
// with the stored value (reversed: greater wins), blended, stored, the tests and writes counted
// and the block's farthest value gathered. Mode 0: stored values as double (the rounding a
// round trip, double -> float -> double); mode 1: as float (the rounding one conversion, the
// compare, blend, store and farthest value on 8 floats); mode 2: as double, rounded to float
// by (p + C) - C, C = 1.5 * 2^(e+29) for values in one binade [2^e, 2^(e+1)) of normal floats
// (C's double ulp is the binade's float ulp, so the sum rounds to it, ties to even; the same
// bits as mode 0, which the tile checksum shows). Blocks of 8 rows at random places in a 64x64
// tile. Prints the median ns per row of 40 runs.
//   g++ -O2 -mavx512f -mavx512dq -mavx512vl -o /tmp/float_rows bench/probes/float_rows.cpp
//   for m in 0 1 2; do taskset -c 1 /tmp/float_rows $m 200000; done
#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: float_rows MODE BLOCKS\n");
    return 2;
  }
  const int mode = std::atoi(argv[1]);
  const size_t blocks = size_t(std::atol(argv[2]));
  constexpr int kTile = 64;
  alignas(64) static double tileD[kTile * kTile];
  alignas(64) static float tileF[kTile * kTile];
  for (int i = 0; i < kTile * kTile; ++i) tileD[i] = tileF[i] = float((i * 2654435761u % 1000) / 1000.0);
  std::vector<int> where(blocks);
  for (size_t i = 0; i < blocks; ++i) where[i] = int(i * 40503u % 64);
  const __m512d lane = _mm512_set_pd(7, 6, 5, 4, 3, 2, 1, 0);
  const __m512d C = _mm512_set1_pd(1.5 * 0x1p27);  // C for values in [0.25, 0.5): e = -2
  const __m512d pX = _mm512_mul_pd(lane, _mm512_set1_pd(1e-4)), c = _mm512_set1_pd(0.3);
  const __m512d step0 = _mm512_set1_pd(16.0), step1 = _mm512_set1_pd(-16.0);
  const __m512d bias0 = _mm512_set1_pd(-40.0), bias1 = _mm512_set1_pd(-200.0);
  const __m512d e0Start = _mm512_mul_pd(lane, _mm512_set1_pd(3.0)), e1Start = _mm512_mul_pd(lane, _mm512_set1_pd(-5.0));
  std::vector<double> ns;
  uint64_t sink = 0;
  for (int rep = 0; rep < 40; ++rep) {
    __m512i tests = _mm512_setzero_si512(), writes = _mm512_setzero_si512();
    const __m512i one = _mm512_set1_epi64(1);
    double farSum = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < blocks; ++i) {
      const int b = where[i];
      const size_t first = size_t(b / 8) * 8 * kTile + size_t(b % 8) * 8;
      __m512d e0 = e0Start, e1 = e1Start;
      double Y = 0.5 + double(i & 7);
      if (mode == 0 || mode == 2) {
        __m512d far = _mm512_set1_pd(1.0);
        for (int y = 0; y < 8; ++y, Y += 1.0) {
          double* at = tileD + first + size_t(y) * kTile;
          const __m512d stored = _mm512_load_pd(at);
          __mmask8 cover = _mm512_cmp_pd_mask(e0, bias0, _CMP_GE_OQ);
          e0 = _mm512_add_pd(e0, step0);
          cover = _mm512_mask_cmp_pd_mask(cover, e1, bias1, _CMP_GE_OQ);
          e1 = _mm512_add_pd(e1, step1);
          const __m512d p = _mm512_add_pd(_mm512_add_pd(pX, _mm512_set1_pd(1e-5 * Y)), c);
          const __m512d z = mode == 2 ? _mm512_sub_pd(_mm512_add_pd(p, C), C) : _mm512_cvtps_pd(_mm512_cvtpd_ps(p));
          const __mmask8 win = _mm512_mask_cmp_pd_mask(cover, z, stored, _CMP_GT_OQ);
          tests = _mm512_mask_add_epi64(tests, cover, tests, one);
          writes = _mm512_mask_add_epi64(writes, win, writes, one);
          const __m512d result = _mm512_mask_blend_pd(win, stored, z);
          _mm512_store_pd(at, result);
          far = _mm512_min_pd(far, result);
        }
        farSum += _mm512_reduce_min_pd(far);
      } else {
        __m256 far = _mm256_set1_ps(1.0f);
        for (int y = 0; y < 8; ++y, Y += 1.0) {
          float* at = tileF + first + size_t(y) * kTile;
          const __m256 stored = _mm256_load_ps(at);
          __mmask8 cover = _mm512_cmp_pd_mask(e0, bias0, _CMP_GE_OQ);
          e0 = _mm512_add_pd(e0, step0);
          cover = _mm512_mask_cmp_pd_mask(cover, e1, bias1, _CMP_GE_OQ);
          e1 = _mm512_add_pd(e1, step1);
          const __m512d p = _mm512_add_pd(_mm512_add_pd(pX, _mm512_set1_pd(1e-5 * Y)), c);
          const __m256 z = _mm512_cvtpd_ps(p);
          const __mmask8 win = _mm256_mask_cmp_ps_mask(cover, z, stored, _CMP_GT_OQ);
          tests = _mm512_mask_add_epi64(tests, cover, tests, one);
          writes = _mm512_mask_add_epi64(writes, win, writes, one);
          const __m256 result = _mm256_mask_blend_ps(win, stored, z);
          _mm256_store_ps(at, result);
          far = _mm256_min_ps(far, result);
        }
        alignas(32) float f[8];
        _mm256_store_ps(f, far);
        farSum += *std::min_element(f, f + 8);
      }
    }
    const auto t1 = std::chrono::steady_clock::now();
    ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / double(blocks * 8));
    alignas(64) uint64_t t[8], w[8];
    _mm512_store_si512(t, tests);
    _mm512_store_si512(w, writes);
    sink += t[0] + w[0] + uint64_t(farSum);
  }
  std::sort(ns.begin(), ns.end());
  uint64_t tileSum = 0;  // (modes 0 and 2 store the same bits)
  for (int i = 0; i < kTile * kTile; ++i) {
    uint64_t bits;
    std::memcpy(&bits, &tileD[i], 8);
    tileSum = tileSum * 31 + bits;
  }
  std::printf("mode %d: %.3f ns a row (median of 40), sink %llu, tile %016llx\n", mode, ns[ns.size() / 2],
              (unsigned long long)sink, (unsigned long long)tileSum);
  return 0;
}

// Streaming (non-temporal) writes of 32-bit values into frame buffers, written once against
// Highway and included per instruction set by the files that use them (the tile kernel's resolve,
// core/stream_fill.cpp). A frame buffer is written once per frame and not read back while it is
// written, so the cache lines it covers whole need not be fetched before they are overwritten;
// streamed stores skip that fetch. Lines covered in part take ordinary stores: a streamed line
// that is not written whole goes out piecemeal, far slower — slower even than ordinary stores,
// hence FrameBuffer's cache-line alignment (include/hsr/frame.hpp; figures in
// docs/benchmarks.md). Streamed stores are weakly ordered: a thread fences them
// (hwy::FlushStream) before another thread reads what it wrote.

// Per-target include guard (Highway's pattern: this file is included once per target).
#if defined(HSR_CORE_STREAM_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef HSR_CORE_STREAM_INL_H_
#undef HSR_CORE_STREAM_INL_H_
#else
#define HSR_CORE_STREAM_INL_H_
#endif

#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

HWY_BEFORE_NAMESPACE();
namespace hsr::stream {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

inline constexpr size_t kLineValues = 64 / sizeof(uint32_t);

// Writes n values to dst: at index i, src[i] (Copy) or value (Fill). Whole cache lines streamed.
template <class Source>
HWY_INLINE void StreamWrite(uint32_t* HWY_RESTRICT dst, size_t n, const Source& source) {
  const hn::CappedTag<uint32_t, kLineValues> d;  // a divisor of a line
  const size_t L = hn::Lanes(d);
  const size_t intoLine = reinterpret_cast<uintptr_t>(dst) / sizeof(uint32_t) % kLineValues;
  size_t i = std::min(n, (kLineValues - intoLine) % kLineValues);  // values before dst's next line
  for (size_t j = 0; j < i; ++j) dst[j] = source.at(j);
  for (; i + kLineValues <= n; i += kLineValues)
    for (size_t k = 0; k < kLineValues; k += L) hn::Stream(source.vec(d, i + k), d, dst + i + k);
  for (; i < n; ++i) dst[i] = source.at(i);
}

struct CopySource {
  const uint32_t* HWY_RESTRICT src;
  uint32_t at(size_t i) const { return src[i]; }
  template <class DT>
  hn::Vec<DT> vec(DT d, size_t i) const { return hn::LoadU(d, src + i); }
};
struct FillSource {
  uint32_t value;
  uint32_t at(size_t) const { return value; }
  template <class DT>
  hn::Vec<DT> vec(DT d, size_t) const { return hn::Set(d, value); }
};

// dst[i] = src[i] for i < n (src: e.g. a row staged in L1).
HWY_INLINE void StreamCopy(uint32_t* HWY_RESTRICT dst, const uint32_t* HWY_RESTRICT src, size_t n) {
  StreamWrite(dst, n, CopySource{src});
}
// dst[i] = value for i < n.
HWY_INLINE void StreamFill(uint32_t* HWY_RESTRICT dst, uint32_t value, size_t n) {
  StreamWrite(dst, n, FillSource{value});
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr::stream
HWY_AFTER_NAMESPACE();

#endif  // per-target include guard

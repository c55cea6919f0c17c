// streamFill (core/stream_fill.hpp), compiled per instruction set.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "core/stream_fill.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include "core/stream-inl.h"
#include "core/stream_fill.hpp"

HWY_BEFORE_NAMESPACE();
namespace hsr::stream {
namespace HWY_NAMESPACE {

void FillAndFence(uint32_t* dst, uint32_t value, size_t n) {
  StreamFill(dst, value, n);
  hwy::FlushStream();
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr::stream
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hsr {
namespace stream {
HWY_EXPORT(FillAndFence);
// Dispatched from inside the namespace: HWY_DYNAMIC_DISPATCH names the function unqualified
// when only the static target is compiled (HSR_BASELINE_SIMD_ONLY).
void fillAndFence(uint32_t* dst, uint32_t value, size_t n) { HWY_DYNAMIC_DISPATCH(FillAndFence)(dst, value, n); }
}  // namespace stream

void streamFill(uint32_t* dst, uint32_t value, size_t n) { stream::fillAndFence(dst, value, n); }

}  // namespace hsr
#endif  // HWY_ONCE

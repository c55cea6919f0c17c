// The eye-depth -> [0, 1] mappings of the depth formats, their rounding to the storage and their
// inverse, as inline templates, so the z-buffers' inner loops are compiled per format.
// DepthFormat::map (depth_format.cpp), the reference z-buffer (zbuffer.cpp) and the tiled
// rasterizer (raster/tiled.cpp, whose SIMD kernel repeats these operations lane by lane) use them.
#pragma once
#include <hsr/depth_format.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace hsr {

template <DepthMapping M>
inline double mapDepth(double d, double n, double f, bool ortho) {
  double v;
  if constexpr (M == DepthMapping::Z) {
    v = ortho ? (d - n) / (f - n) : f * (d - n) / ((f - n) * d);
  } else if constexpr (M == DepthMapping::Reversed) {
    // Written directly rather than as 1 - z so no precision is lost near the far plane.
    v = ortho ? (f - d) / (f - n) : n * (f - d) / ((f - n) * d);
  } else if constexpr (M == DepthMapping::Inv) {
    v = n / d;
  } else {
    v = (d - n) / (f - n);
  }
  return std::clamp(v, 0.0, 1.0);
}

/// Stored depth type per storage: u24 lives in 32 bits.
template <DepthStorage S>
using DepthT = std::conditional_t<S == DepthStorage::U16, uint16_t,
                                  std::conditional_t<S == DepthStorage::F32, float, uint32_t>>;

/// Scale of an integer storage: 2^bits - 1.
template <DepthStorage S>
inline constexpr double kDepthScale = S == DepthStorage::U16   ? 65535.0
                                      : S == DepthStorage::U24 ? 16777215.0
                                                               : 4294967295.0;

/// kDepthScale of a storage chosen at run time; 1 for float (its stored value is the mapped one).
inline double depthScaleOf(DepthStorage s) {
  return s == DepthStorage::F32   ? 1.0
         : s == DepthStorage::U16 ? kDepthScale<DepthStorage::U16>
         : s == DepthStorage::U24 ? kDepthScale<DepthStorage::U24>
                                  : kDepthScale<DepthStorage::U32>;
}

/// A mapped value v in [0, 1] as stored: rounded to float, or to the nearest integer code.
template <DepthStorage S>
inline DepthT<S> quantizeDepth(double v) {
  if constexpr (S == DepthStorage::F32) {
    return float(v);
  } else {
    return DepthT<S>(v * kDepthScale<S> + 0.5);
  }
}

/// Eye depth whose mapped value is v: the inverse of mapDepth<M> on [near, far] (v = 0 with the
/// inv mapping gives +inf). Used to report eye depth when only the depth buffer is kept.
template <DepthMapping M>
inline double unmapDepth(double v, double n, double f, bool ortho) {
  if constexpr (M == DepthMapping::Z) {
    return ortho ? n + v * (f - n) : f * n / (f - v * (f - n));
  } else if constexpr (M == DepthMapping::Reversed) {
    return ortho ? f - v * (f - n) : n * f / (n + v * (f - n));
  } else if constexpr (M == DepthMapping::Inv) {
    return v > 0 ? n / v : std::numeric_limits<double>::infinity();
  } else {
    return n + v * (f - n);
  }
}

/// Eye depth of a stored value (integer code or float, as a double).
template <DepthStorage S, DepthMapping M>
inline double eyeDepthOfStored(double stored, double n, double f, bool ortho) {
  const double v = S == DepthStorage::F32 ? stored : stored / kDepthScale<S>;
  return unmapDepth<M>(v, n, f, ortho);
}

/// Calls fn.template operator()<S, M>() with the format's storage and mapping as compile-time
/// values, so that a loop over fragments is compiled once per format (16 loops).
template <class Fn>
void visitDepthFormat(DepthFormat format, Fn&& fn) {
  auto withMapping = [&]<DepthStorage S>() {
    switch (format.mapping) {
      case DepthMapping::Z: return fn.template operator()<S, DepthMapping::Z>();
      case DepthMapping::Reversed: return fn.template operator()<S, DepthMapping::Reversed>();
      case DepthMapping::Inv: return fn.template operator()<S, DepthMapping::Inv>();
      case DepthMapping::Linear: return fn.template operator()<S, DepthMapping::Linear>();
    }
  };
  switch (format.storage) {
    case DepthStorage::U16: return withMapping.template operator()<DepthStorage::U16>();
    case DepthStorage::U24: return withMapping.template operator()<DepthStorage::U24>();
    case DepthStorage::U32: return withMapping.template operator()<DepthStorage::U32>();
    case DepthStorage::F32: return withMapping.template operator()<DepthStorage::F32>();
  }
}

}  // namespace hsr

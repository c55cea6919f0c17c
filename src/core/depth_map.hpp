// The eye-depth -> [0, 1] mappings of the depth formats as inline templates, so the z-buffer's
// inner loop is compiled per mapping. DepthFormat::map (depth_format.cpp) uses the same code.
#pragma once
#include <hsr/depth_format.hpp>

#include <algorithm>

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

}  // namespace hsr

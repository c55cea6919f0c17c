// Depth precision: how finely a depth format separates eye depths, and how its stored values are
// spread over the depth range, computed exactly from the format's own mapping and rounding (the
// ones the z-buffers store). For `hsr precision` and the comparison report (docs/precision.md).
#pragma once
#include <hsr/depth_format.hpp>

#include <cstdint>

namespace hsr {

/// A depth format seen by a perspective camera with planes 0 < near < far.
struct DepthPrecision {
  DepthFormat format;
  double near = 1, far = 100;

  /// The width in eye depth of the set of depths stored as the same value as eye depth d, for d
  /// in [near, far]: the smallest difference in depth the format can separate at d.
  double step(double d) const;
  /// How many distinct values the format stores for eye depths in [a, b] (near <= a <= b <= far).
  uint64_t valuesBetween(double a, double b) const;
  /// The fraction of the values stored for [near, far] that lie in its first part, eye depths in
  /// [near, near + x (far - near)], for x in [0, 1].
  double valueFraction(double x) const;
};

/// Throws InputError unless 0 < near < far, both finite (the message names `what`).
void checkPrecisionPlanes(double near, double far, const char* what);

}  // namespace hsr

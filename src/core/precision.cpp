// Depth precision, exactly (include/hsr/precision.hpp): each stored value covers an interval of
// mapped values (half a code or half a float step either side, as rounding to nearest gives),
// which the format's inverse mapping turns back into an interval of eye depths.
#include <hsr/common.hpp>
#include <hsr/precision.hpp>

#include <bit>
#include <cmath>

#include "core/depth_map.hpp"

namespace hsr {
namespace {

// The stored value's ordinal: the integer code, or the float's bit pattern (ordered like the
// floats themselves for the non-negative values depth maps to).
template <DepthStorage S>
uint64_t ordinal(double v) {
  const DepthT<S> stored = quantizeDepth<S>(v);
  if constexpr (S == DepthStorage::F32) return std::bit_cast<uint32_t>(stored);
  else return uint64_t(stored);
}

// The mapped values [lo, hi] rounded to the same stored value as v.
template <DepthStorage S>
void roundingInterval(double v, double& lo, double& hi) {
  if constexpr (S == DepthStorage::F32) {
    const float f = float(v);
    lo = 0.5 * (double(f) + double(std::nextafter(f, -1.0f)));
    hi = 0.5 * (double(f) + double(std::nextafter(f, 2.0f)));
  } else {
    const double code = double(quantizeDepth<S>(v));
    lo = (code - 0.5) / kDepthScale<S>;
    hi = (code + 0.5) / kDepthScale<S>;
  }
  lo = std::max(lo, 0.0);
  hi = std::min(hi, 1.0);
}

}  // namespace

double DepthPrecision::step(double d) const {
  double width = 0;
  visitDepthFormat(format, [&]<DepthStorage S, DepthMapping M>() {
    double lo = 0, hi = 0;
    roundingInterval<S>(mapDepth<M>(d, near, far, false), lo, hi);
    const double a = unmapDepth<M>(lo, near, far, false), b = unmapDepth<M>(hi, near, far, false);
    width = std::abs(std::min(b, far) - std::min(a, far));
  });
  return width;
}

uint64_t DepthPrecision::valuesBetween(double a, double b) const {
  uint64_t count = 0;
  visitDepthFormat(format, [&]<DepthStorage S, DepthMapping M>() {
    const uint64_t x = ordinal<S>(mapDepth<M>(a, near, far, false));
    const uint64_t y = ordinal<S>(mapDepth<M>(b, near, far, false));
    count = (x > y ? x - y : y - x) + 1;
  });
  return count;
}

double DepthPrecision::valueFraction(double x) const {
  return double(valuesBetween(near, near + x * (far - near))) / double(valuesBetween(near, far));
}

void checkPrecisionPlanes(double near, double far, const char* what) {
  if (!(std::isfinite(near) && std::isfinite(far) && near > 0 && far > near))
    throw InputError(std::string(what) + ": need 0 < near < far, both finite (got near " + std::to_string(near) +
                     ", far " + std::to_string(far) + ")");
}

}  // namespace hsr

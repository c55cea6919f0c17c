// Conservative bounds of the depth values a triangle stores over a convex region of pixel
// centres (its own snapped triangle, or a whole tile), for storage S and mapping M: the tiled
// rasterizer's early rejection (a triangle behind everything a tile holds is skipped) and its
// whole-tile planes (a triangle in front of everything a tile holds replaces it at once) rest
// on them. Used by raster/tiled.cpp and raster/tile_kernel-inl.h.
//
// Why they hold. Eye depth is num/den with num and den affine in the pixel position and den > 0,
// a linear-fractional function: monotone along every line, so over a convex polygon its
// extremes are at the polygon's corners. Every mapping is monotone in eye depth (nearer =
// smaller d), and so are the clamp and the rounding to storage. The rasterizer evaluates num
// and den in double at pixel centres, each with an error of a few ulps of |a||x| + |b||y| + |c|
// (cancellation included), and the mapping with a few ulps of its result: the bounds widen by
// those margins. When the margins are not small (den near 0, a plane much steeper than its
// values) there is no useful bound and the result says "none" (the nearest possible value for
// `nearest`, the farthest possible for `farthest`), which disables the optimisations.
#pragma once
#include <cmath>
#include <limits>

#include "core/depth_map.hpp"
#include "frontend/frontend.hpp"

namespace hsr {

/// Stored values (as double) no fragment is nearer / farther than.
struct StoredRange {
  double nearest, farthest;
};

/// "a is strictly nearer than b" in the stored values of mapping M.
template <DepthMapping M>
inline bool storedNearer(double a, double b) {
  if constexpr (M == DepthMapping::Reversed || M == DepthMapping::Inv) return a > b;
  else return a < b;
}

/// Bounds over the convex polygon of `count` (<= 4) corners (px, py), in pixels.
/// With kFarthest false, only `nearest` is computed (farthest is "none").
template <DepthStorage S, DepthMapping M, bool kFarthest = true>
StoredRange storedRange(const Plane& numPlane, const Plane& denPlane, const double* px, const double* py, int count,
                        double near, double far, bool ortho) {
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr StoredRange none{greater ? inf : -inf, greater ? -inf : inf};
  constexpr double u = 0x1p-52;
  double maxX = 0, maxY = 0;
  for (int i = 0; i < count; ++i) {
    maxX = std::max(maxX, std::abs(px[i]));
    maxY = std::max(maxY, std::abs(py[i]));
  }
  auto error = [&](const Plane& p) {  // absolute, of any evaluation over the region
    return 4 * u * (std::abs(p.a) * maxX + std::abs(p.b) * maxY + std::abs(p.c));
  };
  const double numErr = error(numPlane), denErr = error(denPlane);
  double num[4], den[4], numMin = inf, denMin = inf;
  for (int i = 0; i < count; ++i) {
    num[i] = numPlane.at(px[i], py[i]);
    den[i] = denPlane.at(px[i], py[i]);
    numMin = std::min(numMin, num[i]);
    denMin = std::min(denMin, den[i]);
  }
  const double numLo = numMin - numErr, denLo = denMin - denErr;
  if (!(numLo > 0 && denLo > 0)) return none;  // depth not bounded away from 0 (or NaN)
  // 2 (numErr / numLo + denErr / denLo), with one division: this runs for every triangle.
  const double relative = 2 * (numErr * denLo + denErr * numLo) / (numLo * denLo) + 1e-12;
  if (!(relative < 1e-3)) return none;
  // The corner of smallest depth, compared without dividing (all terms positive); a wrong
  // choice between nearly equal ratios is far inside the margin.
  int nearest = 0;
  for (int i = 1; i < count; ++i)
    if ((num[i] - numErr) * (den[nearest] + denErr) < (num[nearest] - numErr) * (den[i] + denErr)) nearest = i;
  const double dNear = (num[nearest] - numErr) / (den[nearest] + denErr) * (1 - relative);
  // Map, widen by the mapping's own rounding, and round as the storage does (monotone, in
  // double so that out-of-range values stay ordered).
  auto stored = [&](double d, bool towardNear) {
    double v = mapDepth<M>(d, near, far, ortho);
    v = greater == towardNear ? v * (1 + 1e-12) : v * (1 - 1e-12);
    if constexpr (S == DepthStorage::F32) return double(float(v));
    else return std::floor(v * kDepthScale<S> + 0.5);
  };
  StoredRange r{stored(dNear, true), none.farthest};
  if constexpr (kFarthest) {
    int farthest = 0;
    for (int i = 1; i < count; ++i)
      if ((num[i] + numErr) * (den[farthest] - denErr) > (num[farthest] + numErr) * (den[i] - denErr)) farthest = i;
    const double dFar = (num[farthest] + numErr) / (den[farthest] - denErr) * (1 + relative);
    r.farthest = stored(dFar, false);
  }
  return r;
}

}  // namespace hsr

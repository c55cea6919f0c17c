// The stored depth of a fragment, and conservative bounds of it over a region: pure functions of
// a SetupTriangle and the frame's DepthSetup, on any thread. Shared by set-up (nearest bounds),
// the reference z-buffer (algorithms/zbuffer.cpp with --raster halfspace) and the tiled
// rasterizer (raster/binning.cpp, raster/tile_kernel-inl.h), so that all store the same bits.
//
// A fragment at pixel centre (X, Y) stores quantize(clamp(P(X, Y) / Q(X, Y), 0, 1)), where P
// and Q are affine functions of the pixel position built once per triangle from its eye-depth
// planes d = N / D (SetupTriangle: N = d/w, D = 1/w) and the depth mapping (mapPlanes below):
// the mapping of the Ukrainian paper written as one ratio, so a fragment costs one division, not the
// two of mapDepth(N / D). Mathematically the same value; the rounding differs by a few ulps.
// (The scanline rasterizer of the lecture notes steps eye depth along a span instead and stores
// quantize(mapDepth(d)): close to, not bit-identical with, this.)
//
// Bounds (storedRange): P / Q with Q > 0 is a linear-fractional function, monotone along every
// line, so over a convex polygon its extremes are at the corners; the rasterizer evaluates P and
// Q at pixel centres with an error of a few ulps of |a||x| + |b||y| + |c| each, and the ratio
// with a relative ulp; clamp and rounding to storage are monotone. The bounds take the extreme
// corner values, widened by those margins, as the tiled rasterizer's early rejection (a
// triangle behind everything a tile holds is skipped) and its whole-tile planes (a triangle in
// front of everything a tile holds replaces it at once) require. When Q is not bounded away
// from 0 there is no bound: the result says "none" (the nearest possible value for `nearest`,
// the farthest possible for `farthest`), which disables both.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/depth_map.hpp"
#include "setup/fixed_point.hpp"
#include "setup/setup_triangle.hpp"

namespace hsr {

/// The depth buffer a frame is drawn into: its format and the camera's clipping range.
struct DepthSetup {
  DepthFormat format;
  double near = 0, far = 0;
  bool orthographic = false;
};

/// The mapped depth of a triangle's fragments: v(x, y) = p(x, y) / q(x, y), q > 0. When q is a
/// constant (`affine`), mapPlanes has divided p by it once and q is exactly 1: the mapped depth is
/// the affine function p, and p / q = p bit for bit, so a rasterizer may skip the division.
struct MappedPlanes {
  Plane p, q;
  bool affine = false;
};

/// P and Q for mapping M (near n, far f): with d = N / D,
///   z:        f (d - n) / ((f - n) d) = f (N - n D) / ((f - n) N)    (orthographic: linear)
///   reversed: n (f - d) / ((f - n) d) = n (f D - N) / ((f - n) N)    (orthographic: (f D - N) / ((f - n) D))
///   inv:      n / d                   = n D / N
///   linear:   (d - n) / (f - n)       = (N - n D) / ((f - n) D)
/// With a perspective camera w is the eye depth, so N = d / w is exactly 1 at every vertex and
/// its plane is the constant 1; Q is then constant for z, reversed and inv (and with an
/// orthographic camera D = 1 / w = 1 makes it constant for z, reversed and linear): the mapped
/// depth is affine in the image — the property GPUs' z / w has — and normalize() turns P / Q
/// into P' = P * (1 / Q), one division per triangle instead of one per fragment.
template <DepthMapping M>
inline MappedPlanes mapPlanesRaw(const Plane& N, const Plane& D, double n, double f, bool ortho) {
  auto combine = [](double s, const Plane& a, double t, const Plane& b) {  // s a + t b
    return Plane{s * a.a + t * b.a, s * a.b + t * b.b, s * a.c + t * b.c};
  };
  auto scale = [](double s, const Plane& a) { return Plane{s * a.a, s * a.b, s * a.c}; };
  const double range = f - n;
  if constexpr (M == DepthMapping::Z) {
    if (!ortho) return {combine(f, N, -f * n, D), scale(range, N)};
    return {combine(1, N, -n, D), scale(range, D)};
  } else if constexpr (M == DepthMapping::Reversed) {
    if (!ortho) return {combine(n * f, D, -n, N), scale(range, N)};
    return {combine(f, D, -1, N), scale(range, D)};
  } else if constexpr (M == DepthMapping::Inv) {
    return {scale(n, D), N};
  } else {
    return {combine(1, N, -n, D), scale(range, D)};
  }
}

/// The reciprocal normalize() took last, for a rasterizer mapping triangle after triangle:
/// with a perspective camera every triangle's constant Q is the same ((f - n) N, N = 1) for z,
/// reversed and inv, and the same Q gives the same reciprocal — so normalize(m, cache) is
/// normalize(m) bit for bit, without a division per triangle.
struct ReciprocalCache {
  double q = 0, r = 0;  // q = 0: nothing kept (normalize divides only by q >= the least normal)
};
inline MappedPlanes normalize(MappedPlanes m, ReciprocalCache& cache) {
  if (m.q.a == 0 && m.q.b == 0 && m.q.c >= std::numeric_limits<double>::min() &&
      m.q.c <= std::numeric_limits<double>::max()) {
    if (m.q.c != cache.q) cache = {m.q.c, 1.0 / m.q.c};
    const double r = cache.r;
    m.p = Plane{m.p.a * r, m.p.b * r, m.p.c * r};
    m.q = Plane{0.0, 0.0, 1.0};
    m.affine = true;
  }
  return m;
}
inline MappedPlanes normalize(MappedPlanes m) {
  ReciprocalCache none;
  return normalize(m, none);
}

/// P and Q of mapping M, normalized (see normalize()): what every rasterizer uses.
template <DepthMapping M>
inline MappedPlanes mapPlanes(const Plane& N, const Plane& D, double n, double f, bool ortho) {
  return normalize(mapPlanesRaw<M>(N, D, n, f, ortho));
}
template <DepthMapping M>
inline MappedPlanes mapPlanes(const Plane& N, const Plane& D, double n, double f, bool ortho, ReciprocalCache& cache) {
  return normalize(mapPlanesRaw<M>(N, D, n, f, ortho), cache);
}

/// The stored value (as double: exact for every storage) of the ratio p / q: clamped to [0, 1]
/// as std::clamp does (NaN stays NaN), rounded as the storage does.
template <DepthStorage S>
inline double storedOfRatio(double p, double q) {
  return double(quantizeDepth<S>(std::clamp(p / q, 0.0, 1.0)));
}

/// The stored value of the fragment at pixel centre (X, Y); `pRow` = m.p.b * Y and
/// `qRow` = m.q.b * Y (computed once per row, as the SIMD kernel does).
template <DepthStorage S>
inline double fragmentStored(const MappedPlanes& m, double X, double pRow, double qRow) {
  const double p = (m.p.a * X + pRow) + m.p.c;
  if (m.affine) return double(quantizeDepth<S>(std::clamp(p, 0.0, 1.0)));  // p / 1, without dividing
  return storedOfRatio<S>(p, (m.q.a * X + qRow) + m.q.c);
}

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

/// The bound on how far a plane's value computed at any point with |x| <= maxX, |y| <= maxY can
/// be from another point's computed value beyond the true difference: an evaluation errs by at
/// most ~3 ulps of |a||x| + |b||y| + |c| (three roundings); twice that, with room.
inline double planeError(const Plane& p, double maxX, double maxY) {
  constexpr double u = 0x1p-52;
  return 8 * u * (std::abs(p.a) * maxX + std::abs(p.b) * maxY + std::abs(p.c));
}

/// Stored values no fragment is nearer / farther than, given that every fragment's computed p
/// lies in [pMin, pMax] and q in [qMin, qMax] (errors included). "None" (no bound) unless q > 0
/// and all are finite. With kFarthest false only `nearest` is computed: one division less.
template <DepthStorage S, DepthMapping M, bool kFarthest = true>
StoredRange storedRangeOfBounds(const MappedPlanes& m, double pMin, double pMax, double qMin, double qMax) {
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr StoredRange none{greater ? inf : -inf, greater ? -inf : inf};
  if (!(qMin > 0) || !std::isfinite(pMin) || !std::isfinite(pMax) || !std::isfinite(qMax)) return none;
  // p / q over [pMin, pMax] x [qMin, qMax], q > 0 (just p when affine: q = 1 and fragments do
  // not divide); then room for the divisions' rounding.
  auto lowStored = [&] {
    double low = m.affine ? pMin : pMin >= 0 ? pMin / qMax : pMin / qMin;
    low -= std::abs(low) * 1e-12;
    return double(quantizeDepth<S>(std::clamp(low, 0.0, 1.0)));
  };
  auto highStored = [&] {
    double high = m.affine ? pMax : pMax >= 0 ? pMax / qMin : pMax / qMax;
    high += std::abs(high) * 1e-12;
    return double(quantizeDepth<S>(std::clamp(high, 0.0, 1.0)));
  };
  if constexpr (!kFarthest) return greater ? StoredRange{highStored(), none.farthest} : StoredRange{lowStored(), none.farthest};
  return greater ? StoredRange{highStored(), lowStored()} : StoredRange{lowStored(), highStored()};
}

/// Bounds over the convex polygon of `count` (<= 4) corners (px, py), in pixels. With
/// kFarthest false only `nearest` is computed (`farthest` is "none"): one division less.
template <DepthStorage S, DepthMapping M, bool kFarthest = true>
StoredRange storedRange(const MappedPlanes& m, const double* px, const double* py, int count) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  double maxX = 0, maxY = 0;
  for (int i = 0; i < count; ++i) {
    maxX = std::max(maxX, std::abs(px[i]));
    maxY = std::max(maxY, std::abs(py[i]));
  }
  const double pErr = planeError(m.p, maxX, maxY), qErr = planeError(m.q, maxX, maxY);
  double pMin = inf, pMax = -inf, qMin = inf, qMax = -inf;
  for (int i = 0; i < count; ++i) {
    const double p = m.p.at(px[i], py[i]), q = m.q.at(px[i], py[i]);
    pMin = std::min(pMin, p);
    pMax = std::max(pMax, p);
    qMin = std::min(qMin, q);
    qMax = std::max(qMax, q);
  }
  return storedRangeOfBounds<S, M, kFarthest>(m, pMin - pErr, pMax + pErr, qMin - qErr, qMax + qErr);
}

/// storedRange over the rectangle [left, right] x [top, bottom] (0 <= left <= right, 0 <= top <=
/// bottom), with the planes' errors pErr and qErr from planeError for some maxX >= right and
/// maxY >= bottom (computed once for many rectangles, e.g. a tile's blocks). A plane is extreme
/// at the corner its slopes point to: evaluated there, as at any corner, its computed value is
/// within the error of the true extreme.
template <DepthStorage S, DepthMapping M>
StoredRange storedRangeOverRect(const MappedPlanes& m, double pErr, double qErr, double left, double right,
                                double top, double bottom) {
  const Plane &p = m.p, &q = m.q;
  const double pMin = p.at(p.a >= 0 ? left : right, p.b >= 0 ? top : bottom);
  const double pMax = p.at(p.a >= 0 ? right : left, p.b >= 0 ? bottom : top);
  const double qMin = q.at(q.a >= 0 ? left : right, q.b >= 0 ? top : bottom);
  const double qMax = q.at(q.a >= 0 ? right : left, q.b >= 0 ? bottom : top);
  return storedRangeOfBounds<S, M>(m, pMin - pErr, pMax + pErr, qMin - qErr, qMax + qErr);
}

/// storedRange over the snapped corners of `t`, in `depth`: every covered pixel centre lies in
/// the snapped triangle, so no fragment of `t` is nearer / farther than the result.
template <DepthStorage S, DepthMapping M, bool kFarthest = true>
StoredRange triangleStoredRange(const SetupTriangle& t, const DepthSetup& depth) {
  double px[3], py[3];
  for (int i = 0; i < 3; ++i) {
    px[i] = double(t.x[i]) / double(kSubpixelOne);
    py[i] = double(t.y[i]) / double(kSubpixelOne);
  }
  const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, depth.orthographic);
  return storedRange<S, M, kFarthest>(m, px, py, 3);
}

/// A stored value that no fragment of `t` is nearer than, for storage S and mapping M.
/// (setupBatch computes the same bits with SIMD.)
template <DepthStorage S, DepthMapping M>
double nearestStored(const SetupTriangle& t, const DepthSetup& depth) {
  return triangleStoredRange<S, M, false>(t, depth).nearest;
}

/// nearestStored for the depth setup's format, chosen at run time.
inline double nearestStored(const SetupTriangle& t, const DepthSetup& depth) {
  double nearest = 0;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() { nearest = nearestStored<S, M>(t, depth); });
  return nearest;
}

}  // namespace hsr

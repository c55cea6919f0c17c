// Triangle set-up over batches with SIMD (Highway, dispatched at run time): setupBatch
// (triangle_setup.hpp) writes the SetupTriangles, nearest bounds and deferred faces of a batch of
// triangles inside the clip volume. Called by the front end's set-up workers (frontend.cpp) and
// by the tile pass for deferred triangles (raster/tile_pass.cpp).
//
// The same arithmetic as setupTriangle(const ProjectedVertex*, ...) in frontend.cpp, lane by
// lane: every value is an IEEE double operation in the same order (or an exact integer in
// double: fixed-point coordinates are below 2^24, their products below 2^49), so a batch gives
// bit for bit the scalar function's SetupTriangles (tests/raster_test.cpp). Clipped ones stay scalar.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "frontend/setup_batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include "core/depth_map.hpp"
#include "frontend/triangle_setup.hpp"
#include "setup/fixed_point.hpp"
#include "setup/fragment_depth.hpp"

HWY_BEFORE_NAMESPACE();
namespace hsr {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, kSetupBatch>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;

// An affine function of pixel position per lane (Plane, lane by lane).
struct PlaneV {
  V a, b, c;
};

// s x + t y and s x, as mapPlanes' combine and scale compute them (setup/fragment_depth.hpp).
HWY_INLINE PlaneV Combine(double s, const PlaneV& x, double t, const PlaneV& y) {
  const D d;
  const V sv = hn::Set(d, s), tv = hn::Set(d, t);
  return {hn::Add(hn::Mul(sv, x.a), hn::Mul(tv, y.a)), hn::Add(hn::Mul(sv, x.b), hn::Mul(tv, y.b)),
          hn::Add(hn::Mul(sv, x.c), hn::Mul(tv, y.c))};
}
HWY_INLINE PlaneV Scale(double s, const PlaneV& x) {
  const D d;
  const V sv = hn::Set(d, s);
  return {hn::Mul(sv, x.a), hn::Mul(sv, x.b), hn::Mul(sv, x.c)};
}

// nearestStored() (setup/fragment_depth.hpp: mapPlanes, then storedRange<S, M, false> over the
// snapped corners px, py) lane by lane, with the same IEEE operations in the same order, for the
// depth setup's format chosen at run time.
HWY_INLINE V NearestStored(const DepthSetup& depth, const PlaneV& N, const PlaneV& Dn, const V* px, const V* py) {
  const D d;
  const double n = depth.near, f = depth.far, range = f - n;
  const bool ortho = depth.orthographic;
  const DepthMapping mapping = depth.format.mapping;
  PlaneV P, Q;
  switch (mapping) {
    case DepthMapping::Z:
      P = ortho ? Combine(1, N, -n, Dn) : Combine(f, N, -f * n, Dn);
      Q = Scale(range, ortho ? Dn : N);
      break;
    case DepthMapping::Reversed:
      P = ortho ? Combine(f, Dn, -1, N) : Combine(n * f, Dn, -n, N);
      Q = Scale(range, ortho ? Dn : N);
      break;
    case DepthMapping::Inv:
      P = Scale(n, Dn);
      Q = N;
      break;
    default:
      P = Combine(1, N, -n, Dn);
      Q = Scale(range, Dn);
  }
  // normalize(): a constant Q divides P once, and becomes 1.
  const M constant = hn::And(hn::And(hn::Eq(Q.a, hn::Zero(d)), hn::Eq(Q.b, hn::Zero(d))),
                             hn::And(hn::Ge(Q.c, hn::Set(d, std::numeric_limits<double>::min())),
                                     hn::Le(Q.c, hn::Set(d, std::numeric_limits<double>::max()))));
  const V r = hn::Div(hn::Set(d, 1.0), Q.c);
  P = {hn::IfThenElse(constant, hn::Mul(P.a, r), P.a), hn::IfThenElse(constant, hn::Mul(P.b, r), P.b),
       hn::IfThenElse(constant, hn::Mul(P.c, r), P.c)};
  Q = {hn::IfThenElseZero(hn::Not(constant), Q.a), hn::IfThenElseZero(hn::Not(constant), Q.b),
       hn::IfThenElse(constant, hn::Set(d, 1.0), Q.c)};
  const bool greater = mapping == DepthMapping::Reversed || mapping == DepthMapping::Inv;
  const double inf = std::numeric_limits<double>::infinity();
  V maxX = hn::Zero(d), maxY = hn::Zero(d);
  for (int i = 0; i < 3; ++i) {
    maxX = hn::IfThenElse(hn::Lt(maxX, hn::Abs(px[i])), hn::Abs(px[i]), maxX);
    maxY = hn::IfThenElse(hn::Lt(maxY, hn::Abs(py[i])), hn::Abs(py[i]), maxY);
  }
  const V eightUlp = hn::Set(d, 8 * 0x1p-52);
  auto error = [&](const PlaneV& p) {
    return hn::Mul(eightUlp, hn::Add(hn::Add(hn::Mul(hn::Abs(p.a), maxX), hn::Mul(hn::Abs(p.b), maxY)), hn::Abs(p.c)));
  };
  // (When every lane is affine, as with a perspective camera and z, reversed or inv, Q is 1:
  // q is 1 at every corner ((0 x + 0 y) + 1), its bounds 1 -+ 8 ulp, positive and finite, so Q
  // is not evaluated, and the quotients are not needed: two vector divisions less.)
  const bool allConstant = hn::AllTrue(d, constant);
  const V pErr = error(P);
  V pMin = hn::Set(d, inf), pMax = hn::Set(d, -inf), qMin = pMin, qMax = pMax;
  for (int i = 0; i < 3; ++i) {
    const V p = hn::Add(hn::Add(hn::Mul(P.a, px[i]), hn::Mul(P.b, py[i])), P.c);
    pMin = hn::IfThenElse(hn::Lt(p, pMin), p, pMin);  // std::min(pMin, p)
    pMax = hn::IfThenElse(hn::Lt(pMax, p), p, pMax);  // std::max(pMax, p)
  }
  pMin = hn::Sub(pMin, pErr);
  pMax = hn::Add(pMax, pErr);
  M bounded = hn::And(hn::IsFinite(pMin), hn::IsFinite(pMax));
  if (!allConstant) {
    const V qErr = error(Q);
    for (int i = 0; i < 3; ++i) {
      const V q = hn::Add(hn::Add(hn::Mul(Q.a, px[i]), hn::Mul(Q.b, py[i])), Q.c);
      qMin = hn::IfThenElse(hn::Lt(q, qMin), q, qMin);
      qMax = hn::IfThenElse(hn::Lt(qMax, q), q, qMax);
    }
    qMin = hn::Sub(qMin, qErr);
    qMax = hn::Add(qMax, qErr);
    bounded = hn::And(bounded, hn::And(hn::Gt(qMin, hn::Zero(d)), hn::IsFinite(qMax)));
  }
  const V margin = hn::Set(d, 1e-12);
  V v;
  if (greater) {  // highStored: the largest value (just pMax when affine)
    v = allConstant ? pMax : hn::IfThenElse(hn::Ge(pMax, hn::Zero(d)), hn::Div(pMax, qMin), hn::Div(pMax, qMax));
    v = hn::IfThenElse(constant, pMax, v);
    v = hn::Add(v, hn::Mul(hn::Abs(v), margin));
  } else {  // lowStored: the smallest
    v = allConstant ? pMin : hn::IfThenElse(hn::Ge(pMin, hn::Zero(d)), hn::Div(pMin, qMax), hn::Div(pMin, qMin));
    v = hn::IfThenElse(constant, pMin, v);
    v = hn::Sub(v, hn::Mul(hn::Abs(v), margin));
  }
  // std::clamp(v, 0, 1), then quantizeDepth of the storage (as a double).
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0);
  v = hn::IfThenElse(hn::Lt(v, zero), zero, hn::IfThenElse(hn::Lt(one, v), one, v));
  const DepthStorage storage = depth.format.storage;
  if (storage == DepthStorage::F32) {
    v = hn::PromoteTo(d, hn::DemoteTo(hn::Rebind<float, D>(), v));
  } else {  // v * scale + 0.5, truncated (v >= 0: floor)
    const double scale = depthScaleOf(storage);
    v = hn::Floor(hn::Add(hn::Mul(v, hn::Set(d, scale)), hn::Set(d, 0.5)));
  }
  return hn::IfThenElse(bounded, v, hn::Set(d, greater ? inf : -inf));
}

// The fields of the three vertices (ProjectedVertex: sx, sy, num, den; 4 x 8 bytes) of the
// triangles [first, first + lanes) of the lists `vertex`, lane by lane (a last, partial vector
// repeats its last triangle).
HWY_INLINE void LoadVertices(const ProjectedVertex* projected, const uint32_t* const* vertex, size_t first,
                             size_t lanes, V* sx, V* sy, V* num, V* den) {
  const D d;
  const size_t N = hn::Lanes(d);
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  // Each lane's vertex indices: the batch's own lists, or (a last, partial batch) its last
  // triangle's repeated.
  uint32_t padded[3][kSetupBatch];
  const uint32_t* index[3];
  for (int k = 0; k < 3; ++k) {
    index[k] = vertex[k] + first;
    if (lanes < N) {
      for (size_t j = 0; j < N; ++j) padded[k][j] = vertex[k][first + std::min(j, lanes - 1)];
      index[k] = padded[k];
    }
  }
#else
  HWY_ALIGN int64_t offset[3][kSetupBatch];
  for (int k = 0; k < 3; ++k)
    for (size_t j = 0; j < N; ++j)
      offset[k][j] = int64_t(vertex[k][first + std::min(j, lanes - 1)]) * int64_t(sizeof(ProjectedVertex) / 8);
#endif
  const double* base = reinterpret_cast<const double*>(projected);
  for (int k = 0; k < 3; ++k) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
    // Each vertex loaded whole (4 doubles, one 32-byte load) and each group of 4 transposed,
    // rather than 4 gathers, which are slower on both AVX-512 (8 lanes, two groups) and AVX2
    // (4 lanes, one group); see docs/benchmarks.md.
    static_assert(kSetupBatch == 8);
    using H4 = hn::CappedTag<double, 4>;  // one vertex's 4 fields
    const H4 h;
    using H = hn::Vec<H4>;
    constexpr int kGroups = int(hn::MaxLanes(D())) / 4;
    static_assert(kGroups == 1 || kGroups == 2);
    H field[4][kGroups];  // sx, sy, num, den; lanes 0-3 (and 4-7)
    for (int g = 0; g < kGroups; ++g) {
      H q[4];
      for (int j = 0; j < 4; ++j)
        q[j] = hn::LoadU(h, base + size_t(index[k][4 * g + j]) * (sizeof(ProjectedVertex) / 8));
      const H l01 = hn::InterleaveLower(h, q[0], q[1]), u01 = hn::InterleaveUpper(h, q[0], q[1]);  // sx sx n n / sy sy d d
      const H l23 = hn::InterleaveLower(h, q[2], q[3]), u23 = hn::InterleaveUpper(h, q[2], q[3]);
      field[0][g] = hn::ConcatLowerLower(h, l23, l01);
      field[1][g] = hn::ConcatLowerLower(h, u23, u01);
      field[2][g] = hn::ConcatUpperUpper(h, l23, l01);
      field[3][g] = hn::ConcatUpperUpper(h, u23, u01);
    }
#if HWY_TARGET <= HWY_AVX3
    sx[k] = hn::Combine(d, field[0][1], field[0][0]);
    sy[k] = hn::Combine(d, field[1][1], field[1][0]);
    num[k] = hn::Combine(d, field[2][1], field[2][0]);
    den[k] = hn::Combine(d, field[3][1], field[3][0]);
#else
    sx[k] = field[0][0], sy[k] = field[1][0], num[k] = field[2][0], den[k] = field[3][0];
#endif
#else
    const auto idx = hn::Load(hn::Rebind<int64_t, D>(), offset[k]);
    sx[k] = hn::GatherIndex(d, base + 0, idx);
    sy[k] = hn::GatherIndex(d, base + 1, idx);
    num[k] = hn::GatherIndex(d, base + 2, idx);
    den[k] = hn::GatherIndex(d, base + 3, idx);
#endif
  }
}

// Snaps the vertices (snapCoordinate: an integer below 2^23, the same in double as in int64)
// into X, Y and classifies each of the first `lanes` lanes by twice its signed area on the
// snapped grid (exact): degenerate (0 or NaN) or culled by `cull` (never a degenerate one), both
// counted, else live; front facing when negative (counter-clockwise with y down). Returns the
// twice signed area.
HWY_INLINE V Facing(const V* sx, const V* sy, Cull cull, size_t lanes, FrontEndCounters& counters, V* X, V* Y,
                    M& front, M& live) {
  const D d;
  const V subpixel = hn::Set(d, double(kSubpixelOne)), halfUnit = hn::Set(d, 0.5);
  for (int k = 0; k < 3; ++k) {
    X[k] = hn::Floor(hn::Add(hn::Mul(sx[k], subpixel), halfUnit));
    Y[k] = hn::Floor(hn::Add(hn::Mul(sy[k], subpixel), halfUnit));
  }
  const V zero = hn::Zero(d);
  const V area = hn::Sub(hn::Mul(hn::Sub(X[1], X[0]), hn::Sub(Y[2], Y[0])), hn::Mul(hn::Sub(Y[1], Y[0]), hn::Sub(X[2], X[0])));
  // Degenerate also when the area is NaN (a vertex projected to NaN): such a lane must not
  // survive to the records, whose coordinates are integers.
  front = hn::Lt(area, zero);
  const M degenerate = hn::Not(hn::Or(front, hn::Gt(area, zero)));
  M culled = hn::FirstN(d, 0);
  if (cull == Cull::Back) culled = hn::AndNot(front, hn::Not(degenerate));
  if (cull == Cull::Front) culled = front;
  culled = hn::AndNot(degenerate, culled);
  const M valid = hn::FirstN(d, lanes);
  counters.degenerate += hn::CountTrue(d, hn::And(valid, degenerate));
  counters.culledBackface += hn::CountTrue(d, hn::And(valid, culled));
  live = hn::AndNot(hn::Or(degenerate, culled), valid);
  return area;
}

// The triangles of a batch: triangle i has vertices projected[vertex[0..2][i]], scene index
// triIndex[i] and face face[i].
struct BatchInput {
  const ProjectedVertex* projected;
  const uint32_t* const* vertex;
  const uint32_t* triIndex;
  const uint32_t* face;
  size_t count;
};

// Where SetupLanes writes, and how much it has written: the survivors to out[0, written) (and
// their bounds to nearest[0, written), when not null), the deferred back faces to
// deferred[0, deferredWritten) (when not null).
struct BatchSink {
  SetupTriangle* out;
  double* nearest;
  DeferredFace* deferred;
  size_t written = 0, deferredWritten = 0;
};

// One vector of triangles in set-up, filled in step by step (the steps below, in order): lane j
// holds triangle first + j of the batch, for j < lanes (a last, partial vector repeats its last
// triangle in the other lanes).
struct LaneGroup {
  size_t first, lanes;
  // LoadGroup: the vertices' fields, snapped positions (1/256 pixel), twice the signed area,
  // front facing, and live (neither degenerate nor culled, and j < lanes).
  V sx[3], sy[3], num[3], den[3], X[3], Y[3];
  V area;
  M front, live;
  // PixelBoxOf: the snapped vertices' extremes (1/256 pixel); the pixel box in the image
  // (inclusive) and its size; no pixel centre in the box; off screen; at most kCoverageBox
  // pixels each way.
  V minX, maxX, minY, maxY;
  V x0, x1, y0, y1, width, height;
  M noBox, offScreen, small;
  // CoverageOf: SetupTriangle::coverage (0 unless small).
  V coverage;
  // DepthPlanesOf: SetupTriangle::depthNum and depthDen; the snapped corners in pixels.
  PlaneV depthNum, depthDen;
  V px[3], py[3];
};

// The lanes of the fields a record is written from (StoreLanes), one row of kSetupBatch lanes
// per field.
enum LaneField { kLaneX = 0, kLaneY = 3, kLaneMinX = 6, kLaneMaxX, kLaneMinY, kLaneMaxY, kLaneDepthNum,
                 kLaneDepthDen = kLaneDepthNum + 3, kLaneNearest = kLaneDepthDen + 3, kLaneFront, kLaneCoverage,
                 kLaneFields };
struct LaneArrays {
  HWY_ALIGN double v[kLaneFields][kSetupBatch];
};

// Step 1: the vertices of triangles [first, first + lanes) loaded, snapped and classified (Facing).
HWY_INLINE void LoadGroup(const BatchInput& in, Cull cull, FrontEndCounters& counters, LaneGroup& g) {
  LoadVertices(in.projected, in.vertex, g.first, g.lanes, g.sx, g.sy, g.num, g.den);
  g.area = Facing(g.sx, g.sy, cull, g.lanes, counters, g.X, g.Y, g.front, g.live);
}

// Step 2: the vertex order that makes the edge functions positive inside: 1 and 2 swapped in
// the lanes whose area is negative (front facing).
HWY_INLINE void OrderVertices(LaneGroup& g) {
  auto order = [&](V* a) {
    const V a1 = hn::IfThenElse(g.front, a[2], a[1]), a2 = hn::IfThenElse(g.front, a[1], a[2]);
    a[1] = a1;
    a[2] = a2;
  };
  order(g.sx), order(g.sy), order(g.X), order(g.Y), order(g.num), order(g.den);
}

// Step 3: the pixel box, x in [ceil((min - 1/2) / 1), floor((max - 1/2))] in pixels, in the image.
HWY_INLINE void PixelBoxOf(const Camera& cam, LaneGroup& g) {
  const D d;
  const V zero = hn::Zero(d);
  const V one = hn::Set(d, double(kSubpixelOne)), half = hn::Set(d, double(kSubpixelOne / 2));
  const V* X = g.X;
  const V* Y = g.Y;
  g.minX = hn::Min(hn::Min(X[0], X[1]), X[2]), g.maxX = hn::Max(hn::Max(X[0], X[1]), X[2]);
  g.minY = hn::Min(hn::Min(Y[0], Y[1]), Y[2]), g.maxY = hn::Max(hn::Max(Y[0], Y[1]), Y[2]);
  const V inv256 = hn::Set(d, 1.0 / double(kSubpixelOne));
  g.x0 = hn::Max(zero, hn::Ceil(hn::Mul(hn::Sub(g.minX, half), inv256)));
  g.x1 = hn::Min(hn::Set(d, double(cam.width - 1)), hn::Floor(hn::Mul(hn::Sub(g.maxX, half), inv256)));
  g.y0 = hn::Max(zero, hn::Ceil(hn::Mul(hn::Sub(g.minY, half), inv256)));
  g.y1 = hn::Min(hn::Set(d, double(cam.height - 1)), hn::Floor(hn::Mul(hn::Sub(g.maxY, half), inv256)));
  g.noBox = hn::Or(hn::Gt(g.x0, g.x1), hn::Gt(g.y0, g.y1));
  g.offScreen = hn::Or(hn::Or(hn::Lt(g.maxX, zero), hn::Lt(g.maxY, zero)),
                       hn::Or(hn::Gt(g.minX, hn::Mul(hn::Set(d, double(cam.width)), one)),
                              hn::Gt(g.minY, hn::Mul(hn::Set(d, double(cam.height)), one))));
  g.width = hn::Add(hn::Sub(g.x1, g.x0), hn::Set(d, 1.0));
  g.height = hn::Add(hn::Sub(g.y1, g.y0), hn::Set(d, 1.0));
  const V boxLimit = hn::Set(d, double(kCoverageBox));
  g.small = hn::AndNot(g.noBox, hn::And(hn::Le(g.width, boxLimit), hn::Le(g.height, boxLimit)));
}

// The three edge functions of a vector of triangles at the centre of their boxes' first pixel,
// their steps per pixel in x (A) and y (B), and the top-left rule's bias (setup/edge.hpp).
struct EdgesV {
  V row[3], stepA[3], stepB[3], bias[3];
};

// Step 4a: edge set-up. Every value is an integer below 2^53 (A = -dy, B = dx per 1/256 pixel,
// stepped by whole pixels), exact in any order.
HWY_INLINE EdgesV EdgesOf(const LaneGroup& g) {
  const D d;
  const V zero = hn::Zero(d);
  const V one = hn::Set(d, double(kSubpixelOne)), half = hn::Set(d, double(kSubpixelOne / 2));
  EdgesV e;
  V edx[3], edy[3];
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    edx[i] = hn::Sub(g.X[j], g.X[i]);
    edy[i] = hn::Sub(g.Y[j], g.Y[i]);
    const M topLeft = hn::Or(hn::Lt(edy[i], zero), hn::And(hn::Eq(edy[i], zero), hn::Gt(edx[i], zero)));
    e.bias[i] = hn::IfThenElseZero(hn::Not(topLeft), hn::Set(d, 1.0));
  }
  const V px = hn::Add(hn::Mul(g.x0, one), half), py = hn::Add(hn::Mul(g.y0, one), half);
  for (int i = 0; i < 3; ++i) {
    e.row[i] = hn::Sub(hn::Mul(edx[i], hn::Sub(py, g.Y[i])), hn::Mul(edy[i], hn::Sub(px, g.X[i])));
    e.stepA[i] = hn::Mul(hn::Neg(edy[i]), one);
    e.stepB[i] = hn::Mul(edx[i], one);
  }
  return e;
}

// Step 4b: for the small boxes (at most kCoverageBox centres each way), the centres the
// triangle covers, one bit each (SetupTriangle::coverage), centre (ox, oy) of the box counting
// 2^(4 oy + ox); 0 in the other lanes.
HWY_INLINE void CoverageOf(LaneGroup& g) {
  const D d;
  g.coverage = hn::Zero(d);
  if (hn::AllFalse(d, g.small)) return;
  EdgesV e = EdgesOf(g);
  // Only as many rows and columns as the vector's largest small box has. A lane's centres beyond
  // its own box are outside its triangle (right of or below every vertex: some edge function is
  // negative there), unless the image's edge cut the box short: only then are they masked, by
  // rowIn and the column test (the masks cost time in every lane, so they are left out when no
  // box was cut).
  const V half = hn::Set(d, double(kSubpixelOne / 2)), inv256 = hn::Set(d, 1.0 / double(kSubpixelOne));
  const V bw = g.width, bh = g.height;
  const int rows = int(hn::GetLane(hn::MaxOfLanes(d, hn::IfThenElseZero(g.small, bh))));
  const int cols = int(hn::GetLane(hn::MaxOfLanes(d, hn::IfThenElseZero(g.small, bw))));
  const V rightmost = hn::Floor(hn::Mul(hn::Sub(g.maxX, half), inv256));
  const V lowest = hn::Floor(hn::Mul(hn::Sub(g.maxY, half), inv256));
  const bool cut = !hn::AllFalse(d, hn::And(g.small, hn::Or(hn::Lt(g.x1, rightmost), hn::Lt(g.y1, lowest))));
  V coverage = hn::Zero(d);
  auto cover = [&](auto masked) HWY_ATTR {
    for (int oy = 0; oy < rows; ++oy) {
      V edge[3] = {e.row[0], e.row[1], e.row[2]};
      const M rowIn = hn::Lt(hn::Set(d, double(oy)), bh);
      for (int ox = 0; ox < cols; ++ox) {
        M inside = hn::Ge(edge[0], e.bias[0]);
        if constexpr (decltype(masked)::value)
          inside = hn::And(inside, hn::And(rowIn, hn::Lt(hn::Set(d, double(ox)), bw)));
        edge[0] = hn::Add(edge[0], e.stepA[0]);
        for (int i = 1; i < 3; ++i) {
          inside = hn::And(inside, hn::Ge(edge[i], e.bias[i]));
          edge[i] = hn::Add(edge[i], e.stepA[i]);
        }
        coverage = hn::Add(coverage, hn::IfThenElseZero(inside, hn::Set(d, double(1 << (oy * kCoverageBox + ox)))));
      }
      for (int i = 0; i < 3; ++i) e.row[i] = hn::Add(e.row[i], e.stepB[i]);
    }
  };
  if (cut) cover(std::true_type());
  else cover(std::false_type());
  g.coverage = hn::IfThenElseZero(g.small, coverage);
}

// Step 5: the depth planes, through the unsnapped positions unless that triangle is (nearly)
// degenerate, then through the snapped corners (as setupTriangle decides).
HWY_INLINE void DepthPlanesOf(LaneGroup& g) {
  const D d;
  const V* sx = g.sx;
  const V* sy = g.sy;
  const V exactArea = hn::Sub(hn::Mul(hn::Sub(sx[1], sx[0]), hn::Sub(sy[2], sy[0])),
                              hn::Mul(hn::Sub(sy[1], sy[0]), hn::Sub(sx[2], sx[0])));
  // (Divisions by powers of two are multiplications by their exact reciprocals: same bits.)
  const M useExact = hn::Gt(exactArea, hn::Mul(hn::Mul(hn::Set(d, 0.5), hn::Abs(g.area)),
                                               hn::Set(d, 1.0 / double(kSubpixelOne * kSubpixelOne))));
  const V inv256 = hn::Set(d, 1.0 / double(kSubpixelOne));
  for (int k = 0; k < 3; ++k) {
    g.px[k] = hn::Mul(g.X[k], inv256);
    g.py[k] = hn::Mul(g.Y[k], inv256);
  }
  V x[3], y[3];
  for (int k = 0; k < 3; ++k) {
    x[k] = hn::IfThenElse(useExact, sx[k], g.px[k]);
    y[k] = hn::IfThenElse(useExact, sy[k], g.py[k]);
  }
  const V x1 = hn::Sub(x[1], x[0]), y1 = hn::Sub(y[1], y[0]), x2 = hn::Sub(x[2], x[0]), y2 = hn::Sub(y[2], y[0]);
  const V inv = hn::Div(hn::Set(d, 1.0), hn::Sub(hn::Mul(x1, y2), hn::Mul(x2, y1)));
  auto through = [&](const V* val, PlaneV& p) {
    const V v1 = hn::Sub(val[1], val[0]), v2 = hn::Sub(val[2], val[0]);
    p.a = hn::Mul(hn::Sub(hn::Mul(v1, y2), hn::Mul(v2, y1)), inv);
    p.b = hn::Mul(hn::Sub(hn::Mul(x1, v2), hn::Mul(x2, v1)), inv);
    p.c = hn::Sub(hn::Sub(val[0], hn::Mul(p.a, x[0])), hn::Mul(p.b, y[0]));
  };
  through(g.num, g.depthNum);
  through(g.den, g.depthDen);
}

// Step 6: the reasons a live lane draws nothing, counted as setupTriangle counts them (the
// first that applies; degenerate and culled by Facing), without a branch per lane. Returns the
// survivors.
HWY_INLINE M CountDropped(const LaneGroup& g, FrontEndCounters& counters) {
  const D d;
  const M empty = hn::AndNot(hn::Gt(g.coverage, hn::Zero(d)), g.small);
  counters.culledFrustum += hn::CountTrue(d, hn::And(g.live, hn::And(g.noBox, g.offScreen)));
  counters.empty += hn::CountTrue(d, hn::And(g.live, empty));  // (empty excludes noBox)
  return hn::AndNot(hn::Or(g.noBox, empty), g.live);
}

// Step 7: the fields records are written from, stored lane by lane (one store per field: a
// braced list of the vectors would be copied whole first). The AVX2 and AVX-512 records are
// built from the vectors, so they need the box and nearest bound only (for DeferredFace and
// `nearest`).
HWY_INLINE void StoreLanes(const LaneGroup& g, V nearest, LaneArrays& lane) {
  const D d;
  hn::Store(g.x0, d, lane.v[kLaneMinX]), hn::Store(g.x1, d, lane.v[kLaneMaxX]);
  hn::Store(g.y0, d, lane.v[kLaneMinY]), hn::Store(g.y1, d, lane.v[kLaneMaxY]);
  hn::Store(nearest, d, lane.v[kLaneNearest]);
#if !(HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2)
  for (int k = 0; k < 3; ++k) {
    hn::Store(g.X[k], d, lane.v[kLaneX + k]);
    hn::Store(g.Y[k], d, lane.v[kLaneY + k]);
  }
  hn::Store(g.depthNum.a, d, lane.v[kLaneDepthNum]), hn::Store(g.depthNum.b, d, lane.v[kLaneDepthNum + 1]);
  hn::Store(g.depthNum.c, d, lane.v[kLaneDepthNum + 2]);
  hn::Store(g.depthDen.a, d, lane.v[kLaneDepthDen]), hn::Store(g.depthDen.b, d, lane.v[kLaneDepthDen + 1]);
  hn::Store(g.depthDen.c, d, lane.v[kLaneDepthDen + 2]);
  hn::Store(hn::VecFromMask(d, g.front), d, lane.v[kLaneFront]);
  hn::Store(g.coverage, d, lane.v[kLaneCoverage]);
#endif
}

// Step 8: with a list of deferred faces, the back faces among the survivors whose box lies in
// one kDeferTile square go there (in order); returns which lanes they were.
HWY_INLINE M WriteDeferred(const LaneGroup& g, M survivors, const LaneArrays& lane, const BatchInput& in,
                           BatchSink& sink) {
  const D d;
  M defer = hn::FirstN(d, 0);
  if (sink.deferred) {
    const V tile = hn::Set(d, 1.0 / kDeferTile);
    auto sameTile = [&](V a, V b) { return hn::Eq(hn::Floor(hn::Mul(a, tile)), hn::Floor(hn::Mul(b, tile))); };
    defer = hn::AndNot(g.front, hn::And(survivors, hn::And(sameTile(g.x0, g.x1), sameTile(g.y0, g.y1))));
  }
  uint8_t deferBits[8] = {};
  hn::StoreMaskBits(d, defer, deferBits);
  for (unsigned bits = deferBits[0]; bits; bits &= bits - 1) {
    const size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(bits);
    DeferredFace& f = sink.deferred[sink.deferredWritten++];
    for (int k = 0; k < 3; ++k) f.v[k] = in.vertex[k][g.first + j];
    f.triangle = in.triIndex[g.first + j];
    f.face = in.face[g.first + j];
    f.minX = int16_t(lane.v[kLaneMinX][j]);
    f.maxX = int16_t(lane.v[kLaneMaxX][j]);
    f.minY = int16_t(lane.v[kLaneMinY][j]);
    f.maxY = int16_t(lane.v[kLaneMaxY][j]);
    f.nearest = lane.v[kLaneNearest][j];
  }
  return defer;
}

// The record's 12 eight-byte words, as the AVX2 and AVX-512 paths below build them.
static_assert(offsetof(SetupTriangle, minX) == 24 && offsetof(SetupTriangle, depthNum) == 32 &&
              offsetof(SetupTriangle, depthDen) == 56 && offsetof(SetupTriangle, triangle) == 80 &&
              offsetof(SetupTriangle, face) == 84 && offsetof(SetupTriangle, frontFacing) == 88 &&
              offsetof(SetupTriangle, coverage) == 90 && offsetof(SetupTriangle, color) == 92,
              "the words below are the record's layout");

// Step 9: a SetupTriangle for each lane of `survivorBits` (its colour is the caller's), in
// order, at sink.out[sink.written], and its bound at sink.nearest[sink.written]. Three ways to
// the same bytes, by instruction set.
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
// 8 lanes (AVX-512): each record's 12 eight-byte words built a vector per word (lane j:
// triangle j's), the vectors transposed, and each survivor's record stored with two stores
// (instead of 24 fields read from the lane arrays and written one by one per record).
HWY_INLINE void WriteRecords(const LaneGroup& g, unsigned survivorBits, const LaneArrays& lane, const BatchInput& in,
                             BatchSink& sink) {
  const D d;
  const size_t N = hn::Lanes(d);
  const hn::Repartition<int64_t, D> di;
  const hn::Repartition<uint64_t, D> du;
  const hn::Rebind<uint32_t, D> du32;
  auto toInt = [&](V v) { return hn::BitCast(du, hn::ConvertTo(di, v)); };
  auto low32 = [&](V v) { return hn::And(toInt(v), hn::Set(du, 0xFFFFFFFFull)); };
  auto low16 = [&](V v) { return hn::And(toInt(v), hn::Set(du, 0xFFFFull)); };
  const auto q0 = hn::Or(low32(g.X[0]), hn::ShiftLeft<32>(toInt(g.X[1])));
  const auto q1 = hn::Or(low32(g.X[2]), hn::ShiftLeft<32>(toInt(g.Y[0])));
  const auto q2 = hn::Or(low32(g.Y[1]), hn::ShiftLeft<32>(toInt(g.Y[2])));
  const auto q3 = hn::Or(hn::Or(low16(g.x0), hn::ShiftLeft<16>(low16(g.y0))),
                         hn::Or(hn::ShiftLeft<32>(low16(g.x1)), hn::ShiftLeft<48>(toInt(g.y1))));
  HWY_ALIGN uint32_t tri8[kSetupBatch], face8[kSetupBatch];  // (the lists end with the batch)
  hn::Vec<decltype(du32)> tris, faces;
  if (g.lanes == N) {
    tris = hn::LoadU(du32, in.triIndex + g.first), faces = hn::LoadU(du32, in.face + g.first);
  } else {
    for (size_t j = 0; j < N; ++j) {
      tri8[j] = in.triIndex[g.first + std::min(j, g.lanes - 1)];
      face8[j] = in.face[g.first + std::min(j, g.lanes - 1)];
    }
    tris = hn::Load(du32, tri8), faces = hn::Load(du32, face8);
  }
  const auto ids = hn::Or(hn::PromoteTo(du, tris), hn::ShiftLeft<32>(hn::PromoteTo(du, faces)));
  // frontFacing (byte 88: 1 or 0), a zero byte, coverage (bytes 90-91), colour (92-95: set by the caller)
  const auto flags = hn::Or(hn::IfThenElseZero(hn::RebindMask(du, g.front), hn::Set(du, 1)),
                            hn::ShiftLeft<16>(toInt(g.coverage)));
  __m512i r[8] = {q0.raw, q1.raw, q2.raw, q3.raw, hn::BitCast(du, g.depthNum.a).raw, hn::BitCast(du, g.depthNum.b).raw,
                  hn::BitCast(du, g.depthNum.c).raw, hn::BitCast(du, g.depthDen.a).raw};
  // 8x8 transpose of 64-bit words: r[j] becomes words 0-7 of triangle j's record.
  __m512i t[8];
  for (int i = 0; i < 8; i += 2) {
    t[i] = _mm512_unpacklo_epi64(r[i], r[i + 1]);
    t[i + 1] = _mm512_unpackhi_epi64(r[i], r[i + 1]);
  }
  for (int i = 0; i < 8; i += 4)
    for (int k = 0; k < 2; ++k) {
      r[i + k] = _mm512_shuffle_i64x2(t[i + k], t[i + k + 2], 0x88);
      r[i + k + 2] = _mm512_shuffle_i64x2(t[i + k], t[i + k + 2], 0xDD);
    }
  __m512i row[8];
  for (int k = 0; k < 4; ++k) {
    row[k] = _mm512_shuffle_i64x2(r[k], r[k + 4], 0x88);
    row[k + 4] = _mm512_shuffle_i64x2(r[k], r[k + 4], 0xDD);
  }
  // Words 8-11 (db, dc, ids, flags): a 4x8 transpose into halves.
  const __m512i w8 = hn::BitCast(du, g.depthDen.b).raw, w9 = hn::BitCast(du, g.depthDen.c).raw;
  const __m512i a0 = _mm512_unpacklo_epi64(w8, w9), a1 = _mm512_unpackhi_epi64(w8, w9);
  const __m512i b0 = _mm512_unpacklo_epi64(ids.raw, flags.raw), b1 = _mm512_unpackhi_epi64(ids.raw, flags.raw);
  const __m512i lo = _mm512_setr_epi64(0, 1, 8, 9, 2, 3, 10, 11), hi = _mm512_setr_epi64(4, 5, 12, 13, 6, 7, 14, 15);
  __m256i tail[8];
  const __m512i even02 = _mm512_permutex2var_epi64(a0, lo, b0), even46 = _mm512_permutex2var_epi64(a0, hi, b0);
  const __m512i odd13 = _mm512_permutex2var_epi64(a1, lo, b1), odd57 = _mm512_permutex2var_epi64(a1, hi, b1);
  tail[0] = _mm512_castsi512_si256(even02), tail[2] = _mm512_extracti64x4_epi64(even02, 1);
  tail[4] = _mm512_castsi512_si256(even46), tail[6] = _mm512_extracti64x4_epi64(even46, 1);
  tail[1] = _mm512_castsi512_si256(odd13), tail[3] = _mm512_extracti64x4_epi64(odd13, 1);
  tail[5] = _mm512_castsi512_si256(odd57), tail[7] = _mm512_extracti64x4_epi64(odd57, 1);
  for (unsigned bits = survivorBits; bits; bits &= bits - 1) {
    const size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(bits);
    if (sink.nearest) sink.nearest[sink.written] = lane.v[kLaneNearest][j];
    char* at = reinterpret_cast<char*>(sink.out + sink.written++);
    _mm512_storeu_si512(at, row[j]);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(at + 64), tail[j]);
  }
}
#elif HWY_ARCH_X86 && HWY_TARGET == HWY_AVX2
// 4 lanes (AVX2): the same 12 words per record as above, built as three 4x4 transposes of
// 64-bit words (words 0-3, 4-7, 8-11), each survivor's record stored with three 32-byte
// stores (instead of 24 fields read from the lane arrays and written one by one).
HWY_INLINE void WriteRecords(const LaneGroup& g, unsigned survivorBits, const LaneArrays& lane, const BatchInput& in,
                             BatchSink& sink) {
  const D d;
  const size_t N = hn::Lanes(d);
  // (Every value converted is an integer well inside int32: exact. Lane j of a 64-bit word
  // pair (a, b) holds a in its low half.)
  auto pairs = [](__m128i a, __m128i b) {
    return _mm256_set_m128i(_mm_unpackhi_epi32(a, b), _mm_unpacklo_epi32(a, b));
  };
  auto int32 = [](V v) { return _mm256_cvtpd_epi32(v.raw); };
  const __m128i x0 = int32(g.X[0]), x1 = int32(g.X[1]), x2 = int32(g.X[2]);
  const __m128i y0 = int32(g.Y[0]), y1 = int32(g.Y[1]), y2 = int32(g.Y[2]);
  // The box: (minX, minY) and (maxX, maxY) as 16-bit pairs (0 <= each < 2^15 for a survivor).
  const __m128i minXY = _mm_unpacklo_epi16(_mm_packs_epi32(int32(g.x0), int32(g.x0)),
                                           _mm_packs_epi32(int32(g.y0), int32(g.y0)));
  const __m128i maxXY = _mm_unpacklo_epi16(_mm_packs_epi32(int32(g.x1), int32(g.x1)),
                                           _mm_packs_epi32(int32(g.y1), int32(g.y1)));
  __m128i tris, faces;
  if (g.lanes == N) {
    tris = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in.triIndex + g.first));
    faces = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in.face + g.first));
  } else {  // (the lists end with the batch)
    alignas(16) uint32_t tri4[4], face4[4];
    for (size_t j = 0; j < 4; ++j) {
      tri4[j] = in.triIndex[g.first + std::min(j, g.lanes - 1)];
      face4[j] = in.face[g.first + std::min(j, g.lanes - 1)];
    }
    tris = _mm_load_si128(reinterpret_cast<const __m128i*>(tri4));
    faces = _mm_load_si128(reinterpret_cast<const __m128i*>(face4));
  }
  // frontFacing (byte 88: 1 or 0), a zero byte, coverage (bytes 90-91), colour (92-95: set
  // by the caller).
  const __m128i flags32 = _mm_or_si128(int32(hn::IfThenElseZero(g.front, hn::Set(d, 1.0))),
                                       _mm_slli_epi32(int32(g.coverage), 16));
  auto asInt = [](V v) { return _mm256_castpd_si256(v.raw); };
  const __m256i word[12] = {pairs(x0, x1),       pairs(x2, y0),       pairs(y1, y2),
                            pairs(minXY, maxXY), asInt(g.depthNum.a), asInt(g.depthNum.b),
                            asInt(g.depthNum.c), asInt(g.depthDen.a), asInt(g.depthDen.b),
                            asInt(g.depthDen.c), pairs(tris, faces),  _mm256_cvtepu32_epi64(flags32)};
  // Three 4x4 transposes: row[k][j] holds words 4 k to 4 k + 3 of lane j's record.
  __m256i row[3][4];
  for (int k = 0; k < 3; ++k) {
    const __m256i* q = word + 4 * k;
    const __m256i t0 = _mm256_unpacklo_epi64(q[0], q[1]), t1 = _mm256_unpackhi_epi64(q[0], q[1]);
    const __m256i t2 = _mm256_unpacklo_epi64(q[2], q[3]), t3 = _mm256_unpackhi_epi64(q[2], q[3]);
    row[k][0] = _mm256_permute2x128_si256(t0, t2, 0x20);
    row[k][1] = _mm256_permute2x128_si256(t1, t3, 0x20);
    row[k][2] = _mm256_permute2x128_si256(t0, t2, 0x31);
    row[k][3] = _mm256_permute2x128_si256(t1, t3, 0x31);
  }
  for (unsigned bits = survivorBits; bits; bits &= bits - 1) {
    const size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(bits);
    if (sink.nearest) sink.nearest[sink.written] = lane.v[kLaneNearest][j];
    __m256i* at = reinterpret_cast<__m256i*>(sink.out + sink.written++);
    for (int k = 0; k < 3; ++k) _mm256_storeu_si256(at + k, row[k][j]);
  }
}
#else
// Other instruction sets: each survivor's fields read from the lane arrays.
HWY_INLINE void WriteRecords(const LaneGroup& g, unsigned survivorBits, const LaneArrays& lane, const BatchInput& in,
                             BatchSink& sink) {
  for (unsigned bits = survivorBits; bits; bits &= bits - 1) {
    const size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(bits);
    if (sink.nearest) sink.nearest[sink.written] = lane.v[kLaneNearest][j];
    SetupTriangle& t = sink.out[sink.written++];
    for (int k = 0; k < 3; ++k) {
      t.x[k] = int32_t(lane.v[kLaneX + k][j]);
      t.y[k] = int32_t(lane.v[kLaneY + k][j]);
    }
    t.minX = int16_t(lane.v[kLaneMinX][j]);
    t.maxX = int16_t(lane.v[kLaneMaxX][j]);
    t.minY = int16_t(lane.v[kLaneMinY][j]);
    t.maxY = int16_t(lane.v[kLaneMaxY][j]);
    t.depthNum = Plane{lane.v[kLaneDepthNum][j], lane.v[kLaneDepthNum + 1][j], lane.v[kLaneDepthNum + 2][j]};
    t.depthDen = Plane{lane.v[kLaneDepthDen][j], lane.v[kLaneDepthDen + 1][j], lane.v[kLaneDepthDen + 2][j]};
    t.triangle = in.triIndex[g.first + j];
    t.face = in.face[g.first + j];
    t.frontFacing = lane.v[kLaneFront][j] != 0;
    t.coverage = uint16_t(lane.v[kLaneCoverage][j]);
  }
}
#endif

// setupBatch (triangle_setup.hpp) without cullFirst: the triangles of `in`, a vector at a time, each
// through the steps above; a vector whose lanes are all dropped stops early (nothing more to
// compute). With `depth`, also their nearest bounds (and, with sink.deferred, deferred faces).
size_t SetupLanes(const BatchInput& input, const Camera& cam, Cull cull, const DepthSetup* depth,
                  FrontEndCounters& counters, BatchSink& sinkOut) {
  const D d;
  const size_t N = hn::Lanes(d);
  // (Locals, whose fields stay in registers: the record stores below cannot alias them.)
  const BatchInput in = input;
  BatchSink sink = sinkOut;
  if (!depth) sink.nearest = nullptr, sink.deferred = nullptr;  // (a deferred face needs its nearest bound)
  for (size_t first = 0; first < in.count; first += N) {
    LaneGroup g;
    g.first = first;
    g.lanes = std::min(N, in.count - first);
    LoadGroup(in, cull, counters, g);
    if (hn::AllFalse(d, g.live)) continue;  // all culled or degenerate: counted, nothing more to do
    OrderVertices(g);
    PixelBoxOf(cam, g);
    CoverageOf(g);
    DepthPlanesOf(g);
    const M survivors = CountDropped(g, counters);
    if (hn::AllFalse(d, survivors)) continue;
    const V largeBox = hn::Set(d, double(kLargeBoxPixels));
    counters.large +=
        hn::CountTrue(d, hn::And(survivors, hn::And(hn::Ge(g.width, largeBox), hn::Ge(g.height, largeBox))));
    const V nearest = depth ? NearestStored(*depth, g.depthNum, g.depthDen, g.px, g.py) : hn::Zero(d);
    LaneArrays lane;
    StoreLanes(g, nearest, lane);
    const M deferred = WriteDeferred(g, survivors, lane, in, sink);
    uint8_t survivorBits[8] = {};
    hn::StoreMaskBits(d, hn::AndNot(deferred, survivors), survivorBits);
    WriteRecords(g, survivorBits[0], lane, in, sink);
  }
  sinkOut.written = sink.written, sinkOut.deferredWritten = sink.deferredWritten;
  return sink.written;
}

// The facing test of `in`'s triangles [from, end), a vector at a time (counting those it drops),
// and the triangles it keeps copied to `kept` (kept.count of them, from 0).
template <size_t kPart>
struct KeptLists {
  uint32_t vertex[3][kPart], triangle[kPart], face[kPart];
  const uint32_t* lists[3] = {vertex[0], vertex[1], vertex[2]};
  size_t count = 0;
};
template <size_t kPart>
HWY_INLINE void KeepFacing(const BatchInput& in, size_t from, size_t end, Cull cull, FrontEndCounters& counters,
                           KeptLists<kPart>& kept) {
  const D d;
  const size_t N = hn::Lanes(d);
  kept.count = 0;
  for (size_t first = from; first < end; first += N) {
    const size_t lanes = std::min(N, end - first);
    V sx[3], sy[3], X[3], Y[3], num[3], den[3];
    LoadVertices(in.projected, in.vertex, first, lanes, sx, sy, num, den);
    M front, live;
    Facing(sx, sy, cull, lanes, counters, X, Y, front, live);
    uint8_t keepBits[8] = {};
    hn::StoreMaskBits(d, live, keepBits);
    for (unsigned bits = keepBits[0]; bits; bits &= bits - 1) {
      const size_t j = first + hwy::Num0BitsBelowLS1Bit_Nonzero32(bits);
      for (int k = 0; k < 3; ++k) kept.vertex[k][kept.count] = in.vertex[k][j];
      kept.triangle[kept.count] = in.triIndex[j];
      kept.face[kept.count++] = in.face[j];
    }
  }
}

// Set-up of `count` triangles (see setupBatch in triangle_setup.hpp). With cullFirst (and a cull),
// the facing test goes first, a vector of triangles at a time, and the triangles it keeps are
// compacted and set up together: a culled triangle then costs its vertex loads and area only,
// a kept one those twice.
size_t SetupBatch(const ProjectedVertex* projected, const uint32_t* const* vertex, const uint32_t* triIndex,
                  const uint32_t* face, size_t count, const Camera& cam, Cull cull, FrontEndCounters& counters,
                  SetupTriangle* out, const SetupBatchOptions& options) {
  const BatchInput in{projected, vertex, triIndex, face, count};
  BatchSink sink{out, options.nearest, options.deferred};
  if (cull == Cull::None || !options.cullFirst) {
    SetupLanes(in, cam, cull, options.depth, counters, sink);
  } else {
    constexpr size_t kPart = 64;
    KeptLists<kPart> kept;
    for (size_t from = 0; from < count; from += kPart) {
      KeepFacing(in, from, std::min(count, from + kPart), cull, counters, kept);
      // The kept triangles' set-up, written after the earlier parts' (faces are deferred only
      // without a cull, but that is not assumed here).
      const BatchInput part{projected, kept.lists, kept.triangle, kept.face, kept.count};
      BatchSink rest{sink.out + sink.written, sink.nearest ? sink.nearest + sink.written : nullptr,
                     sink.deferred ? sink.deferred + sink.deferredWritten : nullptr};
      SetupLanes(part, cam, cull, options.depth, counters, rest);
      sink.written += rest.written, sink.deferredWritten += rest.deferredWritten;
    }
  }
  if (options.deferredCount) *options.deferredCount = sink.deferredWritten;
  return sink.written;
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hsr {
HWY_EXPORT(SetupBatch);

size_t setupBatch(const ProjectedVertex* projected, const uint32_t* const* vertex, const uint32_t* triIndex,
                  const uint32_t* face, size_t count, const Camera& cam, Cull cull, FrontEndCounters& counters,
                  SetupTriangle* out, const SetupBatchOptions& options) {
  return HWY_DYNAMIC_DISPATCH(SetupBatch)(projected, vertex, triIndex, face, count, cam, cull, counters, out, options);
}
}  // namespace hsr
#endif

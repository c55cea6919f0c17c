// The SIMD tile kernel of the tiled rasterizer, written once against Highway and compiled per
// instruction set by raster/tiled.cpp (foreach_target; one function exported, dispatched at run
// time). One long file because its steps are force-inlined into one loop per instruction set.
// RasterizeTile() runs the triangles binned to one tile, nearest first (orderTile), through the
// tile's depth and triangle buffers (TileScratch); it runs on whichever worker owns the tile.
//
// One vector holds up to 8 double lanes, one row of an 8x8 block (AVX-512: one vector per row,
// AVX2: two, SSE4: four, scalar: eight). Every lane repeats the reference's arithmetic exactly:
//  - coverage: the integer edge functions of setup/edge.hpp, exact in double (|E| < 2^50); for
//    a triangle with a box of at most 4x4 pixels, set-up's list of the centres those functions
//    cover (SetupTriangle::coverage);
//  - depth: ((a*X + b*Y) + c) for the planes P and Q of setup/fragment_depth.hpp, their
//    quotient (none when Q is 1: MappedPlanes::affine), std::clamp and quantizeDepth<S> — the
//    same IEEE operations in the same order as fragmentStored<S>, which the reference
//    (zbuffer.cpp with halfspace.hpp) calls, never fused (no MulAdd here; tiled.cpp is built
//    with -ffp-contract=off);
//  - depth test: strictly nearer wins, or equal with the lower triangleKey (submitted first),
//    so the visit order does not matter: per pixel the nearest value and, among equals, the
//    first submitted triangle — what the reference leaves drawing in submission order.
// Hence stored values and winners are bit-identical to the scalar reference.
//
// RasterizeTileT reads top-down. Per triangle: rejected by the tile's farthest value, or drawn
// by one of DrawCoverage (set-up's list of covered centres), TryWholeTile (the tile becomes its
// plane), DrawSmall (a box of at most kSmallPixels centres, in scalar code) or DrawBlocks, which
// sets up (SetUpBlocks), classifies every block row of the box (ClassifyRow) and visits the
// blocks left (VisitBlock: TryWholeBlock, ReadyLazyBlock, ReadyColumn, StartBlockRows,
// DrawBlockRows — the inner loop — and UpdateBlockBounds). The steps share a TileCtx (per tile)
// and a TriangleCtx (per triangle), and are all force-inlined into the one loop.

// Per-target include guard (Highway's pattern: this file is included once per target).
#if defined(HSR_RASTER_TILE_KERNEL_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef HSR_RASTER_TILE_KERNEL_INL_H_
#undef HSR_RASTER_TILE_KERNEL_INL_H_
#else
#define HSR_RASTER_TILE_KERNEL_INL_H_
#endif

#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "core/depth_map.hpp"
#include "core/stream-inl.h"
#include "raster/tiled.hpp"
#include "setup/edge.hpp"
#include "setup/fragment_depth.hpp"

// For the kernel's lambdas that must not become calls: made calls, their captures would live
// in memory. (Functions use HWY_INLINE, which forces inlining the same way.)
#ifndef HSR_ALWAYS_INLINE
#define HSR_ALWAYS_INLINE __attribute__((always_inline))
#endif

HWY_BEFORE_NAMESPACE();
namespace hsr::tiled {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// double -> float lane by lane as the C++ cast rounds it (IEEE). Highway's emulated targets
// saturate infinities to the float range when they narrow; eye depth is +inf where nothing was
// drawn, so those targets convert lane by lane instead.
template <class DF, class VD>
HWY_INLINE hn::Vec<DF> NarrowToFloat(DF df, VD v) {
#if HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR
  const hn::Rebind<double, DF> dd;  // as many lanes as df
  constexpr size_t kLanes = HWY_MAX_BYTES / sizeof(double);
  HWY_ALIGN double wide[kLanes];
  HWY_ALIGN float narrow[kLanes];
  hn::Store(v, dd, wide);
  for (size_t i = 0; i < hn::Lanes(df); ++i) narrow[i] = static_cast<float>(wide[i]);
  return hn::Load(df, narrow);
#else
  return hn::DemoteTo(df, v);
#endif
}

using hsr::stream::HWY_NAMESPACE::StreamCopy;
using hsr::stream::HWY_NAMESPACE::StreamFill;
using hsr::stream::HWY_NAMESPACE::kLineValues;

using D = hn::CappedTag<double, kBlockSize>;  // at most one block row per vector
using V = hn::Vec<D>;
using Mask = hn::Mask<D>;
using DU = hn::RebindToUnsigned<D>;           // triangle ids, same lane count and size

// The tile in blocks: block columns and rows; the vectors of a block's row (one on AVX-512) and
// of a row of block columns (lane: block column).
inline constexpr int kBlocksX = kTileSize / kBlockSize;
inline constexpr int kBlockRows = kTileSize / kBlockSize;
inline constexpr size_t kRowVectors = size_t(kBlockSize) / hn::MaxLanes(D());
inline constexpr size_t kColumnVectors = size_t(kBlocksX) / hn::MaxLanes(D());
static_assert(kRowVectors >= 1 && size_t(kBlockSize) % hn::MaxLanes(D()) == 0);
static_assert(kColumnVectors >= 1 && size_t(kBlocksX) % hn::MaxLanes(D()) == 0);

// Whether greater stored values are nearer (the format's compare direction).
constexpr bool GreaterWins(DepthMapping M) { return M == DepthMapping::Reversed || M == DepthMapping::Inv; }

// acc + 1 in the lanes of m (the rows' per-lane counts): one masked add with AVX-512's mask
// registers; elsewhere masks are vectors of all-ones (-1) lanes, and subtracting one is one
// operation instead of an add and a blend. The rows wrote when a lane of rowWrites moved (no
// mask gathered per row).
HWY_INLINE hn::Vec<DU> CountIn(hn::Vec<DU> acc, Mask m) {
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3
  const DU du;
  return hn::IfThenElse(hn::RebindMask(du, m), hn::Add(acc, hn::Set(du, 1)), acc);
#else
  return hn::Sub(acc, hn::BitCast(DU(), hn::VecFromMask(D(), m)));
#endif
}

// Streams up to k lines of the pump's background (BackgroundPump; none without one), refilling
// as it goes.
HWY_INLINE void Pump(BackgroundPump* p, uint32_t k) {
  if (!p || p->done) return;
  const hn::ScalableTag<uint32_t> du32;
  const size_t L = hn::Lanes(du32);
  while (k) {
    if (p->lines == 0 && !p->refill(*p)) {
      p->done = true;
      return;
    }
    const uint32_t n = std::min(k, p->lines);
    const auto v = hn::Set(du32, p->value);
    uint32_t* dst = p->dst;
    for (uint32_t i = 0; i < n; ++i, dst += kLineValues)
      for (size_t j = 0; j < kLineValues; j += L) hn::Stream(v, du32, dst + j);
    p->dst = dst;
    p->lines -= n;
    k -= n;
  }
}
// drainBackground (tiled.hpp).
void DrainPump(BackgroundPump& p) {
  while (!p.done) Pump(&p, 1u << 30);
}

// "a is nearer than b" for the format's compare direction.
template <bool kGreater>
HWY_INLINE Mask Nearer(V a, V b) {
  if constexpr (kGreater) return hn::Gt(a, b);
  else return hn::Lt(a, b);
}

// A triangle whose fragments are at best `nearest` cannot change a cell that holds `stored`:
// nearest is farther (with ids: a fragment equal to the stored value wins when its triangle was
// submitted first, so only a farther one is beaten), or, depth only, not nearer (equal values
// leave the depth as it is).
template <DepthMapping M, bool kIds>
HWY_INLINE bool Beaten(double nearest, double stored) {
  if constexpr (kIds) return storedNearer<M>(stored, nearest);
  else return !storedNearer<M>(nearest, stored);
}

// std::clamp(v, 0, 1) lane by lane (v < 0 ? 0 : 1 < v ? 1 : v, which keeps NaN and -0).
HWY_INLINE V Clamp01(V v) {
  const D d;
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0);
#if HWY_ARCH_X86 && HWY_TARGET != HWY_EMU128 && HWY_TARGET != HWY_SCALAR
  // x86's max(a, b) is a > b ? a : b and min(a, b) a < b ? a : b (the second operand when one
  // is NaN or both are zeros): max(0, v) is v < 0 ? 0 : v, keeping NaN and -0, then min(1, .)
  // is 1 < . ? 1 : . -- the same lanes as the compares below, in two instructions, not four.
  return hn::Min(one, hn::Max(zero, v));
#else
  return hn::IfThenElse(hn::Lt(v, zero), zero, hn::IfThenElse(hn::Lt(one, v), one, v));
#endif
}

// quantizeDepth<S> lane by lane, kept as a double (exact for every storage): float rounding, or
// v * scale + 0.5 truncated (v >= 0, so truncation is floor).
template <DepthStorage S>
HWY_INLINE V Quantize(V v) {
  const D d;
  if constexpr (S == DepthStorage::F32) {
    return hn::PromoteTo(d, hn::DemoteTo(hn::Rebind<float, D>(), v));
  } else {
    return hn::Floor(hn::Add(hn::Mul(v, hn::Set(d, kDepthScale<S>)), hn::Set(d, 0.5)));
  }
}

// Stored values of a triangle's fragments at the pixel centres X (lanes) of the row whose
// centre is Y, exactly as fragmentStored<S> (setup/fragment_depth.hpp) computes them:
// ((a X + b Y) + c) for P and Q, their quotient, clamp and rounding to storage.
template <DepthStorage S>
HWY_INLINE V StoredDepth(const MappedPlanes& m, V X, double Y) {
  const D d;
  const V p = hn::Add(hn::Add(hn::Mul(hn::Set(d, m.p.a), X), hn::Set(d, m.p.b * Y)), hn::Set(d, m.p.c));
  if (m.affine) return Quantize<S>(Clamp01(p));  // q = 1: p / q is p
  const V q = hn::Add(hn::Add(hn::Mul(hn::Set(d, m.q.a), X), hn::Set(d, m.q.b * Y)), hn::Set(d, m.q.c));
  return Quantize<S>(Clamp01(hn::Div(p, q)));
}

// StoredDepth with a X of both planes given (pX = m.p.a X, qX = m.q.a X, as StoredDepth computes
// them) and P's b Y broadcast (pY): the same bits. kUnclamped: m is affine and every p lies
// strictly within (0, 1), so the clamp, the identity there, is left out.
template <DepthStorage S, bool kUnclamped = false>
HWY_INLINE V StoredDepthAt(const MappedPlanes& m, V pX, V pY, V qX, double Y) {
  const D d;
  const V p = hn::Add(hn::Add(pX, pY), hn::Set(d, m.p.c));
  if constexpr (kUnclamped) return Quantize<S>(p);
  if (m.affine) return Quantize<S>(Clamp01(p));  // q = 1: p / q is p
  const V q = hn::Add(hn::Add(qX, hn::Set(d, m.q.b * Y)), hn::Set(d, m.q.c));
  return Quantize<S>(Clamp01(hn::Div(p, q)));
}

// The farther / nearer of two vectors of stored values, lane by lane.
template <bool kGreater>
HWY_INLINE V Farther(V a, V b) {
  return kGreater ? hn::Min(a, b) : hn::Max(a, b);
}
template <bool kGreater>
HWY_INLINE V NearerOf(V a, V b) {
  return kGreater ? hn::Max(a, b) : hn::Min(a, b);
}
template <bool kGreater>
HWY_INLINE double FarthestLane(V v) {
  const D d;
  return hn::GetLane(kGreater ? hn::MinOfLanes(d, v) : hn::MaxOfLanes(d, v));
}
template <bool kGreater>
HWY_INLINE double NearestLane(V v) {
  const D d;
  return hn::GetLane(kGreater ? hn::MaxOfLanes(d, v) : hn::MinOfLanes(d, v));
}

// storedRangeOverRect (setup/fragment_depth.hpp) for an affine m (q = 1) lane by lane, over the
// rectangles [left, right] (lanes) x [top, bottom], with the same operations: the same bits.
// Given a X at the columns where p is least and most (aXLow, aXHigh: a left or a right).
// For planes whose error pErr (planeError, over the tile) is below 1e280 only: then |a| x + |b| y
// + |c| is below 1e280 / 2^-49 < 2^1000 at every point of the tile, so p's bounds are finite
// (storedRangeOverRect's "none" cannot occur; q = 1 is bounded, 1 -+ its error).
struct StoredRangeV {
  V nearest, farthest;
};
template <DepthStorage S, DepthMapping M>
HWY_INLINE StoredRangeV RectRange(const MappedPlanes& m, double pErr, V aXLow, V aXHigh, double top, double bottom) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const Plane& p = m.p;
  const V c = hn::Set(d, p.c), err = hn::Set(d, pErr);
  const V pMin = hn::Sub(hn::Add(hn::Add(aXLow, hn::Set(d, p.b * (p.b >= 0 ? top : bottom))), c), err);
  const V pMax = hn::Add(hn::Add(hn::Add(aXHigh, hn::Set(d, p.b * (p.b >= 0 ? bottom : top))), c), err);
  const V margin = hn::Set(d, 1e-12);
  const V low = Quantize<S>(Clamp01(hn::Sub(pMin, hn::Mul(hn::Abs(pMin), margin))));
  const V high = Quantize<S>(Clamp01(hn::Add(pMax, hn::Mul(hn::Abs(pMax), margin))));
  return kGreater ? StoredRangeV{high, low} : StoredRangeV{low, high};
}

// The tile's part of the image: origin and size.
struct TileRect {
  int x0, y0, w, h;
};
HWY_INLINE TileRect RectOf(const TileJob& job) {
  const Bins& bins = *job.bins;
  const int x0 = (job.tile % bins.tilesX) * kTileSize, y0 = (job.tile / bins.tilesX) * kTileSize;
  return {x0, y0, std::min(kTileSize, bins.width - x0), std::min(kTileSize, bins.height - y0)};
}

// Eye depths at the pixel centres X (lanes) from a triangle's planes broadcast: a, b Y and c of
// the numerator's and the denominator's plane (Y the row's centre), with the operations of
// SetupTriangle::eyeDepth (as the reference resolves them).
struct EyePlanesV {
  V numA, numBY, numC, denA, denBY, denC;
};
HWY_INLINE V EyeDepthAt(const EyePlanesV& e, V X) {
  return hn::Div(hn::Add(hn::Add(hn::Mul(e.numA, X), e.numBY), e.numC),
                 hn::Add(hn::Add(hn::Mul(e.denA, X), e.denBY), e.denC));
}
// The same for triangle t in the row whose centre is Y.
HWY_INLINE V EyeDepthRow(const SetupTriangle& t, V X, double Y) {
  const D d;
  return EyeDepthAt({hn::Set(d, t.depthNum.a), hn::Set(d, t.depthNum.b * Y), hn::Set(d, t.depthNum.c),
                     hn::Set(d, t.depthDen.a), hn::Set(d, t.depthDen.b * Y), hn::Set(d, t.depthDen.c)},
                    X);
}

// The tile's part of the image and the constants of its depth format.
struct TileFrame : TileRect {
  double clear;           // the format's clear value, as stored
  double nearestPossible; // stored in cells outside the image: never drawn, never the farthest
  double farthestPossible;
  double storedOne;       // the stored value of mapped depth 1 (that of 0 is 0)
  // Whether block b lies wholly in the image (its cells all drawable).
  bool blockInImage(int b) const {
    return (b % kBlocksX + 1) * kBlockSize <= w && (b / kBlocksX + 1) * kBlockSize <= h;
  }
};

template <DepthStorage S, DepthMapping M>
TileFrame MakeTileFrame(const TileJob& job) {
  constexpr bool kGreater = GreaterWins(M);
  TileFrame f;
  static_cast<TileRect&>(f) = RectOf(job);
  f.clear = double(quantizeDepth<S>(job.depth.format.clearValue()));
  constexpr double inf = std::numeric_limits<double>::infinity();
  f.nearestPossible = kGreater ? inf : -inf;
  f.farthestPossible = kGreater ? -inf : inf;
  f.storedOne = double(quantizeDepth<S>(1.0));
  return f;
}

// Writes block b's cells: inside the image, the plane m's values when `plane` (else `value`),
// with triangle key `key`; outside, the never-drawn value and key 0. Returns the farthest value
// written and the nearest in-image one in `far` and `near`. The plane's values are computed as
// the kernel computes every fragment, so they are the bits drawing the triangle would store.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void FillBlock(TileScratch& s, const TileFrame& f, int b, bool plane, const MappedPlanes& m, double value,
                          uint64_t key, double& farOut, double& nearOut) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const DU du;
  const size_t N = hn::Lanes(d);
  const V valueV = hn::Set(d, value), outside = hn::Set(d, f.nearestPossible), widthV = hn::Set(d, double(f.w));
  const V farthestV = hn::Set(d, f.farthestPossible);
  const auto keyV = hn::Set(du, key), zeroKey = hn::Zero(du);
  const int bx = (b % kBlocksX) * kBlockSize, by = (b / kBlocksX) * kBlockSize;
  if (!plane && f.blockInImage(b)) {  // one value, all in the image
    for (int y = by; y < by + kBlockSize; ++y)
      for (size_t k = 0; k < size_t(kBlockSize); k += N) {
        const size_t at = size_t(y) * kTileSize + size_t(bx) + k;
        hn::Store(valueV, d, s.depth + at);
        if constexpr (kIds) hn::Store(keyV, du, s.triangle + at);
      }
    farOut = nearOut = value;
    return;
  }
  V far = outside, near = farthestV;
  for (int y = by; y < by + kBlockSize; ++y)
    for (size_t k = 0; k < size_t(kBlockSize); k += N) {
      const size_t at = size_t(y) * kTileSize + size_t(bx) + k;
      const V col = hn::Iota(d, double(bx + int(k)));
      Mask in = hn::Lt(col, widthV);
      if (y >= f.h) in = hn::FirstN(d, 0);
      V v = outside;
      if (!hn::AllFalse(d, in)) {
        const V drawn =
            plane ? StoredDepth<S>(m, hn::Add(col, hn::Set(d, double(f.x0) + 0.5)), double(f.y0 + y) + 0.5) : valueV;
        v = hn::IfThenElse(in, drawn, outside);
      }
      hn::Store(v, d, s.depth + at);
      if constexpr (kIds) hn::Store(hn::IfThenElse(hn::RebindMask(du, in), keyV, zeroKey), du, s.triangle + at);
      far = Farther<kGreater>(far, v);
      near = NearerOf<kGreater>(near, hn::IfThenElse(in, v, farthestV));
    }
  farOut = FarthestLane<kGreater>(far);
  nearOut = NearestLane<kGreater>(near);
}

// Turns the tile's uniform state (cleared, or one triangle's plane over all of it) into state
// Pixels, with the bounds of each block, so that triangles can be drawn pixel by pixel from here
// on: the blocks wholly in the image keep the state, one per block (blockClear, or the plane as
// blockKey), written only when a triangle lands on them (MaterializeBlock); the others are
// written. (Faster for planes than writing every block at once: see docs/benchmarks.md.)
template <DepthStorage S, DepthMapping M, bool kIds>
void Materialize(const TileJob& job, const TileFrame& f) {
  constexpr bool kGreater = GreaterWins(M);
  TileScratch& s = *job.scratch;
  const bool plane = s.state == TileState::Plane;
  const MappedPlanes m = plane ? mapPlanes<M>(s.plane->depthNum, s.plane->depthDen, job.depth.near, job.depth.far,
                                              job.depth.orthographic)
                               : MappedPlanes{};
  const double pErr = planeError(m.p, f.x0 + f.w, f.y0 + f.h), qErr = planeError(m.q, f.x0 + f.w, f.y0 + f.h);
  double tileFar = f.nearestPossible;
  for (int b = 0; b < kBlocksPerTile; ++b) {
    const int bx = (b % kBlocksX) * kBlockSize, by = (b / kBlocksX) * kBlockSize;
    s.blockClear[b] = false;
    if (!plane && f.blockInImage(b)) {
      s.blockKey[b] = 0;
      s.blockClear[b] = true;
      s.blockFar[b] = s.blockNear[b] = f.clear;
    } else if (plane && f.blockInImage(b)) {
      // A block wholly in the image keeps the plane as its uniform state (written only when a
      // triangle lands on it: MaterializeBlock), with the plane's bounds over its corners.
      const StoredRange r = storedRangeOverRect<S, M>(m, pErr, qErr, f.x0 + bx + 0.5, f.x0 + bx + kBlockSize - 0.5,
                                                      f.y0 + by + 0.5, f.y0 + by + kBlockSize - 0.5);
      s.blockKey[b] = s.planeKey;
      s.blockTriangle[b] = s.plane;
      s.blockFar[b] = r.farthest;
      s.blockNear[b] = r.nearest;
    } else {
      FillBlock<S, M, kIds>(s, f, b, plane, m, f.clear, plane ? s.planeKey : 0, s.blockFar[b], s.blockNear[b]);
      s.blockKey[b] = 0;
    }
    if (kGreater ? s.blockFar[b] < tileFar : s.blockFar[b] > tileFar) tileFar = s.blockFar[b];
  }
  s.tileFar = tileFar;
  s.tileFarStale = false;
  s.state = TileState::Pixels;
}

// Whether block b (state Pixels) is in a uniform state whose buffers are stale: blockKey or
// blockClear, which MaterializeBlock writes out.
HWY_INLINE bool Lazy(const TileScratch& s, int b) { return s.blockKey[b] != 0 || s.blockClear[b]; }

// Writes block b, wholly in the image, with the plane m's values and triangle key `key`: the
// cells FillBlock writes there (the same operations: StoredDepthAt with a X per column as
// StoredDepth computes it), without the masks and the bounds it gathers.
template <DepthStorage S, bool kIds>
HWY_INLINE void FillPlaneBlock(TileScratch& s, const TileFrame& f, int b, const MappedPlanes& m, uint64_t key) {
  constexpr size_t kVectors = size_t(kBlockSize) / hn::MaxLanes(D());
  const D d;
  const DU du;
  const size_t N = hn::Lanes(d);
  const int bx = (b % kBlocksX) * kBlockSize, by = (b / kBlocksX) * kBlockSize;
  V pX[kVectors], qX[kVectors];
  for (size_t k = 0; k < size_t(kBlockSize); k += N) {
    const V X = hn::Add(hn::Iota(d, double(bx + int(k))), hn::Set(d, double(f.x0) + 0.5));
    pX[k / N] = hn::Mul(hn::Set(d, m.p.a), X);
    qX[k / N] = hn::Mul(hn::Set(d, m.q.a), X);
  }
  const auto keyV = hn::Set(du, key);
  for (int y = by; y < by + kBlockSize; ++y) {
    const double Y = double(f.y0 + y) + 0.5;
    const V pY = hn::Set(d, m.p.b * Y);
    for (size_t k = 0; k < size_t(kBlockSize); k += N) {
      const size_t at = size_t(y) * kTileSize + size_t(bx) + k;
      hn::Store(StoredDepthAt<S>(m, pX[k / N], pY, qX[k / N], Y), d, s.depth + at);
      if constexpr (kIds) hn::Store(keyV, du, s.triangle + at);
    }
  }
}

// Writes block b's uniform state (state Pixels, Lazy(s, b)) — its plane or the clear value —
// into the pixel buffers, as Materialize does for a tile; its bounds stay as they are (still
// valid). The plane is mapped with the kernel's reciprocal cache (the same bits as without),
// and a block in the image is written by FillPlaneBlock, without FillBlock's masks and bounds:
// this runs often enough for both to count.
template <DepthStorage S, DepthMapping M, bool kIds>
void MaterializeBlock(const TileJob& job, const TileFrame& f, int b, ReciprocalCache& reciprocal) {
  TileScratch& s = *job.scratch;
  double far, near;
  if (s.blockClear[b]) {
    FillBlock<S, M, kIds>(s, f, b, false, MappedPlanes{}, f.clear, 0, far, near);
  } else {
    const MappedPlanes m = mapPlanes<M>(s.blockTriangle[b]->depthNum, s.blockTriangle[b]->depthDen, job.depth.near,
                                        job.depth.far, job.depth.orthographic, reciprocal);
    if (f.blockInImage(b)) FillPlaneBlock<S, kIds>(s, f, b, m, s.blockKey[b]);
    else FillBlock<S, M, kIds>(s, f, b, true, m, 0.0, s.blockKey[b], far, near);
  }
  s.blockKey[b] = 0;
  s.blockClear[b] = false;
}

// Triangles whose box in the tile has at most this many pixel centres take the scalar path.
inline constexpr int kSmallPixels = 16;

// The pixel centres at the corners of the tile's part of the image, fixed point (for the edge
// functions) and in pixels (for the plane's bounds): the whole-tile test's.
struct TileCorners {
  int64_t x[2], y[2];
  double rectX[4], rectY[4];
};

// One tile's pass through its triangles (RasterizeTileT): the tile's constants and the state its
// steps share. A local of RasterizeTileT handed by reference to force-inlined steps only, so its
// members stay in registers as plain locals would; what has to live in memory is referenced.
template <DepthStorage S, DepthMapping M, bool kIds>
struct TileCtx {
  const TileJob& job;
  TileScratch& s;
  const Bins& bins;
  const TileFrame& tf;
  const TileCorners& corners;
  ReciprocalCache& reciprocal;  // mapPlanes' division, once for the tile's triangles that share it
  RasterCounters& count;        // added to the job's at the end
  int x0, y0, w, h;             // tf's
  V nearestV, farthestV, clearV;  // tf's values broadcast
  V lane;                         // lane j: j
  uint64_t tests = 0, writes = 0;  // the hottest counts, kept apart from `count` (in registers)
  // The blocks of the classified triangles' boxes, and those of them culled in classification.
  uint64_t blocksInBoxes = 0, blocksCulledHere = 0;
  // The block rows' counts, per lane (summed at the end): CountIn per row instead of popcounts.
  hn::Vec<DU> rowTests, rowWrites;
  // Blocks written by the small-triangle path since their farthest values were computed (those
  // values stay valid bounds meanwhile: writes only bring stored values nearer), and the
  // triangles met since.
  uint64_t dirtyBlocks = 0;
  unsigned sinceRefresh = 0;
};

// One triangle of the tile past the tile's bound: its record, mapped planes, key (triangleKey)
// and nearest possible stored value.
struct TriangleCtx {
  const SetupTriangle& t;
  const MappedPlanes& m;
  uint64_t key;
  double qNear;
};

// The farthest values of the blocks the small-triangle path wrote (dirtyBlocks), read again;
// the tile's farthest value is then stale.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void RefreshDirty(TileCtx<S, M, kIds>& c) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const size_t N = hn::Lanes(d);
  for (uint64_t bits = c.dirtyBlocks; bits; bits &= bits - 1) {
    const int b = hwy::Num0BitsBelowLS1Bit_Nonzero64(bits);
    const size_t first = size_t(b / kBlocksX) * kBlockSize * kTileSize + size_t(b % kBlocksX) * kBlockSize;
    V far = c.nearestV;
    for (int y = 0; y < kBlockSize; ++y)
      for (size_t k = 0; k < size_t(kBlockSize); k += N)
        far = Farther<kGreater>(far, hn::Load(d, c.s.depth + first + size_t(y) * kTileSize + k));
    c.s.blockFar[b] = FarthestLane<kGreater>(far);
  }
  c.dirtyBlocks = 0;
  c.s.tileFarStale = true;
}

// The tile's farthest value: the farthest of its blocks'.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void RefreshTileFar(TileCtx<S, M, kIds>& c) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const size_t N = hn::Lanes(d);
  V far = c.nearestV;
  for (size_t b = 0; b < size_t(kBlocksPerTile); b += N) far = Farther<kGreater>(far, hn::Load(d, c.s.blockFar + b));
  c.s.tileFar = FarthestLane<kGreater>(far);
  c.s.tileFarStale = false;
}

// Fetches the record of the triangle kAhead places on, unless the tile's bound rejects it
// already (nearest first, most hidden ones are rejected unread): the records are scattered over
// the chunks. (12 rather than 6, since small triangles' records carry their coverage list: see
// docs/benchmarks.md.)
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void PrefetchAhead(const TileCtx<S, M, kIds>& c, const std::vector<TileEntry>& order, size_t item,
                              size_t end) {
  constexpr size_t kAhead = 12;
  if (item + kAhead < end && !Beaten<M, kIds>(order[item + kAhead].nearest, c.s.tileFar)) {
    const SetupTriangle* ahead = &c.bins.triangle(order[item + kAhead].key);
    hwy::Prefetch(ahead);
    hwy::Prefetch(reinterpret_cast<const char*>(ahead) + 64);
  }
}

// Turns the tile to state Pixels (Materialize) unless it is there already: from then on its
// triangles are drawn into the pixel buffers, with bounds per block.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void EnsurePixels(TileCtx<S, M, kIds>& c) {
  if (c.s.state != TileState::Pixels) {
    Materialize<S, M, kIds>(c.job, c.tf);
    c.dirtyBlocks = 0;
  }
}

// ---- Small triangles: pixel by pixel, in scalar code ----

// The fragment at tile-local pixel (x, y) (pRow = m.p.b * Y, qRow = m.q.b * Y for its row's
// centre Y), with the same operations as the lanes of DrawBlockRows: tested and, when it wins,
// stored, with its block's and the tile's nearest values moved.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawPixel(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, int x, int y, double pRow, double qRow) {
  constexpr bool kGreater = GreaterWins(M);
  TileScratch& s = c.s;
  const size_t at = size_t(y) * kTileSize + size_t(x);
  const double stored = s.depth[at];
  if (Beaten<M, kIds>(tri.qNear, stored)) return;
  const double z = fragmentStored<S>(tri.m, double(x) + (double(c.x0) + 0.5), pRow, qRow);
  ++c.tests;
  if (storedNearer<M>(z, stored) || (kIds && z == stored && tri.key < s.triangle[at])) {
    ++c.writes;
    s.depth[at] = z;
    if constexpr (kIds) s.triangle[at] = tri.key;
    const int b = (y / kBlockSize) * kBlocksX + x / kBlockSize;
    c.dirtyBlocks |= uint64_t(1) << b;
    // The nearer value without a branch (a data-dependent branch per bound was slower).
    s.blockNear[b] = kGreater ? std::max(z, s.blockNear[b]) : std::min(z, s.blockNear[b]);
    s.tileNear = kGreater ? std::max(z, s.tileNear) : std::min(z, s.tileNear);
  }
}

// A small triangle's box in the tile (tile-local, inclusive): whether it is behind everything
// stored in the blocks the box touches (their farthest values may be stale, still bounds); if
// not, those blocks are made ready to be drawn pixel by pixel. Turns the tile to state Pixels
// first (the blocks' bounds are kept there).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE bool SmallBeaten(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, int bx0, int bx1, int by0, int by1) {
  EnsurePixels(c);
  TileScratch& s = c.s;
  const double qNear = tri.qNear;
  const int first = (by0 / kBlockSize) * kBlocksX + bx0 / kBlockSize;
  const int across = bx1 / kBlockSize - bx0 / kBlockSize, down = by1 / kBlockSize - by0 / kBlockSize;
  if (across <= 1 && down <= 1) {  // (mostly) 1 to 4 blocks: their corners, repeated when fewer
    const int b[4] = {first, first + across, first + down * kBlocksX, first + down * kBlocksX + across};
    if (Beaten<M, kIds>(qNear, s.blockFar[b[0]]) & Beaten<M, kIds>(qNear, s.blockFar[b[1]]) &
        Beaten<M, kIds>(qNear, s.blockFar[b[2]]) & Beaten<M, kIds>(qNear, s.blockFar[b[3]])) {
      if constexpr (kCountBlocks) ++c.count.blocksCulled;
      return true;
    }
    for (int i = 0; i < 4; ++i)  // (a block repeated is no longer Lazy the second time)
      if (Lazy(s, b[i])) MaterializeBlock<S, M, kIds>(c.job, c.tf, b[i], c.reciprocal);
    return false;
  }
  bool beaten = true;
  for (int by = 0; by <= down; ++by)
    for (int bx = 0; bx <= across; ++bx) beaten &= Beaten<M, kIds>(qNear, s.blockFar[first + by * kBlocksX + bx]);
  if (beaten) {
    if constexpr (kCountBlocks) ++c.count.blocksCulled;
    return true;
  }
  for (int by = 0; by <= down; ++by)
    for (int bx = 0; bx <= across; ++bx)
      if (const int b = first + by * kBlocksX + bx; Lazy(s, b)) MaterializeBlock<S, M, kIds>(c.job, c.tf, b, c.reciprocal);
  return false;
}

// A triangle whose covered centres set-up listed (SetupTriangle::coverage: a box of at most 4x4
// pixels): no edge functions, only its covered pixels in the tile are visited.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawCoverage(TileCtx<S, M, kIds>& c, const TriangleCtx& tri) {
  const SetupTriangle& t = tri.t;
  const int ox = t.minX - c.x0, oy = t.minY - c.y0;  // the box's corner, tile-local (maybe outside)
  const int cx0 = std::max(-ox, 0), cx1 = std::min(c.w - 1 - ox, kCoverageBox - 1);
  const int cy0 = std::max(-oy, 0), cy1 = std::min(c.h - 1 - oy, kCoverageBox - 1);
  const unsigned columns = ((2u << cx1) - 1) & ~((1u << cx0) - 1);
  const unsigned rows = ((1u << (kCoverageBox * (cy1 + 1))) - 1) & ~((1u << (kCoverageBox * cy0)) - 1);
  const unsigned bits = t.coverage & rows & (columns * 0x1111u);
  if (!bits || SmallBeaten(c, tri, ox + cx0, ox + cx1, oy + cy0, oy + cy1)) return;
  for (unsigned left = bits; left; left &= left - 1) {
    const int bit = int(hwy::Num0BitsBelowLS1Bit_Nonzero32(left));
    const int y = oy + bit / kCoverageBox;
    const double Y = double(c.y0 + y) + 0.5;
    DrawPixel(c, tri, ox + bit % kCoverageBox, y, tri.m.p.b * Y, tri.m.q.b * Y);
  }
}

// A triangle's pixel box within the tile, tile-local and inclusive.
struct PixelBox {
  int rx0, rx1, ry0, ry1;
};

// A small triangle without a coverage list (a box of at most kSmallPixels centres in the tile):
// its edge functions stepped pixel by pixel.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawSmall(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const Edge (&e)[3], const PixelBox& box) {
  if (SmallBeaten(c, tri, box.rx0, box.rx1, box.ry0, box.ry1)) return;
  int64_t rowE[3];
  for (int i = 0; i < 3; ++i) rowE[i] = e[i].at(centerFixed(c.x0 + box.rx0), centerFixed(c.y0 + box.ry0));
  for (int y = box.ry0; y <= box.ry1; ++y) {
    const double Y = double(c.y0 + y) + 0.5, pRow = tri.m.p.b * Y, qRow = tri.m.q.b * Y;
    int64_t E[3] = {rowE[0], rowE[1], rowE[2]};
    for (int x = box.rx0; x <= box.rx1; ++x) {
      if (E[0] >= e[0].bias && E[1] >= e[1].bias && E[2] >= e[2].bias) DrawPixel(c, tri, x, y, pRow, qRow);
      for (int i = 0; i < 3; ++i) E[i] += e[i].stepX();
    }
    for (int i = 0; i < 3; ++i) rowE[i] += e[i].stepY();
  }
}

// ---- The whole tile ----

// Whole tile: the triangle covers every pixel centre of the tile (its four corner centres;
// coverage is convex) and its farthest value is nearer than the nearest stored, so it wins
// every pixel and the tile becomes its plane, in O(1) ("lossless z-buffer compression").
// Returns whether it did.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE bool TryWholeTile(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const Edge (&e)[3]) {
  const SetupTriangle& t = tri.t;
  TileScratch& s = c.s;
  if (!(t.minX <= c.x0 && t.maxX >= c.x0 + c.w - 1 && t.minY <= c.y0 && t.maxY >= c.y0 + c.h - 1)) return false;
  bool covers = true;
  for (const Edge& edge : e)
    for (int k = 0; k < 4; ++k) covers &= edge.at(c.corners.x[k & 1], c.corners.y[k >> 1]) >= edge.bias;
  if (!covers) return false;
  const StoredRange r = storedRange<S, M>(tri.m, c.corners.rectX, c.corners.rectY, 4);
  if (!storedNearer<M>(r.farthest, s.tileNear)) return false;
  s.state = TileState::Plane;
  s.plane = &t;
  s.planeKey = tri.key;
  s.tileFar = r.farthest;
  s.tileNear = r.nearest;
  s.tileFarStale = false;
  c.dirtyBlocks = 0;  // the pixel buffers are no longer the tile's values
  c.tests += uint64_t(c.w) * uint64_t(c.h);
  c.writes += uint64_t(c.w) * uint64_t(c.h);
  ++c.count.tilesWhole;
  return true;
}

// ---- Larger triangles: block by block, a vector of lanes at a time ----

// What the block path needs of one triangle, set up once (SetUpBlocks): its box in pixels and
// in blocks; per edge, the lanes' steps, the bias and the row terms; its depth's shortcuts and
// error bounds; and, per vector of block columns, what classification needs that does not
// depend on the block row.
struct BlockSetup : PixelBox {
  const Edge* e;  // the triangle's three edges
  int bxFirst, bxLast, byFirst, byLast;
  V laneE[3], biasV[3], stepYV[3];  // per edge: lane j's j stepX; bias; stepY
  // Per edge, in double (exact: |dx| < 2^24, |ay| < 2^23): dx, dx ay, dx ay + bias.
  double edgeDx[3], edgeDxAy[3], edgeDxAyBias[3];
  V qNearV;
  hn::Vec<DU> idV;
  // A triangle parallel to the image plane has both planes constant (a = b = 0): a*X and b*Y
  // are zeros of a fixed sign, so every pixel computes the same bits as its first one, zConstant.
  bool constantDepth;
  V zConstant;
  double pErr, qErr;  // the planes' evaluation errors over the tile, for the bounds of its blocks
  // An affine mapped depth (q = 1: every perspective z, reversed and inv format) gets its bounds
  // over each block's part of the box in classification, a vector of blocks at a time (the lanes
  // repeat storedRangeOverRect's operations: the same bits).
  bool rectBounds;
  // Per vector of block columns (lane: block column): whether the column meets the box, P's a X
  // at the corners of the columns' parts of the box that bound it, and the edge functions' x
  // terms, dy (X - ax), at the corners that make them largest and smallest.
  V inBoxV[kColumnVectors], pXLow[kColumnVectors], pXHigh[kColumnVectors];
  V xLargest[3][kColumnVectors], xSmallest[3][kColumnVectors];
  uint32_t columnReady;  // bit bx: BlockScratch holds block column bx's vectors (ReadyColumn)
};

// What the visits read by index: each block row's classification (ClassifyRow) and each block
// column's vectors (ReadyColumn).
struct BlockScratch {
  HWY_ALIGN double rectNearest[kBlockRows][kBlocksX], rectFarthest[kBlockRows][kBlocksX];  // rectBounds' bounds
  uint64_t visit[kBlockRows];      // bit bx: the block is drawn
  uint64_t inside[kBlockRows][3];  // bit bx: every centre of the block's part of the box is inside edge i
  double rowEdge[kBlockRows][3];   // per edge: dx (py - ay) at the first row of the blocks' parts of the box
  // Per vector of a block's row: its columns in the box, a X of both planes, the edge functions'
  // x terms (lane j: j stepX - dy (px - ax) at the vector's first pixel px).
  V colIn[kBlocksX][kRowVectors], colPX[kBlocksX][kRowVectors], colQX[kBlocksX][kRowVectors];
  V colEdge[3][kBlocksX][kRowVectors];
};

// BlockSetup's terms per vector of block columns (see there).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void SetUpColumns(const TileCtx<S, M, kIds>& c, const TriangleCtx& tri, BlockSetup& bs) {
  const D d;
  const size_t N = hn::Lanes(d);
  const MappedPlanes& m = tri.m;
  const Edge* e = bs.e;
  for (size_t k = 0; k < size_t(kBlocksX); k += N) {
    const V column = hn::Add(c.lane, hn::Set(d, double(k)));
    const Mask inBox =
        hn::And(hn::Ge(column, hn::Set(d, double(bs.bxFirst))), hn::Le(column, hn::Set(d, double(bs.bxLast))));
    bs.inBoxV[k / N] = hn::VecFromMask(d, inBox);
    if (hn::AllFalse(d, inBox)) continue;
    const V firstColumn = hn::Mul(column, hn::Set(d, double(kBlockSize)));
    const V leftCol = hn::Max(firstColumn, hn::Set(d, double(bs.rx0)));
    const V rightCol = hn::Min(hn::Add(firstColumn, hn::Set(d, double(kBlockSize - 1))), hn::Set(d, double(bs.rx1)));
    if (bs.rectBounds) {
      const V leftPx = hn::Add(leftCol, hn::Set(d, double(c.x0) + 0.5));
      const V rightPx = hn::Add(rightCol, hn::Set(d, double(c.x0) + 0.5));
      bs.pXLow[k / N] = hn::Mul(hn::Set(d, m.p.a), m.p.a >= 0 ? leftPx : rightPx);
      bs.pXHigh[k / N] = hn::Mul(hn::Set(d, m.p.a), m.p.a >= 0 ? rightPx : leftPx);
    }
    const V one = hn::Set(d, double(kSubpixelOne)), half = hn::Set(d, double(kSubpixelOne / 2));
    const V origin = hn::Set(d, double(c.x0));
    const V left = hn::Add(hn::Mul(hn::Add(leftCol, origin), one), half);  // centerFixed, exact
    const V right = hn::Add(hn::Mul(hn::Add(rightCol, origin), one), half);
    for (int i = 0; i < 3; ++i) {
      const V dy = hn::Set(d, double(e[i].dy)), ax = hn::Set(d, double(e[i].ax));
      bs.xLargest[i][k / N] = hn::Mul(dy, hn::Sub(e[i].dy < 0 ? right : left, ax));
      bs.xSmallest[i][k / N] = hn::Mul(dy, hn::Sub(e[i].dy < 0 ? left : right, ax));
    }
  }
}

// Sets up the block path of triangle `tri` over `box` (BlockSetup).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void SetUpBlocks(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const Edge (&e)[3], const PixelBox& box,
                            BlockSetup& bs) {
  const D d;
  const DU du;
  const SetupTriangle& t = tri.t;
  const MappedPlanes& m = tri.m;
  static_cast<PixelBox&>(bs) = box;
  bs.e = e;
  for (int i = 0; i < 3; ++i) {
    bs.laneE[i] = hn::Mul(c.lane, hn::Set(d, double(e[i].stepX())));  // lane j: j * stepX, exact
    bs.biasV[i] = hn::Set(d, double(e[i].bias));
  }
  bs.qNearV = hn::Set(d, tri.qNear);
  bs.idV = hn::Set(du, tri.key);
  bs.constantDepth = t.depthNum.a == 0 && t.depthNum.b == 0 && t.depthDen.a == 0 && t.depthDen.b == 0;
  const double Y0 = c.y0 + box.ry0 + 0.5;
  bs.zConstant = bs.constantDepth ? hn::Set(d, fragmentStored<S>(m, c.x0 + box.rx0 + 0.5, m.p.b * Y0, m.q.b * Y0))
                                  : hn::Zero(d);
  bs.pErr = planeError(m.p, c.x0 + c.w, c.y0 + c.h);
  bs.qErr = planeError(m.q, c.x0 + c.w, c.y0 + c.h);
  bs.bxFirst = box.rx0 / kBlockSize;
  bs.bxLast = box.rx1 / kBlockSize;
  bs.rectBounds = m.affine && bs.pErr < 1e280;
  SetUpColumns(c, tri, bs);
  bs.columnReady = 0;
  for (int i = 0; i < 3; ++i) bs.stepYV[i] = hn::Set(d, double(e[i].stepY()));
  for (int i = 0; i < 3; ++i) {
    bs.edgeDx[i] = double(e[i].dx);
    bs.edgeDxAy[i] = double(e[i].dx * e[i].ay);
    bs.edgeDxAyBias[i] = double(e[i].dx * e[i].ay + e[i].bias);
  }
  if constexpr (kCountBlocks)
    c.blocksInBoxes += uint64_t(bs.bxLast - bs.bxFirst + 1) * uint64_t(box.ry1 / kBlockSize - box.ry0 / kBlockSize + 1);
  bs.byFirst = box.ry0 / kBlockSize;
  bs.byLast = box.ry1 / kBlockSize;
}

// Classifies block row `by` of the box, a vector of blocks at a time (lane: block column): a
// block is skipped when behind everything stored there or outside an edge, and is inside an
// edge when every centre of its part of the box is. Each block's part of the box has four
// corner centres that bound every edge function on it, and an edge function is linear: its
// largest and smallest values are at the corners its slopes point to and away from (E grows
// with x when dy < 0, with y when dx > 0), so two corners decide. Computed in double, exactly:
// E = dx (py - ay) - dy (px - ax) with snapped coordinates below 2^23 in magnitude is below
// 2^49; E < bias is then dx (py - ay) - bias < dy (px - ax), integers as well.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void ClassifyRow(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const BlockSetup& bs, BlockScratch& bk,
                            int by) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const size_t N = hn::Lanes(d);
  const Edge* e = bs.e;
  const int cy0 = std::max(by * kBlockSize, bs.ry0), cy1 = std::min(by * kBlockSize + kBlockSize - 1, bs.ry1);
  // (Each term exact in double, as is their difference: the integer the comment above names.)
  const double top = double(centerFixed(c.y0 + cy0)), bottom = double(centerFixed(c.y0 + cy1));
  double yLargest[3], ySmallest[3];  // per edge: dx (py - ay) - bias at the rows that bound it
  double* rowEdge = bk.rowEdge[by];
  for (int i = 0; i < 3; ++i) {
    const double dxTop = bs.edgeDx[i] * top, dxBottom = bs.edgeDx[i] * bottom;
    yLargest[i] = (e[i].dx > 0 ? dxBottom : dxTop) - bs.edgeDxAyBias[i];
    ySmallest[i] = (e[i].dx > 0 ? dxTop : dxBottom) - bs.edgeDxAyBias[i];
    rowEdge[i] = dxTop - bs.edgeDxAy[i];
  }
  // (Gathered in locals and stored to the row's arrays at the end: or-ed into the arrays, through
  // memory, they were slower.)
  uint64_t visit = 0;
  uint64_t insideEdge[3] = {};
  for (size_t k = 0; k < size_t(kBlocksX); k += N) {
    const Mask inBox = hn::MaskFromVec(bs.inBoxV[k / N]);
    if (hn::AllFalse(d, inBox)) continue;
    const V far = hn::Load(d, c.s.blockFar + size_t(by * kBlocksX) + k);
    // The triangle's nearest value in each block: qNear, or the plane's bound over the block's
    // part of the box when nearer to the truth (farther), which also rejects blocks the
    // triangle covers only in part.
    V nearestIn = bs.qNearV;
    if (bs.rectBounds) {
      const StoredRangeV r = RectRange<S, M>(tri.m, bs.pErr, bs.pXLow[k / N], bs.pXHigh[k / N], double(c.y0 + cy0) + 0.5,
                                             double(c.y0 + cy1) + 0.5);
      hn::Store(r.nearest, d, bk.rectNearest[by] + k);
      hn::Store(r.farthest, d, bk.rectFarthest[by] + k);
      nearestIn = Farther<kGreater>(bs.qNearV, r.nearest);
    }
    const Mask beaten = kIds ? Nearer<kGreater>(far, nearestIn) : hn::Not(Nearer<kGreater>(nearestIn, far));
    Mask empty = hn::FirstN(d, 0);
    uint8_t bits[4][8] = {};
    for (int i = 0; i < 3; ++i) {
      empty = hn::Or(empty, hn::Lt(hn::Set(d, yLargest[i]), bs.xLargest[i][k / N]));
      hn::StoreMaskBits(d, hn::Ge(hn::Set(d, ySmallest[i]), bs.xSmallest[i][k / N]), bits[1 + i]);
    }
    hn::StoreMaskBits(d, hn::AndNot(beaten, hn::AndNot(empty, inBox)), bits[0]);
    visit |= uint64_t(bits[0][0]) << k;
    for (int i = 0; i < 3; ++i) insideEdge[i] |= uint64_t(bits[1 + i][0]) << k;
    // (Empty blocks are counted at the end: the boxes' blocks less those culled here and drawn.)
    if constexpr (kCountBlocks) c.blocksCulledHere += hn::CountTrue(d, hn::And(inBox, beaten));
  }
  bk.visit[by] = visit;
  for (int i = 0; i < 3; ++i) bk.inside[by][i] = insideEdge[i];
}

// A block row of the box as the visits read it: its part of the box (rows cy0 to cy1) and its
// classification.
struct BlockRow {
  int by, cy0, cy1;
  const uint64_t* insideEdge;
  const double* rowEdge;
  const double* rectNearest;
  const double* rectFarthest;
};

// One block a triangle visits: its index, the columns of its part of the box, the edges that
// cross that part, and how its rows start.
struct BlockVisit {
  int bx, b, cx0, cx1;
  int bxPixel;        // tile-local x of the block's first column
  unsigned crossing;  // bit i: edge i crosses the block's part of the box (not every centre inside)
  bool fromClear;     // the rows start from the clear value (key 0) without reading it
  bool unclamped;     // the rows' depths need no clamp (see VisitBlock)
};

// A block the triangle covers whole (every pixel centre of the block, in the image), with the
// triangle's bounds over its corner centres (storedRangeOverRect, or the same bits from
// classification; every covered value lies within them): skipped when behind everything stored
// there, or made the triangle's plane in O(1) when in front of it all. That replacement is for
// a triangle parallel to the image plane over any block (every fragment stores zConstant's
// bits) and for a sloped one over a block still uniform (cleared, or another plane not yet
// written out; the resolve's preparation skips the block too); over blocks held pixel by pixel
// sloped planes were slower (see docs/benchmarks.md). With an affine depth, classification has
// skipped the beaten blocks already, covered whole or not. Returns whether the block is done.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE bool TryWholeBlock(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const BlockSetup& bs,
                              const BlockRow& row, const BlockVisit& v) {
  TileScratch& s = c.s;
  const int b = v.b;
  const int blockX1 = std::min(v.bx * kBlockSize + kBlockSize - 1, c.w - 1);
  const int blockY1 = std::min(row.by * kBlockSize + kBlockSize - 1, c.h - 1);
  if (!(v.cx0 == v.bx * kBlockSize && row.cy0 == row.by * kBlockSize && v.cx1 == blockX1 && row.cy1 == blockY1))
    return false;
  StoredRange r{hn::GetLane(bs.zConstant), hn::GetLane(bs.zConstant)};
  if (!bs.constantDepth)
    r = bs.rectBounds ? StoredRange{row.rectNearest[v.bx], row.rectFarthest[v.bx]}
                      : storedRangeOverRect<S, M>(tri.m, bs.pErr, bs.qErr, c.x0 + v.cx0 + 0.5, c.x0 + v.cx1 + 0.5,
                                                  c.y0 + row.cy0 + 0.5, c.y0 + row.cy1 + 0.5);
  if (Beaten<M, kIds>(r.nearest, s.blockFar[b])) {
    if constexpr (kCountBlocks) ++c.count.blocksCulled;
    return true;
  }
  if (!((bs.constantDepth || Lazy(s, b)) && storedNearer<M>(r.farthest, s.blockNear[b]))) return false;
  const uint64_t cells = uint64_t(v.cx1 - v.cx0 + 1) * uint64_t(row.cy1 - row.cy0 + 1);
  c.tests += cells;
  c.writes += cells;
  ++c.count.blocksWhole;
  s.blockKey[b] = tri.key;
  s.blockClear[b] = false;
  s.blockTriangle[b] = &tri.t;
  s.tileFarStale |= s.blockFar[b] == s.tileFar;
  s.blockFar[b] = r.farthest;
  s.blockNear[b] = r.nearest;
  if (storedNearer<M>(r.nearest, s.tileNear)) s.tileNear = r.nearest;
  c.dirtyBlocks &= ~(uint64_t(1) << b);  // its pixel buffers are no longer its values
  Pump(c.job.pump, kPumpPerWholeBlock);
  return true;
}

// A block in a uniform state (Lazy) readied for the triangle's rows. A cleared one is written
// only where those rows do not reach: they start from the clear value (key 0) without reading
// it and store every column (MaterializeBlock's values, without writing those rows twice).
// A plane is written out (MaterializeBlock). Returns whether the rows start from the clear value.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE bool ReadyLazyBlock(TileCtx<S, M, kIds>& c, const BlockRow& row, const BlockVisit& v) {
  const D d;
  const DU du;
  const size_t N = hn::Lanes(d);
  TileScratch& s = c.s;
  const int b = v.b, by = row.by;
  bool fromClear = false;
  if (Lazy(s, b)) {
    if (s.blockClear[b]) {
      fromClear = true;
      for (int y = by * kBlockSize; y < (by + 1) * kBlockSize; ++y) {
        if (y == row.cy0) y = row.cy1 + 1;
        if (y >= (by + 1) * kBlockSize) break;
        for (size_t k = 0; k < size_t(kBlockSize); k += N) {
          const size_t at = size_t(y) * kTileSize + size_t(v.bxPixel) + k;
          hn::Store(c.clearV, d, s.depth + at);
          if constexpr (kIds) hn::Store(hn::Zero(du), du, s.triangle + at);
        }
      }
      s.blockClear[b] = false;
    } else {
      MaterializeBlock<S, M, kIds>(c.job, c.tf, b, c.reciprocal);
    }
  }
  return fromClear;
}

// Block column bx's vectors (BlockScratch), computed at the first of its blocks the triangle
// visits: its columns in the box, a X of both planes (the bits StoredDepth computes) and the
// edge functions' x terms (integers below 2^49: exact in double, in any order).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void ReadyColumn(const TileCtx<S, M, kIds>& c, const TriangleCtx& tri, BlockSetup& bs, BlockScratch& bk,
                            const BlockVisit& v) {
  const D d;
  const size_t N = hn::Lanes(d);
  const int bx = v.bx;
  if (bs.columnReady >> bx & 1) return;
  bs.columnReady |= 1u << bx;
  const Edge* e = bs.e;
  for (size_t k = 0; k < size_t(kBlockSize); k += N) {
    const V col = hn::Add(c.lane, hn::Set(d, double(v.bxPixel + int(k))));
    bk.colIn[bx][k / N] =
        hn::VecFromMask(d, hn::And(hn::Ge(col, hn::Set(d, double(v.cx0))), hn::Le(col, hn::Set(d, double(v.cx1)))));
    const V X = hn::Add(col, hn::Set(d, double(c.x0) + 0.5));
    bk.colPX[bx][k / N] = hn::Mul(hn::Set(d, tri.m.p.a), X);
    bk.colQX[bx][k / N] = hn::Mul(hn::Set(d, tri.m.q.a), X);
    for (int i = 0; i < 3; ++i)  // lane j: j stepX - dy (px - ax) at the vector's first pixel px
      bk.colEdge[i][bx][k / N] =
          hn::Sub(bs.laneE[i], hn::Set(d, double(e[i].dy * (centerFixed(c.x0 + v.bxPixel + int(k)) - e[i].ax))));
  }
}

// A visited block's rows as DrawBlockRows draws them: the crossing edges' functions at the
// current row (stepped row by row), their steps and biases, packed; the block column's vectors;
// and what the rows gather: their farthest value and, per vector, the nearest (VisitBlock).
struct BlockRows {
  V edgeRow[3][kRowVectors], edgeStep[3], edgeBias[3];
  int edges;
  const V* columnIn;
  const V* pX;
  const V* qX;
  V far, nearest[kRowVectors];
};

// BlockRows for block v: only the crossing edges are tested in its rows (none when the triangle
// covers the block's part of the box whole).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void StartBlockRows(const TileCtx<S, M, kIds>& c, const BlockSetup& bs, const BlockScratch& bk,
                               const BlockRow& row, const BlockVisit& v, BlockRows& r) {
  const D d;
  const size_t N = hn::Lanes(d);
  r.columnIn = bk.colIn[v.bx];
  r.pX = bk.colPX[v.bx];
  r.qX = bk.colQX[v.bx];
  r.edges = 0;
  for (int i = 0; i < 3; ++i) {
    if (!(v.crossing >> i & 1)) continue;
    for (size_t k = 0; k < size_t(kBlockSize); k += N)
      r.edgeRow[r.edges][k / N] = hn::Add(hn::Set(d, row.rowEdge[i]), bk.colEdge[i][v.bx][k / N]);
    r.edgeStep[r.edges] = bs.stepYV[i];
    r.edgeBias[r.edges] = bs.biasV[i];
    ++r.edges;
  }
  r.far = c.nearestV;
  for (V& near : r.nearest) near = c.farthestV;
}

// The kernel's inner loop: the rows of block v in the box, kEdges crossing edges tested, the
// clamp left out when kUnclamped. Every covered pixel's depth is computed and compared (counted
// as tested): the rows have no branches, a mispredicted one costs more than the division it
// would save. (No fragment is nearer than the triangle's bound qNear, so testing the stored
// values against qNear first would reject none that wins or ties.)
template <int kEdges, bool kUnclamped, DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawBlockRows(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const BlockSetup& bs,
                              const BlockRow& row, const BlockVisit& v, BlockRows& r) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const DU du;
  const hn::RebindToSigned<DU> di;  // keys compared as signed: they are below 2^63
  const size_t N = hn::Lanes(d);
  TileScratch& s = c.s;
  const MappedPlanes& m = tri.m;
  double Y = double(c.y0 + row.cy0) + 0.5;  // the row's centre, stepped (exact: integers + 0.5)
  for (int y = row.cy0; y <= row.cy1; ++y, Y += 1.0) {
    const V pY = hn::Set(d, m.p.b * Y);
    for (size_t k = 0; k < size_t(kBlockSize); k += N) {
      const size_t at = size_t(y) * kTileSize + size_t(v.bxPixel) + k;
      const V stored = v.fromClear ? c.clearV : hn::Load(d, s.depth + at);
      V result = stored;
      Mask cover = hn::MaskFromVec(r.columnIn[k / N]);
      for (int i = 0; i < kEdges; ++i) {
        cover = hn::And(cover, hn::Ge(r.edgeRow[i][k / N], r.edgeBias[i]));
        r.edgeRow[i][k / N] = hn::Add(r.edgeRow[i][k / N], r.edgeStep[i]);
      }
      // Pixel centres X = x + 0.5; depth = P(X, Y) / Q(X, Y) (setup/fragment_depth.hpp).
      const V z = bs.constantDepth && !kUnclamped ? bs.zConstant
                                                  : StoredDepthAt<S, kUnclamped>(m, r.pX[k / N], pY, r.qX[k / N], Y);
      Mask win = hn::And(cover, Nearer<kGreater>(z, stored));
      if constexpr (kIds) {  // a tie goes to the triangle submitted first
        const auto old = v.fromClear ? hn::Zero(du) : hn::Load(du, s.triangle + at);
        const Mask tie =
            hn::And(hn::Eq(z, stored), hn::RebindMask(d, hn::Lt(hn::BitCast(di, bs.idV), hn::BitCast(di, old))));
        win = hn::Or(win, hn::And(cover, tie));
        hn::Store(hn::IfThenElse(hn::RebindMask(du, win), bs.idV, old), du, s.triangle + at);
      }
      c.rowTests = CountIn(c.rowTests, cover);
      c.rowWrites = CountIn(c.rowWrites, win);
      result = hn::IfThenElse(win, z, stored);
      hn::Store(result, d, s.depth + at);
      if constexpr (!kUnclamped) r.nearest[k / N] = NearerOf<kGreater>(r.nearest[k / N], result);
      r.far = Farther<kGreater>(r.far, result);
    }
  }
}

// DrawBlockRows compiled for each number of crossing edges (0 to 3).
template <bool kUnclamped, DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawBlockRowsFor(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const BlockSetup& bs,
                                 const BlockRow& row, const BlockVisit& v, BlockRows& r) {
  switch (r.edges) {
    case 0: DrawBlockRows<0, kUnclamped>(c, tri, bs, row, v, r); break;
    case 1: DrawBlockRows<1, kUnclamped>(c, tri, bs, row, v, r); break;
    case 2: DrawBlockRows<2, kUnclamped>(c, tri, bs, row, v, r); break;
    default: DrawBlockRows<3, kUnclamped>(c, tri, bs, row, v, r); break;
  }
}

// After rows that wrote: the block's farthest value (of the rows drawn and those outside the box,
// which kept theirs) and its and the tile's nearest, moved by the nearest written. The rows
// gathered that per vector (a lane is one column; only in-image columns count, the others hold
// the nearest possible value): the nearest written, or a stored value no nearer than blockNear,
// a bound of every value in the block's image part, so it moves blockNear as the nearest
// written would. Unclamped rows do not gather it: the triangle's nearest bound over the block's
// part of the box (rectNearest), a bound of what they wrote as well, moves blockNear instead.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void UpdateBlockBounds(TileCtx<S, M, kIds>& c, const BlockRow& row, const BlockVisit& v, BlockRows& r) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const size_t N = hn::Lanes(d);
  TileScratch& s = c.s;
  const int b = v.b, by = row.by;
  for (int y = by * kBlockSize; y < (by + 1) * kBlockSize; ++y) {
    if (y == row.cy0) y = row.cy1 + 1;
    if (y >= (by + 1) * kBlockSize) break;
    for (size_t k = 0; k < size_t(kBlockSize); k += N)
      r.far = Farther<kGreater>(r.far, hn::Load(d, s.depth + size_t(y) * kTileSize + size_t(v.bxPixel) + k));
  }
  // The tile's farthest value can only move when the block that held it moved.
  s.tileFarStale |= s.blockFar[b] == s.tileFar;
  s.blockFar[b] = FarthestLane<kGreater>(r.far);
  double written = row.rectNearest[v.bx];
  if (!v.unclamped) {
    V near = c.farthestV;
    for (size_t k = 0; k < size_t(kBlockSize); k += N) {
      const Mask inImage = hn::Lt(hn::Add(c.lane, hn::Set(d, double(v.bxPixel + int(k)))), hn::Set(d, double(c.w)));
      near = NearerOf<kGreater>(near, hn::IfThenElse(inImage, r.nearest[k / N], c.farthestV));
    }
    written = NearestLane<kGreater>(near);
  }
  if (storedNearer<M>(written, s.blockNear[b])) s.blockNear[b] = written;
  if (storedNearer<M>(written, s.tileNear)) s.tileNear = written;
}

// Block bx of `row`, which classification left to visit: skipped or replaced in O(1) when the
// triangle covers it whole (TryWholeBlock); else readied (ReadyLazyBlock, ReadyColumn), its rows
// drawn (DrawBlockRows) and its bounds moved (UpdateBlockBounds). The rows leave out the clamp
// when the depth is affine and its bounds over the block's part of the box lie strictly between
// the stored values of 0 and 1 (clamping changes nothing there: the same bits).
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void VisitBlock(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, BlockSetup& bs, BlockScratch& bk,
                           const BlockRow& row, int bx) {
  const DU du;
  BlockVisit v;
  v.bx = bx;
  v.b = row.by * kBlocksX + bx;
  v.crossing = unsigned(~row.insideEdge[0] >> bx & 1) | unsigned(~row.insideEdge[1] >> bx & 1) << 1 |
               unsigned(~row.insideEdge[2] >> bx & 1) << 2;
  const bool full = v.crossing == 0;
  v.cx0 = std::max(bx * kBlockSize, bs.rx0);
  v.cx1 = std::min(bx * kBlockSize + kBlockSize - 1, bs.rx1);
  if constexpr (kCountBlocks) ++(full ? c.count.blocksFull : c.count.blocksPartial);
  if (full && TryWholeBlock(c, tri, bs, row, v)) return;
  v.bxPixel = bx * kBlockSize;
  v.fromClear = ReadyLazyBlock(c, row, v);
  ReadyColumn(c, tri, bs, bk, v);
  BlockRows r;
  StartBlockRows(c, bs, bk, row, v, r);
  const hn::Vec<DU> writesBefore = c.rowWrites;  // (the rows wrote when a lane's count moved)
  v.unclamped = bs.rectBounds && !bs.constantDepth && std::min(row.rectNearest[bx], row.rectFarthest[bx]) > 0 &&
                std::max(row.rectNearest[bx], row.rectFarthest[bx]) < c.tf.storedOne;
  if (v.unclamped) DrawBlockRowsFor<true>(c, tri, bs, row, v, r);
  else DrawBlockRowsFor<false>(c, tri, bs, row, v, r);
  Pump(c.job.pump, kPumpPerBlock);
  if (!hn::AllTrue(du, hn::Eq(c.rowWrites, writesBefore))) UpdateBlockBounds(c, row, v, r);
}

// A triangle over more than kSmallPixels centres of the tile, block by block: the box's block
// rows are all classified first, then visited row by row. A row's classification is a long chain
// of dependent operations; classified just before its visits, every row would wait on the one
// before through the visit loop's branches, classified ahead the rows' chains overlap. Only this
// triangle's visits write the blocks it classifies, each block once, so every block reads the
// same values classified ahead as just before its visit: the same blocks are drawn.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void DrawBlocks(TileCtx<S, M, kIds>& c, const TriangleCtx& tri, const Edge (&e)[3], const PixelBox& box) {
  BlockSetup bs;
  SetUpBlocks(c, tri, e, box, bs);
  BlockScratch bk;
  for (int by = bs.byFirst; by <= bs.byLast; ++by) ClassifyRow(c, tri, bs, bk, by);
  for (int by = bs.byFirst; by <= bs.byLast; ++by) {
    const BlockRow row{by,
                       std::max(by * kBlockSize, bs.ry0),
                       std::min(by * kBlockSize + kBlockSize - 1, bs.ry1),
                       bk.inside[by],
                       bk.rowEdge[by],
                       bk.rectNearest[by],
                       bk.rectFarthest[by]};
    Pump(c.job.pump, kPumpPerBlockRow);
    for (uint64_t visit = bk.visit[by]; visit; visit &= visit - 1)
      VisitBlock(c, tri, bs, bk, row, int(hwy::Num0BitsBelowLS1Bit_Nonzero64(visit)));
  }
}

// ---- The tile ----

// The tile's end: exact block bounds for the deferred back faces' test after a front pass
// (tile_pass.cpp, selectLate), and the counts added to the job's.
template <DepthStorage S, DepthMapping M, bool kIds>
HWY_INLINE void FinishTile(TileCtx<S, M, kIds>& c) {
  const DU du;
  if (c.job.pass == TileJob::Pass::Front && c.s.state == TileState::Pixels) {
    if (c.dirtyBlocks) RefreshDirty(c);
    if (c.s.tileFarStale) RefreshTileFar(c);
  }
  if constexpr (kCountBlocks) {
    c.count.blocksCulled += c.blocksCulledHere;
    c.count.blocksEmpty = c.blocksInBoxes - c.blocksCulledHere - c.count.blocksFull - c.count.blocksPartial;
  }
  c.count.depthTests = c.tests + hn::GetLane(hn::SumOfLanes(du, c.rowTests));
  c.count.depthWrites = c.writes + hn::GetLane(hn::SumOfLanes(du, c.rowWrites));
  c.job.counters->add(c.count);
}

// Draws the tile's triangles (TileJob), nearest first. Each triangle is rejected by the tile's
// bound, drawn from its coverage list, made the whole tile's plane, drawn pixel by pixel when
// small, or else block by block. Every step is force-inlined: this is one loop over the
// triangles, and TileCtx holds its locals.
template <DepthStorage S, DepthMapping M, bool kIds>
void RasterizeTileT(const TileJob& job) {
  const D d;
  const DU du;
  TileScratch& s = *job.scratch;
  const TileFrame tf = MakeTileFrame<S, M>(job);
  const int x0 = tf.x0, y0 = tf.y0, w = tf.w, h = tf.h;

  // The tile starts cleared, as one uniform state: nothing is written to its buffers until a
  // triangle covers only part of it. (The late pass goes on from the front pass's tile; with
  // keep, the pass goes on from the tile loaded.)
  if (job.pass != TileJob::Pass::Late && !job.keep) {
    s.state = TileState::Clear;
    s.resolved = false;
    s.tileFar = tf.clear;
    s.tileNear = tf.clear;
    s.tileFarStale = false;
  }

  const double n = job.depth.near, f = job.depth.far;
  const bool ortho = job.depth.orthographic;
  const TileCorners corners{{centerFixed(x0), centerFixed(x0 + w - 1)},
                            {centerFixed(y0), centerFixed(y0 + h - 1)},
                            {x0 + 0.5, x0 + w - 0.5, x0 + w - 0.5, x0 + 0.5},
                            {y0 + 0.5, y0 + 0.5, y0 + h - 0.5, y0 + h - 0.5}};
  RasterCounters count;
  ReciprocalCache reciprocal;
  TileCtx<S, M, kIds> c{.job = job,
                        .s = s,
                        .bins = *job.bins,
                        .tf = tf,
                        .corners = corners,
                        .reciprocal = reciprocal,
                        .count = count,
                        .x0 = x0,
                        .y0 = y0,
                        .w = w,
                        .h = h,
                        .nearestV = hn::Set(d, tf.nearestPossible),
                        .farthestV = hn::Set(d, tf.farthestPossible),
                        .clearV = hn::Set(d, tf.clear),
                        .lane = hn::Iota(d, 0.0),
                        .rowTests = hn::Zero(du),
                        .rowWrites = hn::Zero(du)};

  // The tile's triangles, roughly nearest first (orderTile): any order gives the same image.
  const std::vector<TileEntry>& order =
      job.pass == TileJob::Pass::Late ? job.order->late : orderTile(c.bins, job.tile, job.depth, *job.order);
  for (size_t item = 0, end = order.size(); item < end; ++item) {
    const SetupTriangle& t = c.bins.triangle(order[item].key);
    PrefetchAhead(c, order, item, end);
    const uint64_t key = order[item].key;
    const double qNear = order[item].nearest;
    // Blocks small triangles wrote to: their farthest values, again, every 16 triangles (a stale
    // value is still a valid bound: writes only bring stored values nearer).
    if (c.dirtyBlocks && (++c.sinceRefresh & 15) == 0) RefreshDirty(c);
    if (s.tileFarStale) RefreshTileFar(c);
    // Early rejection: the triangle's nearest possible value is farther than the farthest value
    // stored in the tile (or, without ids, not nearer), so none of its fragments can win here.
    if (Beaten<M, kIds>(qNear, s.tileFar)) {
      ++count.culledTiles;
      continue;
    }
    const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, n, f, ortho, reciprocal);
    const TriangleCtx tri{t, m, key, qNear};
    if (t.coverage) {
      DrawCoverage(c, tri);
      continue;
    }
    const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
    if (TryWholeTile(c, tri, e)) continue;
    EnsurePixels(c);
    const PixelBox box{std::max(t.minX - x0, 0), std::min(t.maxX - x0, w - 1), std::max(t.minY - y0, 0),
                       std::min(t.maxY - y0, h - 1)};
    if ((box.rx1 - box.rx0 + 1) * (box.ry1 - box.ry0 + 1) <= kSmallPixels) DrawSmall(c, tri, e, box);
    else DrawBlocks(c, tri, e, box);
  }
  FinishTile(c);
}

// unmapDepth<M>(stored / scale) (core/depth_map.hpp, eyeDepthOfStored) lane by lane.
template <DepthStorage S, DepthMapping M>
HWY_INLINE V EyeDepthOfStored(V q, const DepthSetup& depth) {
  const D d;
  const double n = depth.near, f = depth.far;
  const V v = S == DepthStorage::F32 ? q : hn::Div(q, hn::Set(d, kDepthScale<S>));
  const V nV = hn::Set(d, n), fV = hn::Set(d, f), fMinusN = hn::Set(d, f - n);
  if constexpr (M == DepthMapping::Z) {
    return depth.orthographic ? hn::Add(nV, hn::Mul(v, fMinusN))
                              : hn::Div(hn::Set(d, f * n), hn::Sub(fV, hn::Mul(v, fMinusN)));
  } else if constexpr (M == DepthMapping::Reversed) {
    return depth.orthographic ? hn::Sub(fV, hn::Mul(v, fMinusN))
                              : hn::Div(hn::Set(d, n * f), hn::Add(nV, hn::Mul(v, fMinusN)));
  } else if constexpr (M == DepthMapping::Inv) {
    return hn::IfThenElse(hn::Gt(v, hn::Zero(d)), hn::Div(nV, v), hn::Set(d, std::numeric_limits<double>::infinity()));
  } else {
    return hn::Add(nV, hn::Mul(v, fMinusN));
  }
}

// The bits of a 4-byte value.
template <class T>
HWY_INLINE uint32_t Bits32(T v) {
  static_assert(sizeof(T) == 4);
  uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return bits;
}

// Depth only: the eye depth of every stored value that left the clear value, +inf elsewhere
// (every pixel of the tile is written).
template <DepthStorage S, DepthMapping M>
uint64_t ResolveDepthT(const TileJob& job, const TileScratch& s, int rowBegin, int rowEnd, Frame& frame) {
  const D d;
  const hn::Rebind<float, D> df;
  const size_t N = hn::Lanes(d);
  const TileFrame tf = MakeTileFrame<S, M>(job);
  const V clearV = hn::Set(d, tf.clear);
  const V infinity = hn::Set(d, std::numeric_limits<double>::infinity());
  const MappedPlanes m = s.state == TileState::Plane ? mapPlanes<M>(s.plane->depthNum, s.plane->depthDen, job.depth.near,
                                                                     job.depth.far, job.depth.orthographic)
                                                      : MappedPlanes{};
  uint64_t covered = 0;
  if (s.state == TileState::Clear) {  // +inf, straight into the frame
    for (int y = rowBegin; y < std::min(rowEnd, tf.h); ++y)
      StreamFill(reinterpret_cast<uint32_t*>(frame.depth.data() + frame.index(tf.x0, tf.y0 + y)),
                 Bits32(std::numeric_limits<float>::infinity()), size_t(tf.w));
    return 0;
  }
  HWY_ALIGN float row[kTileSize];  // a row of the tile, then streamed into the frame (core/stream-inl.h)
  const SetupTriangle* blockPlane = nullptr;  // the planes of the last block in a triangle's plane
  MappedPlanes blockM{};
  // Row by row in two passes: the stored values of the row's lanes (by the tile's or block's
  // state), then their eye depths. Apart, the second pass is a short loop of independent
  // divisions that the processor overlaps; in one loop with the state's branches and the
  // plane's arithmetic, a division's latency shows in every vector (see docs/benchmarks.md).
  HWY_ALIGN double stored[kTileSize];
  for (int y = rowBegin; y < std::min(rowEnd, tf.h); ++y) {
    const double Y = double(tf.y0 + y) + 0.5;
    for (size_t k = 0; k < size_t(tf.w); k += N) {
      const int b = (y / kBlockSize) * kBlocksX + int(k) / kBlockSize;  // lanes within one block
      const V X = hn::Iota(d, double(tf.x0 + int(k)) + 0.5);
      V q;
      if (s.state == TileState::Plane) q = StoredDepth<S>(m, X, Y);
      else if (s.blockClear[b]) q = clearV;
      else if (s.blockKey[b]) {
        if (s.blockTriangle[b] != blockPlane) {  // mapped once per run of lanes of one triangle
          blockPlane = s.blockTriangle[b];
          blockM = mapPlanes<M>(blockPlane->depthNum, blockPlane->depthDen, job.depth.near, job.depth.far,
                                job.depth.orthographic);
        }
        q = StoredDepth<S>(blockM, X, Y);
      }
      else q = hn::Load(d, s.depth + size_t(y) * kTileSize + k);
      hn::Store(q, d, stored + k);
    }
    for (size_t k = 0; k < size_t(tf.w); k += N) {
      const V q = hn::Load(d, stored + k);
      const Mask drawn = hn::And(hn::FirstN(d, std::min(N, size_t(tf.w) - k)), hn::Ne(q, clearV));
      covered += hn::CountTrue(d, drawn);
      const V eye = hn::IfThenElse(drawn, EyeDepthOfStored<S, M>(q, job.depth), infinity);
      hn::Store(NarrowToFloat(df, eye), df, row + k);
    }
    StreamCopy(reinterpret_cast<uint32_t*>(frame.depth.data() + frame.index(tf.x0, tf.y0 + y)),
               reinterpret_cast<const uint32_t*>(row), size_t(tf.w));
  }
  return covered;
}

// A pixel's two cells after prepareResolve (tiled.hpp): depth = (float eye depth, int32 face
// id), triangle = (int32 triangle id, Rgba8 colour), the first of each pair in the low half.
HWY_INLINE uint64_t PackCell(uint32_t low, uint32_t high) { return uint64_t(high) << 32 | low; }

// The colour of a set-up triangle for the frame (FrameOutputs::Color), remembering the last one:
// neighbouring pixels mostly share their triangle, and back faces are shaded here.
struct ColorCache {
  const TriangleShader* shader;
  uint64_t lastKey = 0;
  uint32_t lastColor = 0;
  uint32_t operator()(uint64_t key, const SetupTriangle& t) {
    if (key != lastKey) {
      lastKey = key;
      lastColor = Bits32(triangleColor(t, *shader));
    }
    return lastColor;
  }
};

#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
// Four cells of a row held pixel by pixel (keys, cells: as PrepareResolveT turns them), resolved
// together whoever won them: each winner's record words 4 to 11 (depthNum, depthDen, triangle
// and face, frontFacing and colour: SetupTriangle's layout) loaded whole and transposed, 4x4, and
// the eye depths computed a vector at a time with SetupTriangle::eyeDepth's operations (the same
// bits). X is the first cell's pixel centre, Y the row's. A back face's colour (not in its
// record) is left to shadeBack(j, key) for its lane j.
template <bool kColor, class ShadeBack>
HWY_INLINE void ResolveFour(const Bins& bins, uint64_t* keys, uint64_t* cells, double X, double Y, uint64_t emptyDepth,
                            uint64_t emptyTriangle, const ShadeBack& shadeBack) {
  static_assert(offsetof(SetupTriangle, depthNum) == 32 && offsetof(SetupTriangle, depthDen) == 56 &&
                    offsetof(SetupTriangle, triangle) == 80 && offsetof(SetupTriangle, face) == 84 &&
                    offsetof(SetupTriangle, frontFacing) == 88 && offsetof(SetupTriangle, color) == 92,
                "the words below are the record's layout");
  using H4 = hn::CappedTag<double, 4>;
  const H4 h;
  const hn::RebindToUnsigned<H4> hu;
  using VH = hn::Vec<H4>;
  static const SetupTriangle kNothing{};  // read for cells nothing drew (their lanes are replaced)
  const auto keyV = hn::LoadU(hu, keys);
  const double* words[4];
  for (int j = 0; j < 4; ++j)
    words[j] = reinterpret_cast<const double*>(keys[j] ? &bins.resolved(keys[j]) : &kNothing) + 4;
  auto transpose = [&](int at, VH* out) HSR_ALWAYS_INLINE {
    VH q[4];
    for (int j = 0; j < 4; ++j) q[j] = hn::LoadU(h, words[j] + at);
    const VH l01 = hn::InterleaveLower(h, q[0], q[1]), u01 = hn::InterleaveUpper(h, q[0], q[1]);
    const VH l23 = hn::InterleaveLower(h, q[2], q[3]), u23 = hn::InterleaveUpper(h, q[2], q[3]);
    out[0] = hn::ConcatLowerLower(h, l23, l01);
    out[1] = hn::ConcatLowerLower(h, u23, u01);
    out[2] = hn::ConcatUpperUpper(h, l23, l01);
    out[3] = hn::ConcatUpperUpper(h, u23, u01);
  };
  VH p[4], q[4];
  transpose(0, p);  // depthNum a, b, c, depthDen a
  transpose(4, q);  // depthDen b, c, triangle | face << 32, frontFacing | coverage << 16 | colour << 32
  const VH Xv = hn::Iota(h, X), Yv = hn::Set(h, Y);
  const VH eye = hn::Div(hn::Add(hn::Add(hn::Mul(p[0], Xv), hn::Mul(p[1], Yv)), p[2]),
                         hn::Add(hn::Add(hn::Mul(p[3], Xv), hn::Mul(q[0], Yv)), q[1]));
  const hn::Rebind<float, H4> hf;
  const auto eyeBits = hn::PromoteTo(hu, hn::BitCast(hn::Rebind<uint32_t, H4>(), NarrowToFloat(hf, eye)));
  const auto ids = hn::BitCast(hu, q[2]), flags = hn::BitCast(hu, q[3]);
  const auto high = hn::Set(hu, 0xFFFFFFFF00000000ull);
  auto cell = hn::Or(hn::And(ids, high), eyeBits);  // eye depth, face
  auto key = hn::AndNot(high, ids);                 // triangle, colour (below)
  if constexpr (kColor) key = hn::Or(key, hn::And(flags, high));
  const auto nothing = hn::Eq(keyV, hn::Zero(hu));
  hn::StoreU(hn::IfThenElse(nothing, hn::Set(hu, emptyDepth), cell), hu, cells);
  hn::StoreU(hn::IfThenElse(nothing, hn::Set(hu, emptyTriangle), key), hu, keys);
  if constexpr (kColor) {
    const auto back = hn::AndNot(nothing, hn::Eq(hn::And(flags, hn::Set(hu, 0xFF)), hn::Zero(hu)));
    if (!hn::AllFalse(hu, back)) {
      HWY_ALIGN uint64_t was[4];
      hn::Store(keyV, hu, was);
      uint8_t bits[8] = {};
      hn::StoreMaskBits(hu, back, bits);
      for (unsigned left = bits[0]; left; left &= left - 1) {
        const size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(left);
        shadeBack(j, was[j]);
      }
    }
  }
}
#endif

// prepareResolve (tiled.hpp) for a tile in state Pixels: every block held pixel by pixel (not
// Lazy: neither blockKey nor blockClear) turned in place into the frame's values — face id, triangle id and the eye depth of
// the winning triangle's planes at the pixel centre, as the reference resolves it (the same
// operations as SetupTriangle::eyeDepth; a row of lanes won by one triangle with vectors), or
// the background where nothing was drawn.
template <bool kColor>
void PrepareResolveT(const TileJob& job, TileScratch& s, Rgba8 background) {
  const D d;
  const DU du;
  const hn::Rebind<float, D> df;
  const hn::Rebind<uint32_t, D> du32;
  const size_t N = hn::Lanes(d);
  const Bins& bins = *job.bins;
  const auto [x0, y0, w, h] = RectOf(job);
  ColorCache colorOf{job.shader};
  const uint64_t emptyDepth = PackCell(Bits32(std::numeric_limits<float>::infinity()), Bits32(int32_t(-1)));
  const uint64_t emptyTriangle = PackCell(Bits32(int32_t(-1)), kColor ? Bits32(background) : 0);
  for (int b = 0; b < kBlocksPerTile; ++b) {
    const int bx = (b % kBlocksX) * kBlockSize, by = (b / kBlocksX) * kBlockSize;
    if (Lazy(s, b) || bx >= w || by >= h) continue;
    Pump(job.pump, kPumpPerPreparedBlock);
    // One key in every cell (those outside the image hold 0): the block is that triangle's plane
    // (every value is its fragment's, bit for bit) or empty, resolved from that alone.
    const uint64_t only = s.triangle[size_t(by) * kTileSize + size_t(bx)];
    auto same = hn::Set(du, 0);
    for (int y = by; y < by + kBlockSize; ++y)
      for (size_t k = 0; k < size_t(kBlockSize); k += N)
        same = hn::Or(same, hn::Xor(hn::Load(du, s.triangle + size_t(y) * kTileSize + size_t(bx) + k), hn::Set(du, only)));
    if (hn::AllTrue(du, hn::Eq(same, hn::Zero(du)))) {
      if (only) {
        s.blockKey[b] = only;
        s.blockTriangle[b] = &bins.resolved(only);
      } else {
        s.blockClear[b] = true;
      }
      continue;
    }
    for (int y = by; y < std::min(by + kBlockSize, h); ++y) {
      const double Y = double(y0 + y) + 0.5;
      for (size_t k = 0; k < size_t(kBlockSize); k += N) {
        const size_t at = size_t(y) * kTileSize + size_t(bx) + k;
        uint64_t* keys = s.triangle + at;
        uint64_t* cells = reinterpret_cast<uint64_t*>(s.depth + at);
        // A row of one triangle, or of two (a key 0 is the background): a vector per triangle;
        // rows of more (small triangles) with their records transposed (ResolveFour; without
        // AVX2, lane by lane). (Three triangles a vector each, broadcast, was slower.)
        const auto keyV = hn::Load(du, keys);
        const uint64_t first = keys[0];
        const auto isFirst = hn::Eq(keyV, hn::Set(du, first));
        const uint64_t second = hn::AllTrue(du, isFirst) ? first : keys[hn::FindKnownFirstTrue(du, hn::Not(isFirst))];
        const auto isSecond = hn::Eq(keyV, hn::Set(du, second));
        if (hn::AllTrue(du, hn::Or(isFirst, isSecond))) {
          const V X = hn::Iota(d, double(x0 + bx + int(k)) + 0.5);
          auto cellV = hn::Set(du, emptyDepth), newKeyV = hn::Set(du, emptyTriangle);
          auto blend = [&](uint64_t key, auto lanes) {  // key's lanes get its values (0: background)
            if (!key) return;
            const SetupTriangle& t = bins.resolved(key);
            const auto eye = hn::BitCast(du32, NarrowToFloat(df, EyeDepthRow(t, X, Y)));
            cellV = hn::IfThenElse(lanes, hn::Or(hn::PromoteTo(du, eye), hn::Set(du, PackCell(0, Bits32(int32_t(t.face))))),
                                   cellV);
            const uint32_t color = kColor ? colorOf(key, t) : 0;
            newKeyV = hn::IfThenElse(lanes, hn::Set(du, PackCell(Bits32(int32_t(t.triangle)), color)), newKeyV);
          };
          blend(first, isFirst);
          if (second != first) blend(second, isSecond);
          hn::Store(cellV, du, cells);
          hn::Store(newKeyV, du, keys);
          continue;
        }
#if HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
        // Rows of more, four cells at a time rather than lane by lane (then bound by the
        // division).
        for (size_t g = 0; g < N; g += 4)
          ResolveFour<kColor>(bins, keys + g, cells + g, double(x0 + bx + int(k + g)) + 0.5, Y, emptyDepth,
                              emptyTriangle, [&](size_t j, uint64_t key) {
                                const SetupTriangle& t = bins.resolved(key);
                                keys[g + j] = PackCell(Bits32(int32_t(t.triangle)), colorOf(key, t));
                              });
        continue;
#endif
        for (size_t j = 0; j < N; ++j) {
          const uint64_t key = keys[j];
          if (!key) {
            cells[j] = emptyDepth;
            keys[j] = emptyTriangle;
            continue;
          }
          const SetupTriangle& t = bins.resolved(key);
          const float eye = float(t.eyeDepth(double(x0 + bx + int(k + j)) + 0.5, Y));
          cells[j] = PackCell(Bits32(eye), Bits32(int32_t(t.face)));
          keys[j] = PackCell(Bits32(int32_t(t.triangle)), kColor ? colorOf(key, t) : 0);
        }
      }
    }
  }
  s.resolved = true;
}

// With ids: writes the tile's rows [rowBegin, rowEnd) into the frame's depth and the buffers
// kOutputs asks for (FrameOutputs flags). Blocks held pixel by pixel are copied from the cells
// prepareResolve filled; uniform ones (a cleared tile, a plane tile or block) are computed from
// their triangle, a row of lanes at a time.
template <uint8_t kOutputs>
uint64_t ResolveIdsT(const TileJob& job, const TileScratch& s, Rgba8 background, int rowBegin, int rowEnd,
                     Frame& frame) {
  const D d;
  const hn::Rebind<float, D> df;
  const hn::Rebind<uint32_t, D> du32;
  const size_t N = hn::Lanes(d);
  constexpr bool kFace = kOutputs & uint8_t(FrameOutputs::FaceIds);
  constexpr bool kTriangle = kOutputs & uint8_t(FrameOutputs::TriangleIds);
  constexpr bool kColor = kOutputs & uint8_t(FrameOutputs::Color);
  const Bins& bins = *job.bins;
  const auto [x0, y0, w, h] = RectOf(job);
  if (s.state == TileState::Pixels && !s.resolved)
    throw std::logic_error("resolveTile: a tile held pixel by pixel was not through prepareResolve");
  ColorCache colorOf{job.shader};
  const uint32_t backgroundBits = Bits32(background);
  const auto noId = hn::Set(du32, Bits32(int32_t(-1)));
  uint64_t covered = 0;
  if (s.state == TileState::Clear) {  // the background, straight into the frame
    const uint32_t infinityBits = Bits32(std::numeric_limits<float>::infinity()), noIdBits = Bits32(int32_t(-1));
    for (int y = rowBegin; y < std::min(rowEnd, h); ++y) {
      const size_t at = frame.index(x0, y0 + y);
      StreamFill(reinterpret_cast<uint32_t*>(frame.depth.data() + at), infinityBits, size_t(w));
      if constexpr (kFace) StreamFill(reinterpret_cast<uint32_t*>(frame.faceId.data() + at), noIdBits, size_t(w));
      if constexpr (kTriangle)
        StreamFill(reinterpret_cast<uint32_t*>(frame.triangleId.data() + at), noIdBits, size_t(w));
      if constexpr (kColor) StreamFill(reinterpret_cast<uint32_t*>(frame.color.data() + at), backgroundBits, size_t(w));
    }
    return 0;
  }
  HWY_ALIGN uint32_t rows[4][kTileSize];  // a row of the tile per output, then streamed (core/stream-inl.h)
  auto streamRows = [&](int y) HSR_ALWAYS_INLINE {  // rows[] into the frame's row y of the tile
    const size_t at = frame.index(x0, y0 + y);
    StreamCopy(reinterpret_cast<uint32_t*>(frame.depth.data() + at), rows[0], size_t(w));
    if constexpr (kFace) StreamCopy(reinterpret_cast<uint32_t*>(frame.faceId.data() + at), rows[1], size_t(w));
    if constexpr (kTriangle) StreamCopy(reinterpret_cast<uint32_t*>(frame.triangleId.data() + at), rows[2], size_t(w));
    if constexpr (kColor) StreamCopy(reinterpret_cast<uint32_t*>(frame.color.data() + at), rows[3], size_t(w));
  };
  if (s.state == TileState::Plane) {
    // One triangle's plane over the whole tile: its ids and colour are the same in every row
    // (written once); each row's eye depths in a loop of nothing else, whose divisions overlap
    // (as in ResolveDepthT), with EyeDepthAt's operations: faster than the general loop below
    // (see docs/benchmarks.md).
    const SetupTriangle& t = bins.resolved(s.planeKey);
    const auto face = hn::Set(du32, Bits32(int32_t(t.face))), triangle = hn::Set(du32, Bits32(int32_t(t.triangle)));
    const auto color = hn::Set(du32, kColor ? colorOf(s.planeKey, t) : 0);
    for (size_t k = 0; k < size_t(w); k += N) {
      hn::Store(face, du32, rows[1] + k);
      hn::Store(triangle, du32, rows[2] + k);
      hn::Store(color, du32, rows[3] + k);
    }
    EyePlanesV plane{hn::Set(d, t.depthNum.a), hn::Zero(d), hn::Set(d, t.depthNum.c),
                     hn::Set(d, t.depthDen.a), hn::Zero(d), hn::Set(d, t.depthDen.c)};
    for (int y = rowBegin; y < std::min(rowEnd, h); ++y) {
      const double Y = double(y0 + y) + 0.5;
      plane.numBY = hn::Set(d, t.depthNum.b * Y), plane.denBY = hn::Set(d, t.depthDen.b * Y);
      for (size_t k = 0; k < size_t(w); k += N) {
        const V X = hn::Iota(d, double(x0 + int(k)) + 0.5);
        hn::Store(hn::BitCast(du32, NarrowToFloat(df, EyeDepthAt(plane, X))), du32, rows[0] + k);
      }
      covered += uint64_t(w);
      streamRows(y);
    }
    return covered;
  }
  // The tile is held pixel by pixel (state Pixels), block by block: the cells prepareResolve
  // filled, or a block's uniform state (cleared, or a triangle's plane). The triangle of the
  // uniform lanes last met: its record read and its values broadcast once, not per run of
  // lanes; the planes' b Y once per row (the products EyeDepthRow forms: the same bits).
  uint64_t uniformKey = 0;
  double numB = 0, denB = 0, uniformY = -1;
  EyePlanesV planes{hn::Zero(d), hn::Zero(d), hn::Zero(d), hn::Zero(d), hn::Zero(d), hn::Zero(d)};
  hn::Vec<decltype(du32)> uniformFace = noId, uniformTriangle = noId, uniformColor = noId;
  for (int y = rowBegin; y < std::min(rowEnd, h); ++y) {
    const double Y = double(y0 + y) + 0.5;
    for (size_t k = 0; k < size_t(w); k += N) {
      const size_t count = std::min(N, size_t(w) - k);
      uint32_t* depthOut = rows[0] + k;
      uint32_t* faceOut = rows[1] + k;
      uint32_t* triangleOut = rows[2] + k;
      uint32_t* colorOut = rows[3] + k;
      const int b = (y / kBlockSize) * kBlocksX + int(k) / kBlockSize;  // (lanes within one block)
      const uint64_t key = s.blockKey[b];  // (0 when the block is cleared or held pixel by pixel)
      if (!key && !s.blockClear[b]) {  // the cells prepareResolve filled
        hn::Vec<decltype(du32)> eye, face, triangle, color;
        hn::LoadInterleaved2(du32, reinterpret_cast<const uint32_t*>(s.depth + size_t(y) * kTileSize + k), eye, face);
        hn::LoadInterleaved2(du32, reinterpret_cast<const uint32_t*>(s.triangle + size_t(y) * kTileSize + k), triangle,
                             color);
        hn::Store(eye, du32, depthOut);
        hn::Store(face, du32, faceOut);
        hn::Store(triangle, du32, triangleOut);
        if constexpr (kColor) hn::Store(color, du32, colorOut);
        covered += hn::CountTrue(du32, hn::AndNot(hn::Eq(triangle, noId), hn::FirstN(du32, count)));
        continue;
      }
      if (!key) {  // cleared
        hn::Store(hn::Set(du32, Bits32(std::numeric_limits<float>::infinity())), du32, depthOut);
        hn::Store(noId, du32, faceOut);
        hn::Store(noId, du32, triangleOut);
        if constexpr (kColor) hn::Store(hn::Set(du32, backgroundBits), du32, colorOut);
        continue;
      }
      if (key != uniformKey) {
        const SetupTriangle& t = bins.resolved(key);
        uniformKey = key;
        planes.numA = hn::Set(d, t.depthNum.a), planes.numC = hn::Set(d, t.depthNum.c), numB = t.depthNum.b;
        planes.denA = hn::Set(d, t.depthDen.a), planes.denC = hn::Set(d, t.depthDen.c), denB = t.depthDen.b;
        uniformFace = hn::Set(du32, Bits32(int32_t(t.face)));
        uniformTriangle = hn::Set(du32, Bits32(int32_t(t.triangle)));
        if constexpr (kColor) uniformColor = hn::Set(du32, colorOf(key, t));
        uniformY = -1;
      }
      if (Y != uniformY) {
        planes.numBY = hn::Set(d, numB * Y), planes.denBY = hn::Set(d, denB * Y);
        uniformY = Y;
      }
      const V X = hn::Iota(d, double(x0 + int(k)) + 0.5);
      hn::Store(hn::BitCast(du32, NarrowToFloat(df, EyeDepthAt(planes, X))), du32, depthOut);
      hn::Store(uniformFace, du32, faceOut);
      hn::Store(uniformTriangle, du32, triangleOut);
      if constexpr (kColor) hn::Store(uniformColor, du32, colorOut);
      covered += count;
    }
    streamRows(y);
  }
  return covered;
}

uint64_t ResolveTile(const TileJob& job, const TileScratch& s, FrameOutputs outputs, Rgba8 background, int rowBegin,
                     int rowEnd, Frame& frame) {
  switch (uint8_t(outputs)) {  // every set of flags a frame can ask for: depth always, the rest as asked
    case 0: return ResolveIdsT<0>(job, s, background, rowBegin, rowEnd, frame);
    case 1: return ResolveIdsT<1>(job, s, background, rowBegin, rowEnd, frame);
    case 2: return ResolveIdsT<2>(job, s, background, rowBegin, rowEnd, frame);
    case 3: return ResolveIdsT<3>(job, s, background, rowBegin, rowEnd, frame);
    case 4: return ResolveIdsT<4>(job, s, background, rowBegin, rowEnd, frame);
    case 5: return ResolveIdsT<5>(job, s, background, rowBegin, rowEnd, frame);
    case 6: return ResolveIdsT<6>(job, s, background, rowBegin, rowEnd, frame);
    default: return ResolveIdsT<7>(job, s, background, rowBegin, rowEnd, frame);
  }
  static_assert(uint8_t(FrameOutputs::All) == 7);
}

// resolveStoredDepth (tiled.hpp): the eye depth of each stored value, for tiles kept without ids.
uint64_t ResolveStoredDepth(const TileJob& job, const TileScratch& s, int rowBegin, int rowEnd, Frame& frame) {
  uint64_t covered = 0;
  visitDepthFormat(job.depth.format, [&]<DepthStorage S, DepthMapping M>() {
    covered = ResolveDepthT<S, M>(job, s, rowBegin, rowEnd, frame);
  });
  return covered;
}

void PrepareResolve(const TileJob& job, FrameOutputs outputs, Rgba8 background) {
  if (job.scratch->state != TileState::Pixels) return;  // uniform: resolved from its triangle
  if (has(outputs, FrameOutputs::Color)) PrepareResolveT<true>(job, *job.scratch, background);
  else PrepareResolveT<false>(job, *job.scratch, background);
}

// The exported entry: picks the compiled loop of the job's format and output.
void RasterizeTile(const TileJob& job) {
  visitDepthFormat(job.depth.format, [&]<DepthStorage S, DepthMapping M>() {
    if (job.ids) RasterizeTileT<S, M, true>(job);
    else RasterizeTileT<S, M, false>(job);
  });
}

// storeTile (tiled.hpp): the summary, then the values of the blocks held pixel by pixel, each in
// the format's 32 bits (keptStored inverts it), streamed: a block's 64 values are 4 whole lines.
template <DepthStorage S, DepthMapping M>
void StoreTileT(const TileScratch& from, KeptTile& to) {
  constexpr bool kGreater = GreaterWins(M);
  const D d;
  const size_t N = hn::Lanes(d);
  const hn::Rebind<int32_t, D> di32;
  const hn::Rebind<uint32_t, D> du32;
  const hn::Rebind<float, D> df;
  to.tileFar = from.tileFar;
  to.tileNear = from.tileNear;
  to.tileFarStale = from.tileFarStale;
  if (from.state == TileState::Pixels && from.tileFarStale) {
    // The farthest of the blocks' farthest values, once here rather than at every query of the
    // kept tile (anyFarther; the occlusion buffer's mesh culling asks thousands).
    V far = hn::Load(d, from.blockFar);
    for (size_t b = N; b < size_t(kBlocksPerTile); b += N) far = Farther<kGreater>(far, hn::Load(d, from.blockFar + b));
    to.tileFar = FarthestLane<kGreater>(far);
    to.tileFarStale = false;
  }
  to.resolved = from.resolved;
  to.state = from.state;
  to.plane = from.plane;
  to.planeKey = from.planeKey;
  if (from.state != TileState::Pixels) return;  // (the blocks' summaries are read in state Pixels only)
  auto stream = [](auto& dst, const auto& src) {  // an array of 64-bit values, whole lines
    static_assert(sizeof(dst) % 64 == 0);
    StreamCopy(reinterpret_cast<uint32_t*>(&dst), reinterpret_cast<const uint32_t*>(&src), sizeof(dst) / 4);
  };
  stream(to.blockFar, from.blockFar);
  stream(to.blockNear, from.blockNear);
  stream(to.blockKey, from.blockKey);
  stream(to.blockTriangle, from.blockTriangle);
  std::memcpy(to.blockClear, from.blockClear, sizeof(from.blockClear));
  HWY_ALIGN uint32_t block[kBlockSize * kBlockSize];  // staged, then streamed whole
  for (int b = 0; b < kBlocksPerTile; ++b) {
    if (from.blockKey[b] != 0 || from.blockClear[b]) continue;  // uniform: its pixel values are stale
    const double* first = from.depth + size_t(b / kBlocksX * kBlockSize * kTileSize + b % kBlocksX * kBlockSize);
    for (int y = 0; y < kBlockSize; ++y)
      for (size_t k = 0; k < size_t(kBlockSize); k += N) {
        const V v = hn::Load(d, first + size_t(y) * kTileSize + k);
        hn::Vec<decltype(du32)> bits;
        if constexpr (S == DepthStorage::F32) {
          bits = hn::BitCast(du32, NarrowToFloat(df, v));
        } else {  // an integer code below 2^32, through int32 (exact; outside the image: any bits)
          const auto offset = hn::DemoteTo(di32, hn::Sub(v, hn::Set(d, 2147483648.0)));
          bits = hn::Xor(hn::BitCast(du32, offset), hn::Set(du32, 0x80000000u));
        }
        hn::Store(bits, du32, block + size_t(y) * kBlockSize + k);
      }
    StreamCopy(to.depth + size_t(b) * kBlockSize * kBlockSize, block, size_t(kBlockSize) * kBlockSize);
  }
}

void StoreTile(const TileScratch& from, const DepthSetup& depth, KeptTile& to) {
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() { StoreTileT<S, M>(from, to); });
}

const char* KernelTarget() { return hwy::TargetName(HWY_TARGET); }

void FlushStreams() { hwy::FlushStream(); }

}  // namespace HWY_NAMESPACE
}  // namespace hsr::tiled
HWY_AFTER_NAMESPACE();

#endif  // per-target include guard

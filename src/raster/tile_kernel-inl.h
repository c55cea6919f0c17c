// The SIMD tile kernel of the tiled rasterizer, written once against Highway and compiled per
// instruction set by raster/tiled.cpp (foreach_target; one function exported, dispatched at run
// time). RasterizeTile() runs the triangles binned to one tile, in submission order, through
// the tile's depth and triangle buffers (TileScratch); it runs on whichever worker owns the tile.
//
// One vector holds up to 8 double lanes, one row of an 8x8 block (AVX-512: one vector per row,
// AVX2: two, SSE4: four, scalar: eight). Every lane repeats the reference's arithmetic exactly:
//  - coverage: the integer edge functions of raster/edge.hpp, exact in double (|E| < 2^50);
//  - depth: ((a*X + b*Y) + c) per plane, their quotient, mapDepth<M>, std::clamp and
//    quantizeDepth<S> — the same IEEE operations in the same order as zbuffer.cpp with
//    halfspace.hpp, never fused (no MulAdd here; tiled.cpp is built with -ffp-contract=off);
//  - depth test: strictly nearer wins, so ties keep the triangle drawn first.
// Hence stored values and winners are bit-identical to the scalar reference.

// Per-target include guard (Highway's pattern: this file is included once per target).
#if defined(HSR_RASTER_TILE_KERNEL_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef HSR_RASTER_TILE_KERNEL_INL_H_
#undef HSR_RASTER_TILE_KERNEL_INL_H_
#else
#define HSR_RASTER_TILE_KERNEL_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cstring>
#include <limits>

#include "core/depth_map.hpp"
#include "raster/edge.hpp"
#include "raster/tiled.hpp"

HWY_BEFORE_NAMESPACE();
namespace hsr::tiled {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, kBlockSize>;  // at most one block row per vector
using V = hn::Vec<D>;
using Mask = hn::Mask<D>;
using DU = hn::RebindToUnsigned<D>;           // triangle ids, same lane count and size

// "a is nearer than b" for the format's compare direction.
template <bool kGreater>
HWY_INLINE Mask Nearer(V a, V b) {
  if constexpr (kGreater) return hn::Gt(a, b);
  else return hn::Lt(a, b);
}

// mapDepth<M> (core/depth_map.hpp) lane by lane: same operations, same order, then std::clamp
// (v < 0 ? 0 : 1 < v ? 1 : v, which keeps NaN and -0 as they are).
template <DepthMapping M>
HWY_INLINE V MapDepth(V d, V n, V f, V fMinusN, bool ortho) {
  V v;
  if constexpr (M == DepthMapping::Z) {
    v = ortho ? hn::Div(hn::Sub(d, n), fMinusN) : hn::Div(hn::Mul(f, hn::Sub(d, n)), hn::Mul(fMinusN, d));
  } else if constexpr (M == DepthMapping::Reversed) {
    v = ortho ? hn::Div(hn::Sub(f, d), fMinusN) : hn::Div(hn::Mul(n, hn::Sub(f, d)), hn::Mul(fMinusN, d));
  } else if constexpr (M == DepthMapping::Inv) {
    v = hn::Div(n, d);
  } else {
    v = hn::Div(hn::Sub(d, n), fMinusN);
  }
  const D dd;
  const V zero = hn::Zero(dd), one = hn::Set(dd, 1.0);
  return hn::IfThenElse(hn::Lt(v, zero), zero, hn::IfThenElse(hn::Lt(one, v), one, v));
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

template <DepthStorage S, DepthMapping M, bool kIds>
void RasterizeTileT(const TileJob& job) {
  constexpr bool kGreater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  constexpr int kBlocksX = kTileSize / kBlockSize;
  const D d;
  const DU du;
  const size_t N = hn::Lanes(d);
  TileScratch& s = *job.scratch;
  RasterCounters count;  // added to the job's at the end
  uint64_t tests = 0, writes = 0;  // the hottest counts, plain locals so they stay in registers
  const Bins& bins = *job.bins;

  // The tile in the image: origin (x0, y0), w x h pixels (less at the right and bottom edges).
  const int x0 = (job.tile % bins.tilesX) * kTileSize, y0 = (job.tile / bins.tilesX) * kTileSize;
  const int w = std::min(kTileSize, bins.width - x0), h = std::min(kTileSize, bins.height - y0);

  // Clear: in-image cells to the format's clear value, the others to a value nearer than any
  // (they are never drawn — triangles are clipped to the image — and never the farthest).
  const double clear = double(quantizeDepth<S>(job.depth.format.clearValue()));
  const double nearest = kGreater ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  const V clearV = hn::Set(d, clear), nearestV = hn::Set(d, nearest), widthV = hn::Set(d, double(w));
  for (int y = 0; y < kTileSize; ++y)
    for (size_t k = 0; k < size_t(kTileSize); k += N) {
      const V v = y < h ? hn::IfThenElse(hn::Lt(hn::Iota(d, double(k)), widthV), clearV, nearestV) : nearestV;
      hn::Store(v, d, s.depth + size_t(y) * kTileSize + k);
      if constexpr (kIds) hn::Store(hn::Zero(du), du, s.triangle + size_t(y) * kTileSize + k);
    }
  for (int b = 0; b < kBlocksPerTile; ++b) {
    const bool inImage = (b % kBlocksX) * kBlockSize < w && (b / kBlocksX) * kBlockSize < h;
    s.blockFar[b] = inImage ? clear : nearest;
  }
  s.tileFar = clear;
  s.tileFarStale = false;

  const double n = job.depth.near, f = job.depth.far;
  const bool ortho = job.depth.orthographic;
  const V nV = hn::Set(d, n), fV = hn::Set(d, f), fMinusNV = hn::Set(d, f - n);
  const V lane = hn::Iota(d, 0.0);

  for (size_t chunk = 0; chunk < bins.chunkCount; ++chunk) {
    const ChunkBins& cb = bins.chunks[chunk];
    const SetupTriangle* tris = bins.triangles[chunk];
    for (uint32_t item = cb.start[size_t(job.tile)], end = cb.start[size_t(job.tile) + 1]; item < end; ++item) {
      const uint32_t ti = cb.items[item];
      const SetupTriangle& t = tris[ti];
      // Early rejection: the triangle's nearest possible value is not nearer than the farthest
      // value stored in the tile, so none of its fragments can win here.
      const double qNear = cb.nearest[ti];
      if (s.tileFarStale) {  // the farthest of the blocks' farthest values
        V far = nearestV;
        for (size_t b = 0; b < size_t(kBlocksPerTile); b += N) {
          const V v = hn::Load(d, s.blockFar + b);
          far = kGreater ? hn::Min(far, v) : hn::Max(far, v);
        }
        s.tileFar = hn::GetLane(kGreater ? hn::MinOfLanes(d, far) : hn::MaxOfLanes(d, far));
        s.tileFarStale = false;
      }
      if (!(kGreater ? qNear > s.tileFar : qNear < s.tileFar)) {
        ++count.culledTiles;
        continue;
      }

      // The triangle's pixel box within the tile, tile-local and inclusive.
      const int rx0 = std::max(t.minX - x0, 0), rx1 = std::min(t.maxX - x0, w - 1);
      const int ry0 = std::max(t.minY - y0, 0), ry1 = std::min(t.maxY - y0, h - 1);
      const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
      V laneE[3], biasV[3];
      for (int i = 0; i < 3; ++i) {
        laneE[i] = hn::Mul(lane, hn::Set(d, double(e[i].stepX())));  // lane j: j * stepX, exact
        biasV[i] = hn::Set(d, double(e[i].bias));
      }
      const V qNearV = hn::Set(d, qNear);
      const auto idV = hn::Set(du, triangleKey(chunk, ti));
      const V numA = hn::Set(d, t.depthNum.a), numC = hn::Set(d, t.depthNum.c);
      const V denA = hn::Set(d, t.depthDen.a), denC = hn::Set(d, t.depthDen.c);
      // A triangle parallel to the image plane has both planes constant (a = b = 0): a*X and
      // b*Y are zeros of a fixed sign, so every pixel computes the same bits as its first one.
      const bool constantDepth = t.depthNum.a == 0 && t.depthNum.b == 0 && t.depthDen.a == 0 && t.depthDen.b == 0;
      const V zConstant =
          constantDepth
              ? hn::Set(d, double(quantizeDepth<S>(mapDepth<M>(t.eyeDepth(x0 + rx0 + 0.5, y0 + ry0 + 0.5), n, f, ortho))))
              : hn::Zero(d);

      for (int by = ry0 / kBlockSize; by <= ry1 / kBlockSize; ++by)
        for (int bx = rx0 / kBlockSize; bx <= rx1 / kBlockSize; ++bx) {
          const int b = by * kBlocksX + bx;
          if (!(kGreater ? qNear > s.blockFar[b] : qNear < s.blockFar[b])) {
            if constexpr (kCountBlocks) ++count.blocksCulled;
            continue;
          }
          // The block's part of the box. Its four corner centres bound every edge function on
          // it: all outside one edge -> empty, all inside all edges -> full.
          const int cx0 = std::max(bx * kBlockSize, rx0), cx1 = std::min(bx * kBlockSize + kBlockSize - 1, rx1);
          const int cy0 = std::max(by * kBlockSize, ry0), cy1 = std::min(by * kBlockSize + kBlockSize - 1, ry1);
          bool full = true, empty = false;
          for (const Edge& edge : e) {
            int inside = 0;
            for (int c = 0; c < 4; ++c)
              inside += edge.at(centerFixed(x0 + (c & 1 ? cx1 : cx0)), centerFixed(y0 + (c & 2 ? cy1 : cy0))) >= edge.bias;
            empty |= inside == 0;
            full &= inside == 4;
          }
          if (empty) {
            if constexpr (kCountBlocks) ++count.blocksEmpty;
            continue;
          }
          if constexpr (kCountBlocks) ++(full ? count.blocksFull : count.blocksPartial);

          const int bxPixel = bx * kBlockSize;  // tile-local x of the block's first column
          const V colLo = hn::Set(d, double(cx0)), colHi = hn::Set(d, double(cx1));
          int64_t rowE[3];  // edge functions at the block's first column, current row
          for (int i = 0; i < 3; ++i) rowE[i] = e[i].at(centerFixed(x0 + bxPixel), centerFixed(y0 + cy0));
          // The block's farthest value after this triangle, gathered from the rows it visits.
          V far = nearestV;
          bool wrote = false;
          for (int y = cy0; y <= cy1; ++y) {
            const double Y = double(y0 + y) + 0.5;
            const V numRow = hn::Set(d, t.depthNum.b * Y), denRow = hn::Set(d, t.depthDen.b * Y);
            for (size_t k = 0; k < size_t(kBlockSize); k += N) {
              const size_t at = size_t(y) * kTileSize + size_t(bxPixel) + k;
              const V stored = hn::Load(d, s.depth + at);
              V result = stored;
              const V col = hn::Add(lane, hn::Set(d, double(bxPixel + int(k))));
              Mask cover = hn::And(hn::Ge(col, colLo), hn::Le(col, colHi));
              if (!full)
                for (int i = 0; i < 3; ++i) {
                  const V edgeV = hn::Add(hn::Set(d, double(rowE[i] + int64_t(k) * e[i].stepX())), laneE[i]);
                  cover = hn::And(cover, hn::Ge(edgeV, biasV[i]));
                }
              // Only pixels where something farther than the triangle's nearest value is stored
              // can change; the row is skipped when there are none.
              const Mask maybe = hn::And(cover, Nearer<kGreater>(qNearV, stored));
              if (!hn::AllFalse(d, maybe)) {
                // Pixel centres X = x + 0.5; depth = (a X + b Y + c) / (a' X + b' Y + c').
                V z = zConstant;
                if (!constantDepth) {
                  const V X = hn::Add(col, hn::Set(d, double(x0) + 0.5));
                  const V num = hn::Add(hn::Add(hn::Mul(numA, X), numRow), numC);
                  const V den = hn::Add(hn::Add(hn::Mul(denA, X), denRow), denC);
                  z = Quantize<S>(MapDepth<M>(hn::Div(num, den), nV, fV, fMinusNV, ortho));
                }
                const Mask win = hn::And(maybe, Nearer<kGreater>(z, stored));
                tests += hn::CountTrue(d, maybe);
                if (!hn::AllFalse(d, win)) {
                  writes += hn::CountTrue(d, win);
                  result = hn::IfThenElse(win, z, stored);
                  hn::Store(result, d, s.depth + at);
                  if constexpr (kIds) {
                    const auto old = hn::Load(du, s.triangle + at);
                    hn::Store(hn::IfThenElse(hn::RebindMask(du, win), idV, old), du, s.triangle + at);
                  }
                  wrote = true;
                }
              } else if (kCountBlocks && !hn::AllFalse(d, cover)) {
                ++count.rowsCulled;
              }
              far = kGreater ? hn::Min(far, result) : hn::Max(far, result);
            }
            for (int i = 0; i < 3; ++i) rowE[i] += e[i].stepY();
          }
          if (wrote) {
            // The block's rows outside the triangle's box kept their values.
            for (int y = by * kBlockSize; y < (by + 1) * kBlockSize; ++y) {
              if (y == cy0) y = cy1 + 1;
              if (y >= (by + 1) * kBlockSize) break;
              for (size_t k = 0; k < size_t(kBlockSize); k += N) {
                const V v = hn::Load(d, s.depth + size_t(y) * kTileSize + size_t(bxPixel) + k);
                far = kGreater ? hn::Min(far, v) : hn::Max(far, v);
              }
            }
            // The tile's farthest value can only move when the block that held it moved.
            s.tileFarStale |= s.blockFar[b] == s.tileFar;
            s.blockFar[b] = hn::GetLane(kGreater ? hn::MinOfLanes(d, far) : hn::MaxOfLanes(d, far));
          }
        }
    }
  }
  count.depthTests = tests;
  count.depthWrites = writes;
  job.counters->add(count);
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

// Stores the first `count` lanes of v at p.
template <class DT>
HWY_INLINE void StorePartial(hn::Vec<DT> v, DT dt, size_t count, hn::TFromD<DT>* p) {
  if (count == hn::Lanes(dt)) return hn::StoreU(v, dt, p);
  HWY_ALIGN hn::TFromD<DT> lanes[hn::MaxLanes(dt)];
  hn::Store(v, dt, lanes);
  std::copy(lanes, lanes + count, p);
}

// Depth only: the eye depth of every stored value that left the clear value (+inf elsewhere).
template <DepthStorage S, DepthMapping M>
uint64_t ResolveDepthT(const TileJob& job, const TileScratch& s, int x0, int y0, int w, int h, Frame& frame) {
  const D d;
  const hn::Rebind<float, D> df;
  const size_t N = hn::Lanes(d);
  const V clearV = hn::Set(d, double(quantizeDepth<S>(job.depth.format.clearValue())));
  const V infinity = hn::Set(d, std::numeric_limits<double>::infinity());
  uint64_t covered = 0;
  for (int y = 0; y < h; ++y)
    for (size_t k = 0; k < size_t(w); k += N) {
      const size_t count = std::min(N, size_t(w) - k);
      const V q = hn::Load(d, s.depth + size_t(y) * kTileSize + k);
      const Mask drawn = hn::And(hn::FirstN(d, count), hn::Ne(q, clearV));
      if (hn::AllFalse(d, drawn)) continue;
      covered += hn::CountTrue(d, drawn);
      const V eye = hn::IfThenElse(drawn, EyeDepthOfStored<S, M>(q, job.depth), infinity);
      StorePartial(hn::DemoteTo(df, eye), df, count, frame.depth.data() + frame.index(x0 + int(k), y0 + y));
    }
  return covered;
}

// Ids (and colour): face id, triangle id and the eye depth of the winning triangle's planes at
// the pixel centre, as the reference resolves it. A row of lanes won by one triangle is done
// with vectors (the same operations as SetupTriangle::eyeDepth), others pixel by pixel.
template <bool kColor>
uint64_t ResolveIdsT(const TileJob& job, const TileScratch& s, int x0, int y0, int w, int h, Frame& frame) {
  const D d;
  const DU du;
  const hn::Rebind<float, D> df;
  const hn::Rebind<int32_t, D> di;
  const hn::Rebind<uint32_t, D> du32;
  const size_t N = hn::Lanes(d);
  const Bins& bins = *job.bins;
  // Colour is shaded here, for winners only; neighbouring pixels mostly share their triangle.
  uint64_t lastKey = 0;
  Rgba8 lastColor{};
  [[maybe_unused]] auto colorOf = [&](uint64_t key, const SetupTriangle& t) {
    if (key != lastKey) {
      lastKey = key;
      lastColor = (*job.shader)(t.triangle);
    }
    return lastColor;
  };
  uint64_t covered = 0;
  for (int y = 0; y < h; ++y) {
    const double Y = double(y0 + y) + 0.5;
    for (size_t k = 0; k < size_t(w); k += N) {
      const uint64_t* ids = s.triangle + size_t(y) * kTileSize + k;
      const auto idV = hn::Load(du, ids);
      const size_t count = std::min(N, size_t(w) - k);
      if (hn::AllTrue(du, hn::Eq(idV, hn::Zero(du)))) continue;
      const size_t at = frame.index(x0 + int(k), y0 + y);
      if (count == N && ids[0] != 0 && hn::AllTrue(du, hn::Eq(idV, hn::Set(du, ids[0])))) {
        const SetupTriangle& t = bins.triangle(ids[0]);
        const V X = hn::Iota(d, double(x0 + int(k)) + 0.5);
        const V num = hn::Add(hn::Add(hn::Mul(hn::Set(d, t.depthNum.a), X), hn::Set(d, t.depthNum.b * Y)),
                              hn::Set(d, t.depthNum.c));
        const V den = hn::Add(hn::Add(hn::Mul(hn::Set(d, t.depthDen.a), X), hn::Set(d, t.depthDen.b * Y)),
                              hn::Set(d, t.depthDen.c));
        hn::StoreU(hn::DemoteTo(df, hn::Div(num, den)), df, frame.depth.data() + at);
        hn::StoreU(hn::Set(di, int32_t(t.face)), di, frame.faceId.data() + at);
        hn::StoreU(hn::Set(di, int32_t(t.triangle)), di, frame.triangleId.data() + at);
        if constexpr (kColor) {
          uint32_t rgba;
          const Rgba8 color = colorOf(ids[0], t);
          std::memcpy(&rgba, &color, sizeof rgba);
          hn::StoreU(hn::Set(du32, rgba), du32, reinterpret_cast<uint32_t*>(frame.color.data() + at));
        }
        covered += N;
        continue;
      }
      for (size_t j = 0; j < count; ++j) {
        if (!ids[j]) continue;
        const SetupTriangle& t = bins.triangle(ids[j]);
        frame.faceId[at + j] = int32_t(t.face);
        frame.triangleId[at + j] = int32_t(t.triangle);
        frame.depth[at + j] = float(t.eyeDepth(double(x0 + int(k + j)) + 0.5, Y));
        if constexpr (kColor) frame.color[at + j] = colorOf(ids[j], t);
        ++covered;
      }
    }
  }
  return covered;
}

uint64_t ResolveTile(const TileJob& job, const TileScratch& s, FrameOutputs outputs, Frame& frame) {
  const Bins& bins = *job.bins;
  const int x0 = (job.tile % bins.tilesX) * kTileSize, y0 = (job.tile / bins.tilesX) * kTileSize;
  const int w = std::min(kTileSize, bins.width - x0), h = std::min(kTileSize, bins.height - y0);
  if (outputs == FrameOutputs::All) return ResolveIdsT<true>(job, s, x0, y0, w, h, frame);
  if (outputs == FrameOutputs::IdsAndDepth) return ResolveIdsT<false>(job, s, x0, y0, w, h, frame);
  uint64_t covered = 0;
  visitDepthFormat(job.depth.format, [&]<DepthStorage S, DepthMapping M>() {
    covered = ResolveDepthT<S, M>(job, s, x0, y0, w, h, frame);
  });
  return covered;
}

// The exported entry: picks the compiled loop of the job's format and output.
void RasterizeTile(const TileJob& job) {
  visitDepthFormat(job.depth.format, [&]<DepthStorage S, DepthMapping M>() {
    if (job.ids) RasterizeTileT<S, M, true>(job);
    else RasterizeTileT<S, M, false>(job);
  });
}

const char* KernelTarget() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace hsr::tiled
HWY_AFTER_NAMESPACE();

#endif  // per-target include guard

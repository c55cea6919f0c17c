// The tiled rasterizer (see tiled.hpp): binning, the conservative nearest depth of each
// triangle, the per-tile resolve, and the run-time dispatch of the SIMD kernel, which Highway
// compiles here once per instruction set from raster/tile_kernel-inl.h. Called by the z-buffer
// (algorithms/zbuffer.cpp) and the benchmarks; every function runs on the caller's thread.
// Built with -ffp-contract=off (CMakeLists.txt), like all of hsr: no fused multiply-add may
// change a bit of the depth arithmetic that the kernel shares with the reference.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/tile_kernel-inl.h"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include "raster/tile_kernel-inl.h"

#if HWY_ONCE
#include <cmath>
#include <limits>

#include "core/depth_map.hpp"
#include "raster/edge.hpp"
#include "raster/tiled.hpp"

namespace hsr::tiled {

HWY_EXPORT(RasterizeTile);
HWY_EXPORT(ResolveTile);
HWY_EXPORT(KernelTarget);

size_t Bins::entries(int tile) const {
  size_t n = 0;
  for (size_t c = 0; c < chunkCount; ++c) n += chunks[c].start[size_t(tile) + 1] - chunks[c].start[size_t(tile)];
  return n;
}

uint64_t Bins::memoryBytes() const {
  uint64_t bytes = triangles.capacity() * sizeof(void*);
  for (const ChunkBins& c : chunks)
    bytes += (c.start.capacity() + c.items.capacity()) * sizeof(uint32_t) + c.nearest.capacity() * sizeof(double) +
             c.pairs.capacity() * sizeof(uint64_t) + sizeof(c);
  return bytes;
}

void RasterCounters::add(const RasterCounters& o) {
  depthTests += o.depthTests;
  depthWrites += o.depthWrites;
  culledTiles += o.culledTiles;
  blocksEmpty += o.blocksEmpty;
  blocksPartial += o.blocksPartial;
  blocksFull += o.blocksFull;
  blocksCulled += o.blocksCulled;
  rowsCulled += o.rowsCulled;
}

namespace {

// A stored value that no fragment of `t` can be nearer than, for storage S and mapping M.
//
// Every covered pixel centre lies in the snapped triangle, and eye depth num/den (both planes
// affine, den > 0) takes its extremes over it at the vertices; every mapping is monotone in eye
// depth (nearer = smaller d), and so are the clamp and the rounding. So the nearest value is
// the mapping of the smallest vertex depth — up to rounding, which is bounded and paid for
// with margins: each plane's evaluation errs by at most a few ulps of |a||x| + |b||y| + |c|
// (cancellation included), each mapping by a few ulps of its result. When those bounds are
// not small (den near 0, a plane much steeper than its values), there is no bound: the
// triangle is never rejected early.
template <DepthStorage S, DepthMapping M>
double nearestStored(const SetupTriangle& t, const DepthSetup& depth) {
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  constexpr double none = greater ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  constexpr double u = 0x1p-52;
  double px[3], py[3], maxX = 0, maxY = 0;
  for (int i = 0; i < 3; ++i) {
    px[i] = double(t.x[i]) / double(kSubpixelOne);
    py[i] = double(t.y[i]) / double(kSubpixelOne);
    maxX = std::max(maxX, std::abs(px[i]));
    maxY = std::max(maxY, std::abs(py[i]));
  }
  auto error = [&](const Plane& p) {  // absolute, of any evaluation over the triangle
    return 4 * u * (std::abs(p.a) * maxX + std::abs(p.b) * maxY + std::abs(p.c));
  };
  const double numErr = error(t.depthNum), denErr = error(t.depthDen);
  double num[3], den[3], numMin = std::numeric_limits<double>::infinity(), denMin = numMin;
  for (int i = 0; i < 3; ++i) {
    num[i] = t.depthNum.at(px[i], py[i]);
    den[i] = t.depthDen.at(px[i], py[i]);
    numMin = std::min(numMin, num[i]);
    denMin = std::min(denMin, den[i]);
  }
  const double numLo = numMin - numErr, denLo = denMin - denErr;
  if (!(numLo > 0 && denLo > 0)) return none;  // depth not bounded away from 0 (or NaN)
  // 2 (numErr / numLo + denErr / denLo), with one division: this runs for every triangle.
  const double relative = 2 * (numErr * denLo + denErr * numLo) / (numLo * denLo) + 1e-12;
  if (!(relative < 1e-3)) return none;
  // The vertex of smallest depth, compared without dividing (all terms positive); a wrong
  // choice between nearly equal ratios is far inside the margin.
  int nearest = 0;
  for (int i = 1; i < 3; ++i)
    if ((num[i] - numErr) * (den[nearest] + denErr) < (num[nearest] - numErr) * (den[i] + denErr)) nearest = i;
  const double dNear = (num[nearest] - numErr) / (den[nearest] + denErr) * (1 - relative);
  // Map, widen by the mapping's own rounding toward "nearer", and round as the storage does
  // (monotone, in double so that out-of-range values stay ordered).
  double v = mapDepth<M>(dNear, depth.near, depth.far, depth.orthographic);
  v = greater ? v * (1 + 1e-12) : v * (1 - 1e-12);
  if constexpr (S == DepthStorage::F32) return double(float(v));
  else return std::floor(v * kDepthScale<S> + 0.5);
}

// Appends (tile << 32 | index) for each tile triangle `index` may cover: the tiles its box
// overlaps, less those that one edge excludes (all four corner pixel centres of the box's part
// outside).
void binTriangle(const SetupTriangle& t, uint32_t index, int tilesX, std::vector<uint64_t>& pairs) {
  const int tx0 = t.minX / kTileSize, tx1 = t.maxX / kTileSize;
  const int ty0 = t.minY / kTileSize, ty1 = t.maxY / kTileSize;
  if (tx0 == tx1 && ty0 == ty1) {
    pairs.push_back(uint64_t(ty0 * tilesX + tx0) << 32 | index);
    return;
  }
  const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
  for (int ty = ty0; ty <= ty1; ++ty) {
    const int y0 = std::max<int>(ty * kTileSize, t.minY), y1 = std::min<int>(ty * kTileSize + kTileSize - 1, t.maxY);
    for (int tx = tx0; tx <= tx1; ++tx) {
      const int x0 = std::max<int>(tx * kTileSize, t.minX), x1 = std::min<int>(tx * kTileSize + kTileSize - 1, t.maxX);
      bool outside = false;
      for (const Edge& edge : e) {
        bool anyInside = false;
        for (int c = 0; c < 4; ++c)
          anyInside |= edge.at(centerFixed(c & 1 ? x1 : x0), centerFixed(c & 2 ? y1 : y0)) >= edge.bias;
        outside |= !anyInside;
      }
      if (!outside) pairs.push_back(uint64_t(ty * tilesX + tx) << 32 | index);
    }
  }
}

}  // namespace

void prepareBins(Bins& bins, int width, int height, size_t chunkCount) {
  bins.width = width;
  bins.height = height;
  bins.tilesX = (width + kTileSize - 1) / kTileSize;
  bins.tilesY = (height + kTileSize - 1) / kTileSize;
  bins.chunkCount = chunkCount;
  if (bins.chunks.size() < chunkCount) bins.chunks.resize(chunkCount);
  bins.triangles.assign(chunkCount, nullptr);
}

void binChunk(Bins& bins, size_t chunk, const std::vector<SetupTriangle>& tris, const DepthSetup& depth) {
  ChunkBins& cb = bins.chunks[chunk];
  bins.triangles[chunk] = tris.data();
  const size_t n = tris.size(), tiles = size_t(bins.tileCount());
  cb.nearest.resize(n);
  cb.pairs.clear();
  // One pass while the chunk is in cache: nearest bounds and (tile, triangle) pairs.
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    for (size_t i = 0; i < n; ++i) {
      cb.nearest[i] = nearestStored<S, M>(tris[i], depth);
      binTriangle(tris[i], uint32_t(i), bins.tilesX, cb.pairs);
    }
  });
  // Counting sort by tile, stable: each tile's triangles stay in submission order.
  cb.start.assign(tiles + 1, 0);
  for (uint64_t p : cb.pairs) ++cb.start[(p >> 32) + 1];
  for (size_t t = 0; t < tiles; ++t) cb.start[t + 1] += cb.start[t];
  cb.items.resize(cb.pairs.size());
  for (uint64_t p : cb.pairs) cb.items[cb.start[p >> 32]++] = uint32_t(p);
  for (size_t t = tiles; t > 0; --t) cb.start[t] = cb.start[t - 1];  // back to the beginnings
  cb.start[0] = 0;
}

void rasterizeTile(const Bins& bins, int tile, const DepthSetup& depth, bool ids, TileScratch& scratch,
                   RasterCounters& counters) {
  const TileJob job{&bins, tile, depth, ids, &scratch, &counters, nullptr};
  HWY_DYNAMIC_DISPATCH(RasterizeTile)(job);
}

uint64_t resolveTile(const Bins& bins, int tile, const DepthSetup& depth, FrameOutputs outputs,
                     const TriangleShader* shader, const TileScratch& scratch, Frame& frame) {
  const TileJob job{&bins, tile, depth, outputs != FrameOutputs::DepthOnly, nullptr, nullptr, shader};
  return HWY_DYNAMIC_DISPATCH(ResolveTile)(job, scratch, outputs, frame);
}

const char* kernelTarget() { return HWY_DYNAMIC_DISPATCH(KernelTarget)(); }

}  // namespace hsr::tiled
#endif  // HWY_ONCE

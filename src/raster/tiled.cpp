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
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include "core/depth_map.hpp"
#include "raster/fragment_depth.hpp"
#include "raster/edge.hpp"
#include "raster/tiled.hpp"

namespace hsr::tiled {

HWY_EXPORT(RasterizeTile);
HWY_EXPORT(ResolveTile);
HWY_EXPORT(PrepareResolve);
HWY_EXPORT(KernelTarget);
HWY_EXPORT(FlushStreams);
HWY_EXPORT(StoreTile);
HWY_EXPORT(DrainPump);

void Bins::countEntries() {
  const size_t tiles = size_t(tileCount());
  tileEntries.assign(3 * tiles, 0);
  tileChunkStart.assign(tiles + 1, 0);
  for (size_t c = 0; c < chunkCount; ++c)
    for (uint32_t t : chunks[c].touched) {
      tileEntries[t] += chunks[c].start[t + 1] - chunks[c].start[t];
      tileEntries[tiles + t] += late[c].start[t + 1] - late[c].start[t];
      tileEntries[2 * tiles + t] += clusters[c].start[t + 1] - clusters[c].start[t];
      ++tileChunkStart[t + 1];
    }
  for (size_t t = 0; t < tiles; ++t) tileChunkStart[t + 1] += tileChunkStart[t];
  tileChunks.resize(tileChunkStart[tiles]);
  for (size_t c = 0; c < chunkCount; ++c)
    for (uint32_t t : chunks[c].touched) tileChunks[tileChunkStart[t]++] = uint32_t(c);
  for (size_t t = tiles; t > 0; --t) tileChunkStart[t] = tileChunkStart[t - 1];  // back to the beginnings
  tileChunkStart[0] = 0;
}

size_t Bins::entries(int tile, bool inLate) const {
  if (!tileEntries.empty()) {
    const size_t tiles = size_t(tileCount());
    return inLate ? tileEntries[tiles + size_t(tile)] + tileEntries[2 * tiles + size_t(tile)] : tileEntries[size_t(tile)];
  }
  size_t n = 0;
  for (const std::vector<ChunkBins>* set : {inLate ? &late : &chunks, inLate ? &clusters : nullptr})
    if (set)
      for (size_t c = 0; c < chunkCount; ++c) n += (*set)[c].start[size_t(tile) + 1] - (*set)[c].start[size_t(tile)];
  return n;
}

uint64_t Bins::culled() const {
  uint64_t n = 0;
  for (size_t c = 0; c < chunkCount; ++c) n += chunks[c].culled;
  return n;
}

uint64_t Bins::memoryBytes() const {
  uint64_t bytes = records.capacity() * sizeof(void*) +
                   (tileEntries.capacity() + tileChunkStart.capacity() + tileChunks.capacity()) * sizeof(uint32_t);
  for (const std::vector<ChunkBins>* set : {&chunks, &late, &clusters})
    for (const ChunkBins& c : *set)
      bytes += (c.start.capacity() + c.items.capacity()) * sizeof(uint32_t) + c.pairs.capacity() * sizeof(uint64_t) +
               (c.itemNearest.capacity() + c.cover.capacity() + c.slotNearest.capacity()) * sizeof(double) +
               c.slotBox.capacity() * sizeof(ChunkBins::Box) +
               (c.itemBox.capacity() + c.touched.capacity() + c.area.capacity()) * sizeof(uint32_t) +
               c.touchedBits.capacity() * sizeof(uint64_t) + c.records.capacity() * sizeof(SetupTriangle) +
               c.setUpCapacity + c.survivors.capacity() + sizeof(c);
  return bytes;
}

void RasterCounters::add(const RasterCounters& o) {
  depthTests += o.depthTests;
  depthWrites += o.depthWrites;
  culledTiles += o.culledTiles;
  setUpLate += o.setUpLate;
  blocksEmpty += o.blocksEmpty;
  blocksPartial += o.blocksPartial;
  blocksFull += o.blocksFull;
  blocksCulled += o.blocksCulled;
  tilesWhole += o.tilesWhole;
  blocksWhole += o.blocksWhole;
}

namespace {

// Appends (tile << 32 | index) for each tile triangle `index` may cover: the tiles its box
// overlaps, less those that one edge excludes (all four corner pixel centres of the box's part
// outside: the edge function is linear, so it is enough that the corner where it is largest is).
// With kCull (binChunk's cull), tiles whose covering bound in `cover` is strictly nearer than
// `nearest` (in the direction `greater`) are left out and counted in `culled`. Adds the pixels of
// the box's part in each tile it is appended to to that tile's `area` (ChunkBins::area).
template <bool kCull>
HWY_INLINE void binTriangle(const SetupTriangle& t, uint32_t index, int tilesX, std::vector<uint64_t>& pairs,
                            uint32_t* area, const double* cover = nullptr, double nearest = 0, bool greater = false,
                            uint64_t* culled = nullptr) {
  const int tx0 = t.minX / kTileSize, tx1 = t.maxX / kTileSize;
  const int ty0 = t.minY / kTileSize, ty1 = t.maxY / kTileSize;
  auto hidden = [&](int tile) {
    if constexpr (!kCull) return false;
    const double c = cover[tile];
    const bool behind = greater ? c > nearest : c < nearest;
    *culled += behind;
    return behind;
  };
  if (tx0 == tx1 && ty0 == ty1) {
    if (!hidden(ty0 * tilesX + tx0)) {
      pairs.push_back(uint64_t(ty0 * tilesX + tx0) << 32 | index);
      area[ty0 * tilesX + tx0] += uint32_t(t.maxX - t.minX + 1) * uint32_t(t.maxY - t.minY + 1);
    }
    return;
  }
  const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
  for (int ty = ty0; ty <= ty1; ++ty) {
    const int y0 = std::max<int>(ty * kTileSize, t.minY), y1 = std::min<int>(ty * kTileSize + kTileSize - 1, t.maxY);
    // Per edge, dx (py - ay) at the row where E is largest (the lower one when dx > 0).
    int64_t rowTerm[3];
    for (int i = 0; i < 3; ++i) rowTerm[i] = e[i].dx * (centerFixed(e[i].dx > 0 ? y1 : y0) - e[i].ay);
    const uint64_t rowKey = uint64_t(ty * tilesX) << 32 | index;
    for (int tx = tx0; tx <= tx1; ++tx) {
      // Each edge at the tile's column where E is largest (the right one when dy < 0): a few
      // multiplications, not narrowTilesToEdge's 64-bit divisions (the same tiles; its test
      // checks it against this per-tile evaluation).
      const int left = std::max<int>(tx * kTileSize, t.minX), right = std::min<int>(tx * kTileSize + kTileSize - 1, t.maxX);
      bool touches = true;
      for (int i = 0; i < 3; ++i)
        touches &= rowTerm[i] - e[i].dy * (centerFixed(e[i].dy < 0 ? right : left) - e[i].ax) >= e[i].bias;
      if (touches && !hidden(ty * tilesX + tx)) {
        pairs.push_back(rowKey + (uint64_t(tx) << 32));
        area[ty * tilesX + tx] += uint32_t(right - left + 1) * uint32_t(y1 - y0 + 1);
      }
    }
  }
}

// Whether the circle inscribed in triangle t (radius 2 area / perimeter, in subpixel units) is
// narrower than `radius`. (Coordinates below 2^24 in magnitude: no square overflows, so
// std::hypot's costly care is not needed.)
bool inscribedCircleBelow(const SetupTriangle& t, double radius) {
  const double ux = double(t.x[1]) - t.x[0], uy = double(t.y[1]) - t.y[0];
  const double vx = double(t.x[2]) - t.x[0], vy = double(t.y[2]) - t.y[0];
  const double wx = double(t.x[2]) - t.x[1], wy = double(t.y[2]) - t.y[1];
  const double twiceArea = std::abs(ux * vy - vx * uy);
  const double perimeter = std::sqrt(ux * ux + uy * uy) + std::sqrt(vx * vx + vy * vy) + std::sqrt(wx * wx + wy * wy);
  return twiceArea < radius * perimeter;
}

// Per tile, the nearest of the farthest bounds of the chunk's triangles that cover all of the
// tile's pixel centres in the image (each edge's function at its smallest corner is inside; along
// a row of tiles that corner moves monotonically, so the covered tiles are an interval of the
// row). Only triangles whose box can hold a whole tile are looked at. Returns whether any tile
// got a bound.
template <DepthStorage S, DepthMapping M>
bool coverBounds(const SetupTriangles& tris, const DepthSetup& depth, int width, int height, int tilesX,
                 std::vector<double>& cover) {
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  bool any = false;
  const int side = std::min({kTileSize, width, height});
  // A triangle that covers a side x side square of pixel centres holds its inscribed circle, of
  // radius (side - 1) / 2 pixels: a triangle whose own inscribed circle is smaller covers no
  // such tile. (Most triangles with a box that large fail this test cheaply; see
  // docs/benchmarks.md for what the whole function costs.)
  const double minRadius = (side - 1) * 0.5 * double(kSubpixelOne) * (1 - 1e-9);  // (a margin for rounding)
  for (const SetupTriangle& t : tris) {
    if (std::min(t.maxX - t.minX, t.maxY - t.minY) + 1 < side || inscribedCircleBelow(t, minRadius)) continue;
    const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
    double far = 0;
    bool farKnown = false;  // computed for the first tile covered
    for (int ty = (t.minY + kTileSize - 1) / kTileSize; ty * kTileSize <= t.maxY; ++ty) {
      const int y0 = ty * kTileSize, y1 = std::min(y0 + kTileSize, height) - 1;
      if (y1 > t.maxY) break;
      // The tiles of the row inside the box, whose every pixel centre in the image is inside
      // the edges (a tile spans columns tx T .. min(tx T + T - 1, width - 1)).
      int lastInBox = t.maxX / kTileSize;
      if (std::min(lastInBox * kTileSize + kTileSize, width) - 1 > t.maxX) --lastInBox;
      int first = (t.minX + kTileSize - 1) / kTileSize, last = lastInBox;
      for (const Edge& edge : e) narrowTilesToEdge(edge, true, kTileSize, 0, width - 1, y0, y1, first, last);
      if (first > last) continue;
      if (!farKnown) {
        double px[3], py[3];
        for (int i = 0; i < 3; ++i) {
          px[i] = double(t.x[i]) / double(kSubpixelOne);
          py[i] = double(t.y[i]) / double(kSubpixelOne);
        }
        const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, depth.orthographic);
        far = storedRange<S, M>(m, px, py, 3).farthest;  // "none" (farthest possible) culls nothing
        farKnown = true;
      }
      for (int tx = first; tx <= last; ++tx) {
        double& c = cover[size_t(ty * tilesX + tx)];
        if (greater ? far > c : far < c) c = far;
      }
      any = true;
    }
  }
  return any;
}

}  // namespace

void prepareBins(Bins& bins, int width, int height, size_t chunkCount) {
  bins.width = width;
  bins.height = height;
  bins.tilesX = (width + kTileSize - 1) / kTileSize;
  bins.tilesY = (height + kTileSize - 1) / kTileSize;
  bins.chunkCount = chunkCount;
  if (bins.chunks.size() < chunkCount) bins.chunks.resize(chunkCount);
  if (bins.late.size() < chunkCount) bins.late.resize(chunkCount);
  if (bins.clusters.size() < chunkCount) bins.clusters.resize(chunkCount);
  bins.records.assign(2 * chunkCount, nullptr);
  bins.projected = nullptr;
  bins.camera = nullptr;
  bins.sceneTriangles = nullptr;
  bins.tileEntries.clear();
  bins.tileChunkStart.clear();  // (until countEntries: every chunk is walked)
  bins.tileChunks.clear();
}

namespace {

// Sorts cb.pairs (tile << 32 | name: a localKey, or the index of a deferred face or cluster) by
// tile into cb.start/items/itemNearest (a counting sort, stable: each tile's items stay in
// submission order), each item itemOf(name) with its nearest bound nearestOf(localIndex(name)),
// and placed(item, tile, name) called for each. Marks the tiles with items in `touched` (bit t).
template <class ItemOf, class NearestOf, class Placed>
void sortPairs(ChunkBins& cb, size_t tiles, ItemOf&& itemOf, NearestOf&& nearestOf, Placed&& placed,
               uint64_t* touched) {
  cb.start.assign(tiles + 1, 0);
  // Run by run of pairs in one tile (neighbouring triangles mostly share theirs): a counter
  // incremented pair by pair in memory made each increment wait for the one before.
  const uint64_t* pairs = cb.pairs.data();
  const size_t n = cb.pairs.size();
  if (n == 0) {  // (most chunks' deferred lists; two passes over the tiles' starts saved)
    cb.items.clear();
    cb.itemNearest.clear();
    return;
  }
  auto runEnd = [&](size_t i) {
    const uint64_t tile = pairs[i] >> 32;
    size_t j = i + 1;
    while (j < n && pairs[j] >> 32 == tile) ++j;
    return j;
  };
  for (size_t i = 0, j; i < n; i = j) {
    j = runEnd(i);
    const uint64_t tile = pairs[i] >> 32;
    cb.start[tile + 1] += uint32_t(j - i);
    touched[tile / 64] |= uint64_t(1) << (tile % 64);
  }
  for (size_t t = 0; t < tiles; ++t) cb.start[t + 1] += cb.start[t];
  cb.items.resize(n);
  cb.itemNearest.resize(n);
  uint32_t* const items = cb.items.data();
  double* const itemNearest = cb.itemNearest.data();
  for (size_t i = 0, j; i < n; i = j) {
    j = runEnd(i);
    const uint32_t tile = uint32_t(pairs[i] >> 32);
    // (The run's first place in a local: stored through items, which may alias cb.start, it
    // would be read again for every item.)
    const uint32_t at = cb.start[tile];
    cb.start[tile] = at + uint32_t(j - i);
    for (size_t k = i; k < j; ++k) {
      const uint32_t place = at + uint32_t(k - i);
      items[place] = itemOf(uint32_t(pairs[k]));
      // Next to the item: the tile pass reads them in order.
      itemNearest[place] = nearestOf(localIndex(uint32_t(pairs[k])));
      placed(place, tile, uint32_t(pairs[k]));
    }
  }
  for (size_t t = tiles; t > 0; --t) cb.start[t] = cb.start[t - 1];  // back to the beginnings
  cb.start[0] = 0;
}

}  // namespace

void binChunk(Bins& bins, size_t chunk, const FrontEndChunk& triangles, const DepthSetup* cullFor) {
  ChunkBins& cb = bins.chunks[chunk];
  const SetupTriangles& tris = triangles.triangles;
  if (triangles.nearest.size() != tris.size())
    throw std::logic_error("binChunk: the chunk has no nearest bounds (runFrontEnd without nearestFor)");
  bins.records[2 * chunk] = tris.data();
  const size_t n = tris.size(), tiles = size_t(bins.tileCount());
  const uint32_t firstTriangle = triangles.firstTriangle;
  cb.pairs.clear();
  cb.culled = 0;
  bool cull = false;
  const bool greater = cullFor && cullFor->format.greaterWins();
  static_assert(kLargeBoxPixels == kTileSize, "the front end counts the triangles that can cover a tile");
  if (cullFor && (triangles.counters.large > 0 || bins.width < kTileSize || bins.height < kTileSize)) {
    cb.cover.assign(tiles, greater ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity());
    visitDepthFormat(cullFor->format, [&]<DepthStorage S, DepthMapping M>() {
      cull = coverBounds<S, M>(tris, *cullFor, bins.width, bins.height, bins.tilesX, cb.cover);
    });
  }
  const double* nearest = triangles.nearest.data();
  // The tiles with items of the chunk in any of the three sets (bit t), for cb.touched.
  cb.touchedBits.assign((tiles + 63) / 64, 0);
  const auto nothing = [](uint32_t, uint32_t, uint32_t) {};
  cb.area.assign(tiles, 0);
  uint32_t* area = cb.area.data();
  for (size_t i = 0; i < n; ++i) {
    const uint32_t local = localKey(tris[i].triangle - firstTriangle, false, uint32_t(i));
    if (cull)
      binTriangle<true>(tris[i], local, bins.tilesX, cb.pairs, area, cb.cover.data(), nearest[i], greater, &cb.culled);
    else binTriangle<false>(tris[i], local, bins.tilesX, cb.pairs, area);
  }
  const auto same = [](uint32_t item) { return item; };
  sortPairs(cb, tiles, same, [&](uint32_t i) { return nearest[i]; }, nothing, cb.touchedBits.data());

  // The deferred back faces, each in its one tile: a counting sort by tile (stable).
  ChunkBins& late = bins.late[chunk];
  const std::vector<DeferredFace>& faces = triangles.deferred;
  const size_t m = faces.size();
  late.culled = 0;
  late.faces = faces.data();
  const std::vector<DeferredCluster>& clusters = triangles.clusters;
  late.records.reserve(m + clusters.size() * kClusterTriangles);  // (slots for the clusters' triangles)
  bins.records[2 * chunk + 1] = late.records.data();
  late.pairs.clear();
  for (size_t i = 0; i < m; ++i) {
    const DeferredFace& f = faces[i];
    const uint32_t tile = uint32_t(f.minY / kTileSize) * uint32_t(bins.tilesX) + uint32_t(f.minX / kTileSize);
    late.pairs.push_back(uint64_t(tile) << 32 | i);
  }
  late.itemBox.resize(m);
  sortPairs(
      late, tiles, [&](uint32_t i) { return localKey(faces[i].triangle - firstTriangle, true, i); },
      [&](uint32_t i) { return faces[i].nearest; },
      [&](uint32_t item, uint32_t, uint32_t i) {  // the face's box in its tile
        const DeferredFace& f = faces[i];
        const uint32_t x0 = uint32_t(f.minX % kTileSize), y0 = uint32_t(f.minY % kTileSize);
        late.itemBox[item] = x0 | y0 << 8 | uint32_t(x0 + f.maxX - f.minX) << 16 | uint32_t(y0 + f.maxY - f.minY) << 24;
      },
      cb.touchedBits.data());

  // The deferred clusters, in every tile their box overlaps (a counting sort by tile, stable).
  ChunkBins& cl = bins.clusters[chunk];
  const size_t k = clusters.size();
  cl.clusterList = clusters.data();
  cl.firstTriangle = firstTriangle;
  cl.firstSlot = uint32_t(m);
  if (cl.setUpCapacity < k) {
    cl.setUp.reset(new std::atomic<uint8_t>[k]);
    cl.setUpCapacity = k;
  }
  for (size_t i = 0; i < k; ++i) cl.setUp[i].store(0, std::memory_order_relaxed);
  cl.survivors.assign(k, 0);
  cl.slotNearest.resize(m + k * kClusterTriangles);
  cl.slotBox.resize(m + k * kClusterTriangles);
  cl.pairs.clear();
  for (size_t i = 0; i < k; ++i) {
    const DeferredCluster& d = clusters[i];
    for (int ty = d.minY / kTileSize; ty <= d.maxY / kTileSize; ++ty)
      for (int tx = d.minX / kTileSize; tx <= d.maxX / kTileSize; ++tx)
        cl.pairs.push_back(uint64_t(ty * bins.tilesX + tx) << 32 | i);
  }
  cl.itemBox.resize(cl.pairs.size());
  sortPairs(
      cl, tiles, same, [&](uint32_t i) { return clusters[i].nearest; },
      [&](uint32_t item, uint32_t t, uint32_t i) {  // the part of the cluster's box in tile t
        const DeferredCluster& d = clusters[i];
        const int tx0 = int(t % uint32_t(bins.tilesX)) * kTileSize, ty0 = int(t / uint32_t(bins.tilesX)) * kTileSize;
        const uint32_t x0 = uint32_t(std::max(d.minX - tx0, 0)), y0 = uint32_t(std::max(d.minY - ty0, 0));
        const uint32_t x1 = uint32_t(std::min(d.maxX - tx0, kTileSize - 1)), y1 = uint32_t(std::min(d.maxY - ty0, kTileSize - 1));
        cl.itemBox[item] = x0 | y0 << 8 | x1 << 16 | y1 << 24;
      },
      cb.touchedBits.data());
  cb.touched.clear();
  for (size_t w = 0; w < cb.touchedBits.size(); ++w)
    for (uint64_t bits = cb.touchedBits[w]; bits; bits &= bits - 1)
      cb.touched.push_back(uint32_t(w * 64 + size_t(__builtin_ctzll(bits))));
}

uint64_t TileOrder::memoryBytes() const {
  return (entries.capacity() + ordered.capacity() + late.capacity()) * sizeof(TileEntry) + bucket.capacity();
}

namespace {

// Eye depth as 1 / (alpha + beta stored) — a perspective camera's z, reversed and inv mappings
// map 1 / eye depth affinely — or, when `eye` is false (orthographic or linear: the stored value
// is already affine in eye depth), the stored value itself.
struct OrderKey {
  bool eye = false;
  double alpha = 0, beta = 0;
  // (One expression for the extremes and every entry: rounding keeps it monotonic in `stored`,
  // so every entry's key lies between the extremes' keys.)
  double eyeOf(double stored) const { return 1 / (alpha + beta * stored); }
};

OrderKey orderKeyOf(const DepthSetup& depth) {
  OrderKey k;
  const DepthMapping mapping = depth.format.mapping;
  if (depth.orthographic || mapping == DepthMapping::Linear) return k;
  const double n = depth.near, f = depth.far;
  const double scale = depthScaleOf(depth.format.storage);
  k.eye = true;
  if (mapping == DepthMapping::Z) k.alpha = 1 / n, k.beta = -(f - n) / (f * n) / scale;  // unmapDepth<Z>
  else if (mapping == DepthMapping::Reversed) k.alpha = 1 / f, k.beta = (f - n) / (n * f) / scale;
  else k.alpha = 0, k.beta = 1 / (n * scale);  // inv
  return k;
}

}  // namespace

const std::vector<TileEntry>& orderTile(const Bins& bins, int tile, const DepthSetup& depth, TileOrder& order) {
  std::vector<TileEntry>& in = order.entries;
  std::vector<TileEntry>& out = order.ordered;
  in.resize(bins.entries(tile));  // (grows to the fullest tile met: no allocation once warm)
  TileEntry* entry = in.data();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool finite = true;
  uint64_t area = 0;
  bins.forChunksOf(tile, [&](size_t c) {
    const ChunkBins& cb = bins.chunks[c];
    const uint64_t chunkKey = triangleKey(c, 0);  // + localKey
    area += cb.area[size_t(tile)];
    for (uint32_t item = cb.start[size_t(tile)], end = cb.start[size_t(tile) + 1]; item < end; ++item) {
      const double v = cb.itemNearest[item];
      *entry++ = {chunkKey + cb.items[item], v};
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      finite &= v - v == 0;  // false for infinities and NaN
    }
  });
  if (in.size() < 2 || !finite || !(hi > lo) || !std::isfinite(hi - lo)) return in;  // (unsorted: any order is right)
  // Many small triangles (a dense mesh's, like the sphere's: about 1,000 a tile, boxes of 2 to 4
  // pixels), left in submission order (see kUnsortedArea): sorting them costs more than the
  // culling it buys (see docs/benchmarks.md).
  if (in.size() >= kUnsortedEntries && area <= kUnsortedArea) return in;
  // Counting sort into buckets of equal width in eye depth between the extreme bounds, nearest
  // bucket first. (Equal widths in the stored value put most of a perspective scene in a bucket
  // or two: the z, reversed and inv mappings crowd the distance together; see
  // docs/benchmarks.md.) When the tile's farthest
  // bound is less than 1.25 times as far as its nearest, the stored value is nearly affine in
  // eye depth over that range, and the buckets stay in it: no division per triangle (the
  // sphere's tiles, 1000 triangles each at about one distance).
  constexpr int kBuckets = kOrderBuckets;
  static_assert(kBuckets <= 256, "a bucket's index is a byte");
  OrderKey key = orderKeyOf(depth);
  double keyLo = lo, keyHi = hi;  // (the key is monotonic in the stored value)
  if (key.eye) {
    const double eyeLo = key.eyeOf(lo), eyeHi = key.eyeOf(hi);
    keyLo = std::min(eyeLo, eyeHi), keyHi = std::max(eyeLo, eyeHi);
    if (!(keyLo > 0) || !std::isfinite(keyHi) || !(keyHi > 1.25 * keyLo)) key.eye = false, keyLo = lo, keyHi = hi;
  }
  // rank = (k - origin) * sign in [0, kBuckets): nearest first (the smallest eye depth, or the
  // nearest stored value).
  const bool nearerIsLarger = !key.eye && depth.format.greaterWins();
  const double scale = (kBuckets - 0.5) / (keyHi - keyLo), origin = nearerIsLarger ? keyHi : keyLo;
  const double sign = nearerIsLarger ? -scale : scale;
  uint32_t start[kBuckets + 1] = {};
  order.bucket.resize(in.size());
  uint8_t* bucket = order.bucket.data();
  const size_t count = in.size();
  if (key.eye) {
    for (size_t i = 0; i < count; ++i) bucket[i] = uint8_t((key.eyeOf(in[i].nearest) - origin) * sign);
  } else {
    for (size_t i = 0; i < count; ++i) bucket[i] = uint8_t((in[i].nearest - origin) * sign);
  }
  for (size_t i = 0; i < count; ++i) ++start[bucket[i] + 1];
  for (int b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
  out.resize(count);
  for (size_t i = 0; i < count; ++i) out[start[bucket[i]]++] = in[i];
  return out;
}

namespace {

// Sets up deferred cluster k of chunk c, once: the first worker to get here does it, a worker
// that finds it under way waits (the set-up of kClusterTriangles triangles: microseconds). The
// records (same bits as the front end's) go to the chunk's late RecordRoom; they carry no colour
// (frontFacing false: the resolve shades them, triangleColor — the same colour).
void setUpCluster(const Bins& bins, size_t c, size_t k, const DepthSetup& depth, RasterCounters& counters) {
  const ChunkBins& cl = bins.clusters[c];
  std::atomic<uint8_t>& state = cl.setUp[k];
  uint8_t expected = 0;
  if (state.load(std::memory_order_acquire) == 2) return;
  if (!state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
    while (state.load(std::memory_order_acquire) != 2) std::this_thread::yield();
    return;
  }
  const RecordRoom& records = bins.late[c].records;
  const uint32_t slot = cl.clusterSlot(k);
  SetupTriangle* out = records.room(slot);
  prefetchForWriting(out, kClusterTriangles);  // (while the cluster's triangles are read and set up)
  uint32_t vertex[3][kClusterTriangles], tri[kClusterTriangles], face[kClusterTriangles];
  const uint32_t first = cl.clusterList[k].cluster * uint32_t(kClusterTriangles);
  for (uint32_t i = 0; i < kClusterTriangles; ++i) {
    const Triangle& t = bins.sceneTriangles[first + i];
    for (int v = 0; v < 3; ++v) vertex[v][i] = t.v[v];
    tri[i] = first + i;
    face[i] = t.face;
  }
  FrontEndCounters ignored;
  const uint32_t* v[3] = {vertex[0], vertex[1], vertex[2]};
  // Set up straight into the slots (the survivors in order, from `slot` on).
  const size_t n = setupBatch(bins.projected, v, tri, face, kClusterTriangles, *bins.camera, Cull::None, ignored, out,
                              {.depth = &depth, .nearest = cl.slotNearest.data() + slot});
  for (size_t i = 0; i < n; ++i) {
    out[i].frontFacing = false, out[i].color = Rgba8{};
    cl.slotBox[slot + i] = {out[i].minX, out[i].minY, out[i].maxX, out[i].maxY};
  }
  cl.survivors[k] = uint8_t(n);
  counters.setUpLate += n;
  state.store(2, std::memory_order_release);
}

// The deferred back faces and clusters binned to `tile` that may change it, as rasterizeTile's
// Front pass left it in `s`: set up (their records in Bins::late) and listed in order.late. A face
// or a cluster is hidden when every block its box touches holds nothing farther than its nearest
// bound (Beaten, with the kernel's tie rule) — by the block's farthest value, or else by the
// stored values of the box's part of the block; so is each triangle of a cluster that is not;
// hidden ones are counted as culled triangle-tile pairs (a hidden cluster as all its triangles).
void selectLate(const Bins& bins, int tile, const DepthSetup& depth, bool ids, const TileScratch& s, TileOrder& order,
                RasterCounters& counters) {
  constexpr int kBlocksX = kTileSize / kBlockSize;
  const bool greater = depth.format.greaterWins();
  auto beaten = [&](double nearest, double far) {
    return ids ? (greater ? far > nearest : far < nearest) : !(greater ? nearest > far : nearest < far);
  };
  const double uniformFar = s.tileFar;  // a Clear or Plane tile: its farthest value, for every block
  // Whether nothing nearer than `nearest` can show in the tile-local box [x0, x1] x [y0, y1].
  auto hidden = [&](double nearest, int x0, int y0, int x1, int y1) {
    if (s.state != TileState::Pixels) return beaten(nearest, uniformFar);
    if (beaten(nearest, s.tileFar)) return true;  // (behind the farthest value of the tile: of every block)
    for (int by = y0 / kBlockSize; by <= y1 / kBlockSize; ++by)
      for (int bx = x0 / kBlockSize; bx <= x1 / kBlockSize; ++bx) {
        const int b = by * kBlocksX + bx;
        if (beaten(nearest, s.blockFar[b])) continue;
        // Not behind the block's farthest value: behind every stored value of the box's part of
        // the block? (A block held pixel by pixel only: not blockKey or blockClear. Near a
        // silhouette the box often reaches only the drawn part of a block with background.)
        if (s.blockKey[b] || s.blockClear[b]) return false;
        const int cx0 = std::max(x0, bx * kBlockSize), cx1 = std::min(x1, bx * kBlockSize + kBlockSize - 1);
        const int cy0 = std::max(y0, by * kBlockSize), cy1 = std::min(y1, by * kBlockSize + kBlockSize - 1);
        for (int y = cy0; y <= cy1; ++y) {
          const double* row = s.depth + size_t(y) * kTileSize;
          bool all = true;
          for (int x = cx0; x <= cx1; ++x) all &= beaten(nearest, row[x]);
          if (!all) return false;
        }
      }
    return true;
  };
  auto boxHidden = [&](double nearest, uint32_t box) {
    return hidden(nearest, int(box & 0xff), int(box >> 8 & 0xff), int(box >> 16 & 0xff), int(box >> 24));
  };
  order.late.clear();
  constexpr size_t kBatch = 64;
  uint32_t vertex[3][kBatch], tri[kBatch], face[kBatch], index[kBatch];
  size_t batched = 0, batchChunk = 0;
  SetupTriangle out[kBatch];
  FrontEndCounters ignored;
  if (!(bins.projected && bins.camera && bins.sceneTriangles))
    throw std::logic_error("rasterizeTile: deferred triangles, but Bins::projected, camera or sceneTriangles is not set");
  auto flush = [&] {
    const uint32_t* v[3] = {vertex[0], vertex[1], vertex[2]};
    const size_t n = setupBatch(bins.projected, v, tri, face, batched, *bins.camera, Cull::None, ignored, out);
    if (n != batched) throw std::logic_error("rasterizeTile: a deferred back face did not set up again");
    const RecordRoom& records = bins.late[batchChunk].records;
    for (size_t i = 0; i < n; ++i) records.set(index[i], out[i]);  // (colour: shaded at resolve, as a back face)
    counters.setUpLate += n;
    batched = 0;
  };
  // (Each set is a walk over the lists of the chunks with items here: skipped when countEntries
  // says the set is empty here.)
  const size_t tiles = size_t(bins.tileCount());
  const bool anyFaces = bins.tileEntries.empty() || bins.tileEntries[tiles + size_t(tile)] > 0;
  const bool anyClusters = bins.tileEntries.empty() || bins.tileEntries[2 * tiles + size_t(tile)] > 0;
  if (anyFaces)
    bins.forChunksOf(tile, [&](size_t c) {
      const ChunkBins& cb = bins.late[c];
      for (uint32_t item = cb.start[size_t(tile)], end = cb.start[size_t(tile) + 1]; item < end; ++item) {
        const double nearest = cb.itemNearest[item];
        if (boxHidden(nearest, cb.itemBox[item])) {
          ++counters.culledTiles;
          continue;
        }
        const uint32_t local = cb.items[item], i = localIndex(local);
        const DeferredFace& f = cb.faces[i];
        if (batched && (c != batchChunk || batched == kBatch)) flush();
        batchChunk = c;
        for (int k = 0; k < 3; ++k) vertex[k][batched] = f.v[k];
        tri[batched] = f.triangle;
        face[batched] = f.face;
        index[batched++] = i;
        order.late.push_back({triangleKey(c, local), nearest});
      }
    });
  if (batched) flush();
  const int tx0 = (tile % bins.tilesX) * kTileSize, ty0 = (tile / bins.tilesX) * kTileSize;
  if (anyClusters)
    bins.forChunksOf(tile, [&](size_t c) {
      const ChunkBins& cl = bins.clusters[c];
      const uint32_t firstTriangle = cl.firstTriangle;
      for (uint32_t item = cl.start[size_t(tile)], end = cl.start[size_t(tile) + 1]; item < end; ++item) {
        if (boxHidden(cl.itemNearest[item], cl.itemBox[item])) {
          counters.culledTiles += kClusterTriangles;
          continue;
        }
        const size_t k = cl.items[item];
        setUpCluster(bins, c, k, depth, counters);
        const SetupTriangle* records = bins.late[c].records.data();
        for (uint32_t slot = cl.clusterSlot(k), last = slot + cl.survivors[k]; slot < last; ++slot) {
          const ChunkBins::Box& box = cl.slotBox[slot];
          const int x0 = std::max(box.minX - tx0, 0), x1 = std::min(box.maxX - tx0, kTileSize - 1);
          const int y0 = std::max(box.minY - ty0, 0), y1 = std::min(box.maxY - ty0, kTileSize - 1);
          if (x0 > x1 || y0 > y1) continue;  // (not in this tile)
          if (hidden(cl.slotNearest[slot], x0, y0, x1, y1)) {
            ++counters.culledTiles;
            continue;
          }
          const uint32_t triangle = records[slot].triangle;
          order.late.push_back({triangleKey(c, localKey(triangle - firstTriangle, true, slot)), cl.slotNearest[slot]});
        }
      }
    });
}

}  // namespace

void rasterizeTile(const Bins& bins, int tile, const DepthSetup& depth, bool ids, TileScratch& scratch,
                   TileOrder& order, RasterCounters& counters, bool keep, BackgroundPump* pump) {
  const bool late = bins.entries(tile, true) > 0;
  TileJob job{&bins, tile, depth, ids, &scratch, &counters, nullptr, &order, late ? TileJob::Pass::Front : TileJob::Pass::Whole, keep, pump};
  HWY_DYNAMIC_DISPATCH(RasterizeTile)(job);
  if (!late) return;
  selectLate(bins, tile, depth, ids, scratch, order, counters);
  if (order.late.empty()) return;
  job.pass = TileJob::Pass::Late;
  HWY_DYNAMIC_DISPATCH(RasterizeTile)(job);
}

void prepareResolve(const Bins& bins, int tile, FrameOutputs outputs, const TriangleShader* shader, Rgba8 background,
                    TileScratch& scratch, BackgroundPump* pump) {
  TileJob job{&bins, tile, DepthSetup{}, true, &scratch, nullptr, shader, nullptr};  // (depth: not read)
  job.pump = pump;
  HWY_DYNAMIC_DISPATCH(PrepareResolve)(job, outputs, background);
}

uint64_t resolveTile(const Bins& bins, int tile, const DepthSetup& depth, FrameOutputs outputs,
                     const TriangleShader* shader, Rgba8 background, const TileScratch& scratch, Frame& frame,
                     int rowBegin, int rowEnd) {
  const TileJob job{&bins, tile, depth, outputs != FrameOutputs::DepthOnly, nullptr, nullptr, shader, nullptr};
  return HWY_DYNAMIC_DISPATCH(ResolveTile)(job, scratch, outputs, background, rowBegin, rowEnd, frame);
}

namespace {

template <DepthMapping M>
MappedPlanes planesOf(const SetupTriangle& t, const DepthSetup& depth) {
  return mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, depth.orthographic);
}

// The stored value of plane m at image pixel (x, y), as the kernel computes it.
template <DepthStorage S>
double planeStored(const MappedPlanes& m, int x, int y) {
  const double Y = double(y) + 0.5;
  return fragmentStored<S>(m, double(x) + 0.5, m.p.b * Y, m.q.b * Y);
}

// Calls fn(stored value) for the tile-local pixels [x0, x1] x [y0, y1] of one 8x8 block (or of
// any part of a tile in state Clear or Plane), until it returns true; returns whether it did. The
// planes are mapped once, not per pixel.
template <DepthStorage S, DepthMapping M, class Fn>
bool anyStoredIn(const KeptTile& s, const DepthSetup& depth, int tx0, int ty0, int x0, int y0, int x1, int y1,
                 Fn&& fn) {
  constexpr int kBlocksX = kTileSize / kBlockSize;
  const int block = (y0 / kBlockSize) * kBlocksX + x0 / kBlockSize;  // (state Pixels: the only one)
  const SetupTriangle* plane = s.state == TileState::Plane                            ? s.plane
                               : s.state == TileState::Pixels && s.blockKey[block] ? s.blockTriangle[block]
                                                                                    : nullptr;
  const bool cleared = s.state == TileState::Clear || (s.state == TileState::Pixels && s.blockClear[block]);
  const double clear = double(quantizeDepth<S>(depth.format.clearValue()));
  const MappedPlanes m = plane ? planesOf<M>(*plane, depth) : MappedPlanes{};
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double v = plane     ? planeStored<S>(m, tx0 + x, ty0 + y)
                       : cleared ? clear
                                 : keptStored<S>(s.depth[KeptTile::at(x, y)]);
      if (fn(v)) return true;
    }
  return false;
}

template <DepthStorage S, DepthMapping M>
bool anyFartherT(const KeptTile& s, const DepthSetup& depth, int tx0, int ty0, int x0, int y0, int x1, int y1,
                 double q) {
  constexpr int kBlocksX = kTileSize / kBlockSize;
  // Bounds: every stored value is nearer than or equal to the farthest bound (the tile's, or
  // the farthest of its blocks' while it is stale), and farther than or equal to the nearest.
  if (s.state == TileState::Clear) return storedNearer<M>(q, double(quantizeDepth<S>(depth.format.clearValue())));
  double far = s.tileFar;
  if (s.state == TileState::Pixels && s.tileFarStale)
    for (int b = 0; b < kBlocksPerTile; ++b)
      if (b == 0 || storedNearer<M>(far, s.blockFar[b])) far = s.blockFar[b];
  if (!storedNearer<M>(q, far)) return false;
  if (storedNearer<M>(q, s.tileNear)) return true;
  auto anyPixel = [&](int px0, int py0, int px1, int py1) {
    return anyStoredIn<S, M>(s, depth, tx0, ty0, px0, py0, px1, py1,
                             [&](double v) { return storedNearer<M>(q, v); });
  };
  if (s.state == TileState::Plane) return anyPixel(x0, y0, x1, y1);
  for (int by = y0 / kBlockSize; by <= y1 / kBlockSize; ++by)
    for (int bx = x0 / kBlockSize; bx <= x1 / kBlockSize; ++bx) {
      const int b = by * kBlocksX + bx;
      if (!storedNearer<M>(q, s.blockFar[b])) continue;
      if (storedNearer<M>(q, s.blockNear[b])) return true;
      if (anyPixel(std::max(x0, bx * kBlockSize), std::max(y0, by * kBlockSize),
                   std::min(x1, bx * kBlockSize + kBlockSize - 1), std::min(y1, by * kBlockSize + kBlockSize - 1)))
        return true;
    }
  return false;
}

}  // namespace

double storedAt(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x, int y) {
  double v = 0;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    anyStoredIn<S, M>(kept, depth, (tile % bins.tilesX) * kTileSize, (tile / bins.tilesX) * kTileSize, x, y, x, y,
                      [&](double stored) {
                        v = stored;
                        return true;
                      });
  });
  return v;
}

bool anyFarther(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x0, int y0,
                int x1, int y1, double stored) {
  bool any = false;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    any = anyFartherT<S, M>(kept, depth, (tile % bins.tilesX) * kTileSize, (tile / bins.tilesX) * kTileSize, x0,
                            y0, x1, y1, stored);
  });
  return any;
}

const char* kernelTarget() { return HWY_DYNAMIC_DISPATCH(KernelTarget)(); }

void finishResolves() { HWY_DYNAMIC_DISPATCH(FlushStreams)(); }
void drainBackground(BackgroundPump& pump) { HWY_DYNAMIC_DISPATCH(DrainPump)(pump); }

bool BackgroundPump::setPiece(uint32_t* start, size_t count, uint32_t fill) {
  constexpr size_t kLine = stream::HWY_NAMESPACE::kLineValues;
  const size_t head = std::min(count, (kLine - reinterpret_cast<uintptr_t>(start) / sizeof(uint32_t) % kLine) % kLine);
  const size_t whole = (count - head) / kLine;
  std::fill(start, start + head, fill);
  std::fill(start + head + whole * kLine, start + count, fill);
  dst = start + head;
  lines = uint32_t(whole);
  value = fill;
  return whole > 0;
}

void storeTile(const TileScratch& from, const DepthSetup& depth, KeptTile& to) {
  HWY_DYNAMIC_DISPATCH(StoreTile)(from, depth, to);
}

void loadTile(const KeptTile& from, const DepthSetup& depth, TileScratch& to) {
  static_cast<TileSummary&>(to) = from;
  if (from.state != TileState::Pixels) return;
  constexpr int kBlocksX = kTileSize / kBlockSize;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    for (int b = 0; b < kBlocksPerTile; ++b) {
      if (from.blockKey[b] != 0 || from.blockClear[b]) continue;  // uniform: storeTile kept no values
      const int bx = b % kBlocksX * kBlockSize, by = b / kBlocksX * kBlockSize;
      for (int y = by; y < by + kBlockSize; ++y)
        for (int x = bx; x < bx + kBlockSize; ++x)
          to.depth[size_t(y) * kTileSize + size_t(x)] = keptStored<S>(from.depth[KeptTile::at(x, y)]);
    }
  });
}

}  // namespace hsr::tiled
#endif  // HWY_ONCE

// Binning (tiled.hpp): prepareBins sizes a frame's bins; binChunk sorts one front-end chunk's
// set-up triangles, deferred back faces and deferred clusters into per-tile lists (Bins) for the
// tile pass, culling pairs behind a triangle of the chunk that covers the tile. Plain code; binChunk
// runs on the worker that set the chunk up (runFrontEnd's consumer); chunks share no output.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/depth_map.hpp"
#include "raster/tiled.hpp"
#include "setup/edge.hpp"
#include "setup/fixed_point.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr::tiled {

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

namespace {

// Appends (tile << 32 | index) for each tile triangle `index` may cover: the tiles its box
// overlaps, less those that one edge excludes (all four corner pixel centres of the box's part
// outside: the edge function is linear, so it is enough that the corner where it is largest is).
// With kCull (binChunk's cull), tiles whose covering bound in `cover` is strictly nearer than
// `nearest` (in the direction `greater`) are left out and counted in `culled`. Adds the pixels of
// the box's part in each tile it is appended to to that tile's `area` (ChunkBins::area).
template <bool kCull>
[[gnu::always_inline]] inline void binTriangle(const SetupTriangle& t, uint32_t index, int tilesX, std::vector<uint64_t>& pairs,
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
        far = triangleStoredRange<S, M>(t, depth).farthest;  // "none" (farthest possible) culls nothing
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
        const TileBox b = boxInTile(d.minX, d.minY, d.maxX, d.maxY, tx0, ty0);
        cl.itemBox[item] = uint32_t(b.x0) | uint32_t(b.y0) << 8 | uint32_t(b.x1) << 16 | uint32_t(b.y1) << 24;
      },
      cb.touchedBits.data());
  cb.touched.clear();
  for (size_t w = 0; w < cb.touchedBits.size(); ++w)
    for (uint64_t bits = cb.touchedBits[w]; bits; bits &= bits - 1)
      cb.touched.push_back(uint32_t(w * 64 + size_t(__builtin_ctzll(bits))));
}

}  // namespace hsr::tiled

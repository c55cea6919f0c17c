// The tile pass's plain code around the SIMD kernel, run on the worker that owns the tile: the
// order its triangles are drawn in (orderTile, called by the kernel as it starts the tile), the
// deferred faces and clusters that may still show after the Front pass (selectLate, called by
// rasterizeTile in tiled.cpp; a cluster is set up once, by the first worker to need it), counters.
#include "raster/tile_pass.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/depth_map.hpp"
#include "frontend/triangle_setup.hpp"

namespace hsr::tiled {

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

// The order of a tile's triangles (orderTile).

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

// The late pass's triangles: deferred back faces and clusters that may show (selectLate).

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

}  // namespace

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
          const TileBox b = boxInTile(box.minX, box.minY, box.maxX, box.maxY, tx0, ty0);
          if (b.x0 > b.x1 || b.y0 > b.y1) continue;  // (not in this tile)
          if (hidden(cl.slotNearest[slot], b.x0, b.y0, b.x1, b.y1)) {
            ++counters.culledTiles;
            continue;
          }
          const uint32_t triangle = records[slot].triangle;
          order.late.push_back({triangleKey(c, localKey(triangle - firstTriangle, true, slot)), cl.slotNearest[slot]});
        }
      }
    });
}

}  // namespace hsr::tiled

// The tiled (sort-middle) rasterizer behind the default z-buffer: prepareBins()/binChunk() sort
// set-up triangles into per-tile lists in submission order, chunk by chunk (each chunk by the
// worker that set it up; binning.cpp); rasterizeTile() runs every triangle of one tile, in
// orderTile's order (tile_pass.cpp), through the SIMD kernel (tile_kernel-inl.h, compiled and
// dispatched in tiled.cpp) into a worker's tile-sized depth and triangle buffers, then the
// deferred triangles that may show (tile_pass.cpp); resolveTile() writes (rows of) that tile into
// the Frame; kept tiles answer depth queries (kept_tiles.cpp). Plain functions without threads: the
// z-buffer (algorithms/zbuffer.cpp) calls them via parallelFor, one owner per tile, so no locks;
// per-tile counters are summed in tile order. Back faces lying in one tile, and whole clusters of
// triangles facing away from the eye, can be deferred: drawn after the tile's other triangles,
// and only if they may still show (binChunk).
//
// Exactness: the kernel evaluates coverage with the same integer edge functions and depth with
// the same double operations in the same order as the reference (raster/halfspace.hpp +
// setup/fragment_depth.hpp + zbuffer.cpp), so face ids and stored depths are bit-identical to
// it for any thread count and instruction set.
//
// Uniform states ("lossless z-buffer compression", the Ukrainian paper): a tile starts cleared without
// touching its buffers, and a triangle covering all of it in front of everything stored there
// makes it that triangle's plane in O(1) (TileState); likewise an 8x8 block for a triangle
// parallel to the image plane (TileScratch::blockKey), and each block of a plane tile that a
// triangle then covers only in part: the tile's blocks keep the plane, with bounds from its
// corners, until something lands on them — as a cleared tile's blocks stay cleared
// (TileScratch::blockClear). Values are computed from the plane, bit for bit as
// the kernel would have stored them, when a triangle covers part of a block or at resolve.
//
// Early rejection (the base for a hierarchical z-buffer): each tile and each 8x8 block keeps
// conservative farthest and nearest stored values; a triangle whose conservative nearest value
// (FrontEndChunk::nearest, computed in set-up) is not nearer than the farthest is skipped for the tile, the block, or
// (counted only) a SIMD row. Statistics it defines: depth_tests = fragments whose depth was
// computed and compared, plus the pixels of whole-tile/block replacements (rejected ones are
// not); culled_occlusion = triangle-tile pairs skipped whole; depth_writes = fragments that won
// (each tile's triangles are visited nearest first, see orderTile, so far fewer are tested and
// written than in submission order when a scene is drawn back to front).
#pragma once
#include <hsr/frame.hpp>
#include <hsr/options.hpp>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <memory>
#include <new>
#include <vector>

#include "scene/shading.hpp"
#include "frontend/chunks.hpp"
#include "frontend/vertices.hpp"
#include "setup/fragment_depth.hpp"
#include "setup/setup_triangle.hpp"

// Block counters of the kernel (RasterCounters::blocks*), on unless built with
// -DHSR_RASTER_COUNTERS=0.
#ifndef HSR_RASTER_COUNTERS
#define HSR_RASTER_COUNTERS 1
#endif

namespace hsr::tiled {

struct BackgroundPump;  // (below: streamed background written between the kernel's own work)

inline constexpr bool kCountBlocks = HSR_RASTER_COUNTERS;

/// Tile edge in pixels (a multiple of kBlockSize). 32 and 64 perform alike, 128 is slower on
/// dense meshes (see docs/benchmarks.md); 64 has fewer tiles to manage.
inline constexpr int kTileSize = 64;
/// The kernel's block: classified empty/partial/full by its corners, one SIMD row per line.
inline constexpr int kBlockSize = 8;
inline constexpr int kBlocksPerTile = (kTileSize / kBlockSize) * (kTileSize / kBlockSize);

static_assert(kDeferTile == kTileSize, "a deferred back face lies in one tile");

/// The part of pixel box [minX, maxX] x [minY, maxY] (image pixels) in the tile whose first pixel
/// is (tx0, ty0), in tile-local pixels: empty (x0 > x1 or y0 > y1) when they do not meet.
struct TileBox {
  int x0, y0, x1, y1;
};
inline TileBox boxInTile(int minX, int minY, int maxX, int maxY, int tx0, int ty0) {
  return {std::max(minX - tx0, 0), std::max(minY - ty0, 0), std::min(maxX - tx0, kTileSize - 1),
          std::min(maxY - ty0, kTileSize - 1)};
}

/// Room for set-up records that are written one by one, later, and only some of them (the
/// deferred back faces that may show): allocated without being written, so that a first frame
/// does not clear ~100 bytes per deferred face. Grows, never shrinks; keeps nothing when it grows.
class RecordRoom {
 public:
  void reserve(size_t count) {
    if (count <= capacity_) return;
    bytes_.reset(new unsigned char[count * sizeof(SetupTriangle)]);  // (new[]: aligned for any scalar)
    capacity_ = count;
  }
  size_t capacity() const { return capacity_; }
  /// Writes record i (starts its lifetime); i < capacity().
  void set(size_t i, const SetupTriangle& t) const { new (bytes_.get() + i * sizeof(SetupTriangle)) SetupTriangle(t); }
  /// Records [i, ...) to be written in place, as setupBatch writes its output (an aggregate of
  /// plain values: writing every field makes the record); i < capacity().
  SetupTriangle* room(size_t i) const {
    return std::launder(reinterpret_cast<SetupTriangle*>(bytes_.get() + i * sizeof(SetupTriangle)));
  }
  /// The records, of which those set() or written through room() may be read.
  const SetupTriangle* data() const { return std::launder(reinterpret_cast<const SetupTriangle*>(bytes_.get())); }

 private:
  std::unique_ptr<unsigned char[]> bytes_;
  size_t capacity_ = 0;
};

/// The bins of one front-end chunk (FrontEndChunk): its triangles grouped by tile, in
/// submission order within a tile. Reused across frames.
struct ChunkBins {
  std::vector<uint32_t> start;  // tileCount + 1 offsets: items[start[t], start[t + 1]) are tile t's
  std::vector<uint32_t> items;  // localKey of each triangle
  std::vector<double> itemNearest;  // per item: its triangle's nearest bound (FrontEndChunk::nearest)
  std::vector<uint64_t> pairs;  // scratch of binChunk(): tile << 32 | localKey, in submission order
                                // (Bins::late, clusters: | the face's or cluster's index)
  std::vector<double> cover;    // scratch of binChunk(): per tile, the bound of its covering triangles
  // Bins::chunks only: per tile, the pixels of the boxes of the chunk's triangles binned there,
  // each box cut to the tile (orderTile).
  std::vector<uint32_t> area;
  uint64_t culled = 0;          // triangle-tile pairs not binned: behind a triangle covering the tile
  // Bins::chunks only: the part of the parallel job (core/parallel.hpp) whose thread set the chunk
  // up and binned it (its records are in that core's caches; set by the caller of binChunk).
  uint32_t producer = 0;
  // Bins::chunks only: the tiles that have items of this chunk in any of the three sets (chunks,
  // late, clusters), in order (binChunk), for countEntries' per-tile chunk lists.
  std::vector<uint32_t> touched;
  std::vector<uint64_t> touchedBits;  // scratch of binChunk(): bit t, tile t is in `touched`
  // Bins::late only: per item, the face's pixel box in its tile (x0, y0, x1, y1: a byte each,
  // tile-local), next to the item for the tile pass's test; the chunk's deferred back faces
  // (FrontEndChunk::deferred) and their records, written by rasterizeTile when one may show (only
  // the worker that owns its one tile does).
  std::vector<uint32_t> itemBox;
  const DeferredFace* faces = nullptr;
  RecordRoom records;
  // Bins::clusters only: the chunk's deferred clusters (FrontEndChunk::clusters; items name
  // them by index, itemBox is the box's part in the tile). A cluster is set up once, by the
  // first tile pass worker that finds it may show in its tile (setUp: 0 not yet, 1 under way,
  // 2 done): its surviving triangles' records go to Bins::late's RecordRoom, slots
  // clusterSlot(k) on, with their nearest bounds in slotNearest, and their number in survivors.
  const DeferredCluster* clusterList = nullptr;
  uint32_t firstTriangle = 0;  // the chunk's first scene triangle (FrontEndChunk::firstTriangle)
  uint32_t firstSlot = 0;  // the chunk's deferred faces come first in the RecordRoom
  std::unique_ptr<std::atomic<uint8_t>[]> setUp;
  size_t setUpCapacity = 0;
  mutable std::vector<uint8_t> survivors;  // (written by the worker that sets the cluster up)
  mutable std::vector<double> slotNearest;
  struct Box {
    int16_t minX, minY, maxX, maxY;  // SetupTriangle's
  };
  mutable std::vector<Box> slotBox;  // per slot, its record's pixel box (the tiles' test reads 8 bytes, not the record)
  uint32_t clusterSlot(size_t k) const { return firstSlot + uint32_t(k * kClusterTriangles); }
};

/// Per-tile triangle lists of a frame: chunk by chunk, so that each chunk is binned by the worker
/// that set it up (runFrontEnd's consumer); read in chunk order, a tile's lists are one list in
/// submission order. A triangle is named by (chunk, localKey); the tile buffers store
/// `triangleKey` of the winner.
struct Bins {
  int width = 0, height = 0, tilesX = 0, tilesY = 0;
  size_t chunkCount = 0;
  std::vector<ChunkBins> chunks;  // [0, chunkCount) in use
  // [0, chunkCount) in use: each chunk's deferred back faces, in their tiles (FrontEndChunk::deferred)
  std::vector<ChunkBins> late;
  // [0, chunkCount) in use: each chunk's deferred clusters, in every tile their box overlaps
  std::vector<ChunkBins> clusters;
  std::vector<const SetupTriangle*> records;  // per chunk, two: its set-up triangles, its late records
  // Per chunk, two, as `records`: the records the resolve reads each winner from, when not the
  // ones drawn (empty: those). A frame drawn on priority keys is resolved from the triangles' own
  // planes, ids and colours (algorithms/zbuffer_tiled.cpp, TiledZBuffer::drawInOrder).
  std::vector<const SetupTriangle*> resolveRecords;
  // For setting deferred back faces up again: runFrontEnd's vertices and camera (see binChunk).
  const ProjectedVertex* projected = nullptr;
  const Camera* camera = nullptr;
  const Triangle* sceneTriangles = nullptr;  // (for the deferred clusters' vertices)

  // countEntries(): per tile, its items in chunks, late and clusters (all chunks); empty until then.
  std::vector<uint32_t> tileEntries;
  // countEntries(): per tile, the chunks that have items there (in any set), in chunk order:
  // tileChunks[tileChunkStart[t], tileChunkStart[t + 1]). (A tile's lists are read through these,
  // not by a walk over every chunk.)
  std::vector<uint32_t> tileChunkStart, tileChunks;
  /// Calls f(chunk) for every chunk that may have items in `tile`, in chunk order: those
  /// countEntries() listed, or every chunk before it has run.
  template <class F>
  void forChunksOf(int tile, F&& f) const {
    if (tileChunkStart.empty()) {
      for (size_t c = 0; c < chunkCount; ++c) f(c);
      return;
    }
    for (uint32_t i = tileChunkStart[size_t(tile)], end = tileChunkStart[size_t(tile) + 1]; i < end; ++i)
      f(size_t(tileChunks[i]));
  }

  int tileCount() const { return tilesX * tilesY; }
  /// Items of `tile` in `chunks` (or in `late` and `clusters`): a sum over the chunks, or a look-up
  /// once countEntries() has run (after the last binChunk, before the tile pass).
  size_t entries(int tile, bool inLate = false) const;
  void countEntries();
  uint64_t culled() const;  // pairs binChunk left out (ChunkBins::culled), over all chunks
  uint64_t memoryBytes() const;
  /// The record of triangle `key` as drawn, and as resolved (resolveRecords).
  const SetupTriangle& triangle(uint64_t key) const { return recordOf(records, key); }
  const SetupTriangle& resolved(uint64_t key) const {
    return recordOf(resolveRecords.empty() ? records : resolveRecords, key);
  }

 private:
  static const SetupTriangle& recordOf(const std::vector<const SetupTriangle*>& from, uint64_t key);
};

/// A triangle's name within its chunk, in 28 bits that order it as submitted: its scene
/// triangle's index in the chunk (12 bits), whether it was deferred (1 bit: its record is then
/// in Bins::late), and its index among the chunk's records, or its slot in Bins::late's
/// RecordRoom (15 bits: the pieces of a clipped triangle, at most 7 per triangle, keep their
/// order; a deferred face's slot is its index among the deferred faces, a deferred cluster's
/// triangles' come after those, ChunkBins::clusterSlot).
inline constexpr int kLocalIndexBits = 15;
static_assert(kChunkTriangles <= (1u << 12) && 7 * kChunkTriangles < (1u << kLocalIndexBits));
static_assert(2 * kChunkTriangles <= (1u << kLocalIndexBits), "a chunk's deferred faces and clusters' slots");
inline uint32_t localKey(uint32_t triangleInChunk, bool deferred, uint32_t index) {
  return triangleInChunk << 16 | uint32_t(deferred) << kLocalIndexBits | index;
}
/// The index part of a localKey: into the chunk's records, or its deferred faces.
inline uint32_t localIndex(uint32_t local) { return local & ((1u << kLocalIndexBits) - 1); }
/// Names a triangle of chunk `chunk` in a tile buffer (0 = nothing drawn): keys compare in
/// submission order.
inline uint64_t triangleKey(size_t chunk, uint32_t local) { return (uint64_t(chunk) << 28 | local) + 1; }
inline const SetupTriangle& Bins::recordOf(const std::vector<const SetupTriangle*>& from, uint64_t key) {
  const uint64_t k = key - 1;
  const uint32_t local = uint32_t(k) & ((1u << 28) - 1);
  return from[size_t(k >> 28) * 2 + (local >> kLocalIndexBits & 1)][localIndex(local)];
}

/// Counts of the tile pass. depth_tests/writes of the statistics come from here.
struct RasterCounters {
  uint64_t depthTests = 0;    // fragments whose depth was computed and compared with the buffer
  uint64_t depthWrites = 0;   // fragments strictly nearer than the buffer (they win, as in the reference)
  uint64_t culledTiles = 0;   // triangle-tile pairs skipped: the triangle is behind everything stored there
  uint64_t setUpLate = 0;     // deferred triangles set up in the tile pass (faces and clusters' survivors)
  // Blocks (8x8) met by the kernel; counted only when kCountBlocks.
  uint64_t blocksEmpty = 0, blocksPartial = 0, blocksFull = 0;
  uint64_t blocksCulled = 0;  // skipped: the triangle is behind everything stored in the block
  uint64_t tilesWhole = 0;    // triangle-tile pairs applied as a whole-tile plane (every pixel won)
  uint64_t blocksWhole = 0;   // triangle-block pairs applied as a whole-block plane
  void add(const RasterCounters& o);
};

/// What a tile's buffers mean. Clear and Plane are uniform states kept without touching the
/// buffers: nothing drawn yet, or one triangle (`plane`) won every pixel of the tile (its values
/// are the plane's, computed on demand bit for bit as the kernel would have stored them).
/// Pixels: the buffers hold every pixel's value.
enum class TileState : uint8_t { Clear, Plane, Pixels };

/// One triangle binned to a tile, as the kernel visits it (16 bytes: the set-up triangle is
/// Bins::triangle(key)).
struct TileEntry {
  uint64_t key;    // triangleKey: submission order
  double nearest;  // its nearest bound (FrontEndChunk::nearest)
};

/// What a tile's buffers mean and how they are bounded: its state, the uniform states of its
/// blocks, and the conservative farthest value per block and per tile that reject triangles
/// early, with the nearest stored value of the tile that lets a triangle in front of all of it
/// replace it whole. Shared by a worker's tile (TileScratch) and a kept one (KeptTile).
struct TileSummary {
  alignas(64) double blockFar[kBlocksPerTile];   // valid in state Pixels: no value of the block is farther
  alignas(64) double blockNear[kBlocksPerTile];  // ... nearer (conservative bounds, both)
  // State Pixels, per block: a triangle that won every pixel of the block at once (its key, 0 =
  // none): the block's values are that triangle's plane and its pixel buffers are stale — the
  // same uniform state as a tile's Plane, one level down (also what a Plane tile's blocks
  // inside the image become when the tile turns to Pixels).
  alignas(64) uint64_t blockKey[kBlocksPerTile];
  const SetupTriangle* blockTriangle[kBlocksPerTile];
  double tileFar;   // no stored value is farther (conservative; stale while tileFarStale)
  double tileNear;  // no stored value is nearer (conservative)
  bool tileFarStale;
  // State Pixels, per block: every pixel of the block holds the clear value and its buffers are
  // stale — a cleared tile's blocks wholly in the image, until a triangle lands on them (the
  // lazily written state of blockKey, for nothing drawn); after prepareResolve(), also a block
  // where nothing was drawn.
  bool blockClear[kBlocksPerTile];
  // State Pixels after prepareResolve(): the buffers of the blocks without blockKey or
  // blockClear hold the frame's values, not depth and keys (see prepareResolve).
  bool resolved;
  TileState state;
  const SetupTriangle* plane;  // state Plane: the triangle, and its key
  uint64_t planeKey;
};

/// A worker's tile: stored depth (as double: every format's values are exact in it) and the
/// winning triangle (triangleKey, 0 = none), row-major kTileSize x kTileSize, with the
/// summary that says which of those values are current. Reused tile after tile.
struct alignas(64) TileScratch : TileSummary {
  alignas(64) double depth[kTileSize * kTileSize];
  alignas(64) uint64_t triangle[kTileSize * kTileSize];
};

/// A rasterized tile kept after the pass for queries (the occlusion buffer keeps one per screen
/// tile): the summary, and the stored values of the blocks held pixel by pixel in 32 bits, block
/// by block (KeptTile::at) — a quarter of a TileScratch. Each value is the format's exactly:
/// for f32 formats the float's bits, for the integer formats the integer code (keptStored).
struct alignas(64) KeptTile : TileSummary {
  alignas(64) uint32_t depth[kTileSize * kTileSize];
  /// The index of tile-local pixel (x, y): block b's 64 values are [64 b, 64 b + 64), row by row.
  static size_t at(int x, int y) {
    constexpr int kBlocksX = kTileSize / kBlockSize;
    return size_t(((y / kBlockSize) * kBlocksX + x / kBlockSize) * kBlockSize * kBlockSize +
                  (y % kBlockSize) * kBlockSize + x % kBlockSize);
  }
};

/// A KeptTile's 32 bits of a stored value, as the double the kernel compares (exact).
template <DepthStorage S>
inline double keptStored(uint32_t bits) {
  if constexpr (S == DepthStorage::F32) return double(std::bit_cast<float>(bits));
  else return double(bits);
}

/// A worker's lists for orderTile(), reused tile after tile (one per worker, not per tile: a
/// tile's list can hold every triangle of the frame).
struct TileOrder {
  std::vector<TileEntry> entries, ordered;
  std::vector<TileEntry> late;  // the tile's deferred back faces that may show
  std::vector<uint8_t> bucket;
  uint64_t memoryBytes() const;
};

/// A tile of at least kUnsortedEntries triangles whose boxes (cut to the tile) hold at most
/// kUnsortedArea pixels in all is not sorted (orderTile): see there.
inline constexpr size_t kUnsortedEntries = 64;
inline constexpr uint64_t kUnsortedArea = 3 * uint64_t(kTileSize) * uint64_t(kTileSize);
/// orderTile's buckets (at most 256: a bucket's index is a byte). Surfaces closer together than
/// 1/kOrderBuckets of a tile's depth range share a bucket and are visited in submission order,
/// so too few buckets let stacked layers submitted farthest first overwrite pixels; 128 is where
/// more stop paying (see docs/benchmarks.md).
inline constexpr int kOrderBuckets = 128;

/// The triangles binned to `tile`, roughly nearest first (a stable bucket sort of their nearest
/// bounds by the eye depth they stand for, in `depth`'s format; in submission order when a bound
/// is not finite, or for many small triangles: at least kUnsortedEntries, their boxes holding at
/// most kUnsortedArea pixels in all — no order can save more than a few tiles' worth of pixel
/// tests there, and in submission order the kernel reads their records in the order they were
/// written, chunk by chunk), in `order.ordered` or `order.entries`, which it returns.
/// The kernel's depth test makes the order free: a fragment wins when it is strictly nearer
/// than the stored value, or equal to it and its triangle was submitted first (triangleKey) —
/// per pixel, the nearest fragment and, among equals, the first submitted: the image the z-buffer
/// draws in submission order, bit for bit. Nearest first, the tiles' and blocks' farthest depths
/// reject most hidden triangles before their pixels are visited (the front-to-back + z-buffer
/// combination of the KTH report's and thesis's, per tile).
const std::vector<TileEntry>& orderTile(const Bins& bins, int tile, const DepthSetup& depth, TileOrder& order);

/// Binning, in two steps: prepareBins() sizes the bins for a width x height image and
/// `chunkCount` front-end chunks; binChunk(c) sorts chunk c's triangles into its own lists (the
/// chunk's `nearest` bounds, from runFrontEnd with the frame's depth setup, are kept for the
/// kernel). Chunks share no output, so binChunk runs on any thread, in any order (as
/// runFrontEnd's consumer).
///
/// With `cullFor` (the frame's depth setup), a triangle is not binned to a tile that a triangle
/// of the same chunk covers whole (every pixel centre of the tile's part of the image) when its
/// nearest bound is strictly farther than that one's farthest bound (storedRange over its
/// vertices): whatever the order, the z-buffer ends with every pixel of the tile at least as
/// near as the covering triangle's fragment there, so the culled triangle could neither win nor
/// tie anywhere in it (the image stays bit for bit; counted in ChunkBins::culled). Bounded per
/// chunk, so the bins do not depend on the thread count. On stacked screen-filling layers this
/// drops nearly every pair before it is sorted, ordered or visited.
///
/// Deferred back faces (runFrontEnd with deferBackFaces; the KTH report's back-face culling, made
/// exact): on a closed mesh a back face lies behind the front faces over it, but culling it
/// outright is not exact (silhouettes, open meshes, intersecting geometry). Those whose pixel box
/// lies in one tile are kept out of the set-up records (FrontEndChunk::deferred, 40 bytes each)
/// and binned to that tile in Bins::late; rasterizeTile draws the tile's other triangles first,
/// then tests each deferred face against the farthest stored values of the blocks its box touches
/// (the kernel's own early rejection, Beaten), sets up those that may still win or tie (setupBatch:
/// the same bits as the front end) and draws them. The kernel's test is order-free and the keys
/// are the submission order, so the image is the one drawing everything at once gives, bit for
/// bit. The set-up needs Bins::projected and Bins::camera, which the caller sets after
/// runFrontEnd (its FrontEndOutput::projected and camera, alive until the tile pass ends).
///
/// Deferred clusters (FrontEndChunk::clusters, deferCluster in frontend/clusters.hpp): runs of 32
/// well-shaped triangles that all face away from the eye by a margin are not set up by the
/// front end at all; each is binned, as one item with its pixel box and a conservative nearest
/// bound, to every tile the box overlaps (Bins::clusters). A tile tests it like a deferred face;
/// where it may show, the cluster is set up (once per frame, by the first worker to need it:
/// ChunkBins::setUp) and each of its triangles in the tile is tested on its own nearest bound and
/// drawn in the Late pass. Needs Bins::sceneTriangles too. On a dense closed mesh about half the
/// triangles are then never set up.
void prepareBins(Bins& bins, int width, int height, size_t chunkCount);
void binChunk(Bins& bins, size_t chunk, const FrontEndChunk& triangles, const DepthSetup* cullFor = nullptr);

/// Rasterizes every triangle binned to `tile` into `scratch` (cleared first; with `keep`, onto
/// what it holds: a tile loadTile() brought back, whose uniform states' triangles are still
/// alive), visiting them in
/// orderTile's order (lists in `order`), then the tile's deferred back faces and clusters' triangles
/// that may show (see binChunk). With ids false, only depth is kept (no triangle ids). Adds to
/// `counters` (a deferred face found hidden counts as a triangle-tile pair culled, a deferred
/// cluster found hidden as kClusterTriangles of them).
void rasterizeTile(const Bins& bins, int tile, const DepthSetup& depth, bool ids, TileScratch& scratch,
                   TileOrder& order, RasterCounters& counters, bool keep = false, BackgroundPump* pump = nullptr);

/// Readies a tile that rasterizeTile(ids = true) left in `scratch` for resolveTile() (any
/// FrameOutputs, DepthOnly too: depth comes from the winner's plane), right after rasterizing,
/// while the tile's set-up triangles are still in this core's cache. A block won wholly by one triangle gets it as its
/// blockKey, one where nothing was drawn blockClear (both resolved a row of lanes at a time);
/// in the other blocks held pixel by pixel, each pixel is turned, in place, into what the frame
/// gets — depth[i] becomes (float eye depth, int32 face
/// id), triangle[i] (int32 triangle id, Rgba8 colour) — so that the resolve, which writes the
/// frame band by band across several tiles, copies instead of looking triangles up. (Looked up
/// at resolve, the records have left the cache.) Depth and keys are gone afterwards
/// (TileScratch::resolved).
/// `shader` and `background`: colour, for outputs with FrameOutputs::Color only.
void prepareResolve(const Bins& bins, int tile, FrameOutputs outputs, const TriangleShader* shader, Rgba8 background,
                    TileScratch& scratch, BackgroundPump* pump = nullptr);

/// Writes every pixel of the tile of `scratch` into `frame` as `outputs` asks: ids, eye depth
/// of the winning triangle's plane at the pixel centre (exactly as the reference resolves it),
/// its colour (SetupTriangle::color, or from `shader` for back faces; needed with
/// FrameOutputs::Color only); for DepthOnly, that eye depth alone; the background (-1, +inf,
/// `background`) where nothing was drawn. The frame's buffers that `outputs` does not ask for are not touched. Only the tile's rows [rowBegin,
/// rowEnd) (tile-local): a caller resolving several tiles writes the frame band by band across
/// them — row-major frame buffers written one 64x64 tile at a time with ordinary stores are
/// much slower to write (64 rows x 4 buffers of scattered 256-byte pieces defeat the hardware
/// prefetchers and TLB; see docs/benchmarks.md). The tile must have been rasterized with ids
/// and through prepareResolve() (std::logic_error otherwise). Returns the number of covered pixels.
/// The frame's whole cache lines are written with streaming stores: a thread that called
/// resolveTile calls finishResolves() before another thread reads the frame.
uint64_t resolveTile(const Bins& bins, int tile, const DepthSetup& depth, FrameOutputs outputs,
                     const TriangleShader* shader, Rgba8 background, const TileScratch& scratch, Frame& frame,
                     int rowBegin = 0, int rowEnd = kTileSize);
/// The eye depth of each stored value of a tile rasterized without ids (rasterizeTile(ids =
/// false), as the occlusion buffer keeps them), +inf where nothing was drawn, into `frame`'s
/// depth; rows as resolveTile(). Within an ulp or so of the winner's plane (the stored value is
/// rounded to the depth format); frames resolve with resolveTile() instead.
uint64_t resolveStoredDepth(const Bins& bins, int tile, const DepthSetup& depth, const TileScratch& scratch,
                            Frame& frame, int rowBegin = 0, int rowEnd = kTileSize);

/// Makes the calling thread's resolveTile() writes visible to other threads (a store fence).
void finishResolves();

/// Keeps what rasterizeTile(ids = false) left in `from` in `to`, which then answers the queries
/// below as `from` would (the uniform blocks' pixel values and the triangle buffer are not
/// copied). For tiles kept long after they were rasterized (the occlusion buffer's): rasterized in
/// a worker's scratch, which stays in the core's cache tile after tile, then written out with
/// streaming stores at a quarter of the size, so the kernel never waits on a kept tile's cold
/// lines. The writing thread calls finishResolves() before another thread reads `to`.
void storeTile(const TileScratch& from, const DepthSetup& depth, KeptTile& to);
/// The inverse: `to` as the kernel left `from` in rasterizeTile (depth; ids are not kept), for
/// resolveStoredDepth().
void loadTile(const KeptTile& from, const DepthSetup& depth, TileScratch& to);

/// Queries on a tile kept by storeTile (the occlusion buffer keeps one per screen tile). Its
/// uniform states refer to the frame's set-up triangles, which must still be alive.
/// Scalar code; the values are the kernel's bits (fragmentStored, as Materialize computes them).
/// storedAt: the value stored at tile-local pixel (x, y), inside the image.
double storedAt(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x, int y);
/// anyFarther: whether some pixel of the tile-local rectangle [x0, x1] x [y0, y1] (non-empty,
/// inside the image) stores a value farther than `stored` (a value of the depth format). The
/// tile's and blocks' bounds answer first; pixels are read only where they cannot.
bool anyFarther(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x0, int y0,
                int x1, int y1, double stored);

/// A worker's share of the frame's background (the parts of the image where nothing was binned,
/// which get the background values), streamed a few cache lines at a time between the tile
/// kernel's own work (rasterizeTile, prepareResolve), then what is left by drainBackground().
/// A core streams about 10 bytes a cycle; computing between bursts of streams adds the two
/// times, while a few lines after each small piece of work drain while the core computes (a
/// loop on this project's Intel VM: 0.50 ms for 0.43 ms of arithmetic and the 25 MB of a frame
/// to stream, against 0.63 ms in bursts of a band). The current piece is `lines` whole lines of
/// `value` from `dst`; refill(*this) sets the next piece with setPiece (the owner's state in
/// `context` and `cursor`) or returns false when nothing is left (then `done`).
struct BackgroundPump {
  uint32_t* dst = nullptr;
  uint32_t value = 0;
  uint32_t lines = 0;
  bool done = true;
  bool (*refill)(BackgroundPump&) = nullptr;
  void* context = nullptr;
  int cursor[3] = {-1, 0, 0};
  /// The next piece: start[i] = value for i < count. The parts of its first and last cache lines
  /// that it may share with its neighbours are written here with ordinary stores; the whole lines
  /// between them are left to the pump. Returns whether there are any.
  bool setPiece(uint32_t* start, size_t count, uint32_t value);
};
/// Lines the kernel streams from its pump after each block it makes a triangle's plane whole,
/// each block it draws row by row, each block row it classifies, and each block prepareResolve
/// converts: enough to hide the stores behind the kernel's work, few enough not to come in
/// bursts (see docs/benchmarks.md).
inline constexpr uint32_t kPumpPerBlock = 48, kPumpPerWholeBlock = 16, kPumpPerBlockRow = 16,
                          kPumpPerPreparedBlock = 32;
/// Streams every line the pump has left.
void drainBackground(BackgroundPump& pump);

/// What the kernel (tile_kernel-inl.h) needs for one tile (scratch and counters: rasterizing only).
struct TileJob {
  const Bins* bins;
  int tile;
  DepthSetup depth;
  bool ids;  // keep the winning triangle per pixel (false: depth only)
  TileScratch* scratch;
  RasterCounters* counters;
  const TriangleShader* shader;  // resolving colour only
  TileOrder* order;              // rasterizing only
  // Rasterizing: Whole — the binned triangles into a cleared tile; Front — the same, leaving the
  // blocks' farthest values exact for the deferred faces' test; Late — order->late, into the
  // tile as the Front pass left it.
  enum class Pass : uint8_t { Whole, Front, Late } pass = Pass::Whole;
  bool keep = false;  // Whole or Front: onto the tile as it is, not cleared first (rasterizeTile's keep)
  BackgroundPump* pump = nullptr;  // rasterizing and preparing: background to stream meanwhile
};

/// Name of the instruction set the kernel dispatches to on this machine (e.g. "AVX3").
const char* kernelTarget();

}  // namespace hsr::tiled

// What the front end produces: FrontEndOutput, its chunks of set-up triangles in submission
// order, the deferred back faces and clusters, and the counters of what was dropped. Each chunk
// is written by the worker that sets it up (frontend.cpp); the tiled rasterizer bins it
// (raster/binning.cpp) and the algorithms read it, chunk by chunk.
#pragma once
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "frontend/unwritten_allocator.hpp"
#include "frontend/vertices.hpp"
#include "setup/setup_triangle.hpp"

namespace hsr {

/// Why triangles were not drawn, counted per scene triangle or clipped piece.
struct FrontEndCounters {
  uint64_t clipped = 0, culledBackface = 0, culledFrustum = 0, degenerate = 0;
  uint64_t empty = 0;  // on screen, but covering no pixel centre (not in the statistics)
  // Set up with a pixel box at least kLargeBoxPixels wide and tall (not in the statistics): only
  // these can cover a whole 64x64 tile, which binning looks for (raster/tiled.hpp, binChunk).
  uint64_t large = 0;
  void add(const FrontEndCounters& o) {
    clipped += o.clipped;
    culledBackface += o.culledBackface;
    culledFrustum += o.culledFrustum;
    degenerate += o.degenerate;
    empty += o.empty;
    large += o.large;
  }
};

inline constexpr int kLargeBoxPixels = 64;

/// Scene triangles per chunk of front-end work, at most: small enough that a chunk's set-up
/// triangles (<= 7 pieces a triangle when clipped, mostly 1) stay in a core's L2 cache until
/// they are binned.
inline constexpr size_t kChunkTriangles = 1 << 12;
/// The fewest scene triangles per chunk (chunkTrianglesFor), a multiple of kClusterTriangles.
inline constexpr size_t kMinChunkTriangles = 256;
/// Scene triangles per chunk for a scene of `triangles`: kChunkTriangles, or fewer (down to
/// kMinChunkTriangles) so that a scene of under 16K triangles still has about 4 chunks. A chunk
/// is set up and binned by one thread, so too few chunks leave threads idle; too many cost time,
/// because every tile merges the lists of every chunk binned to it (orderTile). Four was the
/// best count measured (see docs/benchmarks.md). A function of the scene only, never of the
/// thread count: binning culls within a chunk, so the statistics would depend on it. (So a
/// scene under 16K triangles never uses more than 4 front-end threads.)
inline size_t chunkTrianglesFor(size_t triangles) {
  constexpr size_t kChunks = 4;
  static_assert(kMinChunkTriangles % kClusterTriangles == 0 && kChunkTriangles % kClusterTriangles == 0);
  const size_t per = (triangles / kChunks + kClusterTriangles - 1) / kClusterTriangles * kClusterTriangles;
  return std::clamp(per, kMinChunkTriangles, kChunkTriangles);
}

/// A back face runFrontEnd(.deferBackFaces = true) did not write a SetupTriangle for: what the
/// tiled rasterizer needs to decide, from its tile's stored depths, whether it can show, and to
/// set it up again (setupBatch, same bits) if so (raster/tiled.hpp: deferred back faces).
/// 40 bytes instead of the record's 96.
struct DeferredFace {
  uint32_t v[3];                   // scene vertex indices (FrontEndOutput::projected)
  uint32_t triangle, face;
  int16_t minX, minY, maxX, maxY;  // the pixel box, within one tile (kDeferTile)
  double nearest;                  // nearestStored() of its set-up triangle
};

/// A cluster of scene triangles (Scene::clusters) that runFrontEnd(.deferBackFaces = true) did
/// not set up: every triangle of it faces away from the eye by a margin, so it is likely hidden
/// behind the front of its mesh; the tiled rasterizer sets it up only in the tiles where it may
/// still show (raster/tiled.hpp: deferred clusters). 24 bytes for kClusterTriangles triangles.
struct DeferredCluster {
  uint32_t cluster;                // index in Scene::clusters: triangles [kClusterTriangles cluster, + kClusterTriangles)
  int16_t minX, minY, maxX, maxY;  // a pixel box in the image holding every pixel its triangles may cover
  double nearest;                  // a stored value of the depth setup none of their fragments is nearer than
};

/// Back faces are deferred only when their pixel box lies in one square of this size (the tiled
/// rasterizer's tile), so that one worker owns everything done with them.
inline constexpr int kDeferTile = 64;

using SetupTriangles = std::vector<SetupTriangle, UnwrittenAllocator<SetupTriangle>>;

/// Fetches the cache lines of records [first, first + count) for writing: records written in
/// place (setupBatch's output) land on lines last written a frame ago, maybe by the other core.
inline void prefetchForWriting(const SetupTriangle* first, size_t count) {
  for (size_t b = 0; b < count * sizeof(SetupTriangle); b += 64)
    __builtin_prefetch(reinterpret_cast<const char*>(first) + b, 1, 3);
}

/// The set-up triangles of one chunk of scene triangles, in submission order.
struct FrontEndChunk {
  uint32_t firstTriangle = 0;  // the scene index of its first triangle: chunk c holds [c k, c k + k), k = chunkTriangles
  SetupTriangles triangles;
  /// With FrontEndOptions::deferBackFaces: the deferred back faces (not in `triangles`), in
  /// submission order (the records of those set up again are the tiled rasterizer's: Bins::late).
  std::vector<DeferredFace> deferred;
  /// With FrontEndOptions::deferBackFaces: the deferred clusters, in submission order (their
  /// triangles are in neither `triangles` nor `deferred`).
  std::vector<DeferredCluster> clusters;
  /// With FrontEndOptions::nearestFor only, one per triangle: a stored value of that depth setup
  /// that none of the triangle's fragments is nearer than (nearestStored() in
  /// setup/fragment_depth.hpp, bit for bit), for occlusion culling.
  std::vector<double> nearest;
  FrontEndCounters counters;
};

struct FrontEndOutput : FrontEndCounters {
  /// chunks[0, chunkCount): read in order, all set-up triangles in submission order. (The
  /// vector may hold more chunks from an earlier, larger frame: their memory is kept.)
  std::vector<FrontEndChunk> chunks;
  size_t chunkCount = 0;
  size_t chunkTriangles = kChunkTriangles;  // scene triangles per chunk (chunkTrianglesFor)

  size_t triangleCount() const;
  /// Calls f(const SetupTriangle&) for every set-up triangle, in submission order.
  template <class F>
  void forEach(F&& f) const {
    for (size_t c = 0; c < chunkCount; ++c)
      for (const SetupTriangle& t : chunks[c].triangles) f(t);
  }
  /// All set-up triangles in one list (a copy; for tests and tools).
  std::vector<SetupTriangle> flatten() const;
  /// The same into `all`, whose memory is reused.
  void flattenInto(std::vector<SetupTriangle>& all) const;
  uint64_t memoryBytes() const;

  // Scratch reused from frame to frame (no allocation once warm).
  dmat4 pixelFromWorld{1.0};  // the frame's world -> homogeneous pixel transform
  std::vector<uint8_t> outcodes;
  std::vector<ProjectedVertex> projected;
  // Per face, 0 when its mesh's box lies wholly outside a clipping plane; empty when no mesh
  // is (the usual case: no 1-byte-per-face pass over memory each frame).
  std::vector<uint8_t> faceVisible;
  std::vector<uint8_t> meshCulled;  // per mesh, 1 when its box lies wholly outside a clipping plane
  // Per mesh, filled by runSetUp: 1 when every vertex of its range has outcode 0 (its triangles
  // need no clipping: set-up batches them without reading their vertices' outcodes).
  std::vector<uint8_t> meshUnclipped;
  /// Whether face `face`'s mesh was not culled whole (see faceVisible).
  bool meshInView(uint32_t face) const { return faceVisible.empty() || faceVisible[face]; }
};

}  // namespace hsr

// The geometry front end shared by every rasterizing algorithm: world -> homogeneous pixel
// coordinates (double, relative to the camera), clipping (near, far, guard band), perspective
// divide, snapping to 1/256 pixel, culling and triangle setup (integer edge functions with the
// top-left rule, depth planes). Produces SetupTriangles in submission order, in fixed chunks of
// scene triangles; consumed by the rasterizers (raster/) through the algorithms, chunk by
// chunk. Called from one thread; spreads its chunks of vertices and triangles over the thread
// pool (core/parallel.hpp) and hands each finished chunk to an optional consumer on the same
// worker, while the chunk is still in that core's cache (the tiled rasterizer bins it there).
#pragma once
#include <hsr/render.hpp>

#include "core/shading.hpp"

#include <cmath>
#include <functional>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace hsr {

/// Sub-pixel precision of snapped vertex positions: 8 bits, 1/256 pixel.
inline constexpr int kSubpixelBits = 8;
inline constexpr int64_t kSubpixelOne = int64_t(1) << kSubpixelBits;
/// Guard band: geometry is clipped to this many pixels beyond each image border, which bounds
/// snapped coordinates by 2^15 pixels (2^23 fixed point) so edge functions fit int64 with room.
inline constexpr double kGuardBandPixels = 8192;
inline constexpr int kMaxImageSize = 16384;

/// Integer division rounding towards minus / plus infinity (b > 0), for pixel ranges.
inline int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
inline int64_t ceilDiv(int64_t a, int64_t b) { return -floorDiv(-a, b); }

/// An affine function of pixel position: value(x, y) = a x + b y + c (x, y in pixels).
struct Plane {
  double a = 0, b = 0, c = 0;
  double at(double x, double y) const { return a * x + b * y + c; }
};

/// A triangle ready to rasterize. Vertices are in fixed point (1/256 pixel), ordered so that the
/// edge functions E_i are positive inside (see raster/edge.hpp); bounding box in whole pixels.
/// 96 bytes: everything the rasterizers and the resolve read.
struct SetupTriangle {
  int32_t x[3], y[3];
  int16_t minX, minY, maxX, maxY;  // inclusive pixel range whose centres may be covered, in the image
  Plane depthNum, depthDen;        // eye depth at pixel position p = depthNum(p) / depthDen(p)
  uint32_t triangle;               // index into Scene::triangles
  uint32_t face;
  bool frontFacing;                // counter-clockwise as seen by the camera
  // A box of at most kCoverageBox x kCoverageBox pixels (most triangles of a dense mesh): the
  // pixel centres it covers, bit kCoverageBox (y - minY) + (x - minX), as the edge functions
  // decide (never 0: such a triangle is dropped); 0 for a larger box. Lets the tiled kernel skip
  // its edge set-up.
  uint16_t coverage = 0;
  Rgba8 color;  // shaded (core/shading.hpp) when the frame keeps colour and frontFacing (a
                // back face is mostly hidden: the resolve shades the few that show)

  double eyeDepth(double px, double py) const { return depthNum.at(px, py) / depthDen.at(px, py); }
};

/// Side of the largest pixel box whose covered centres set-up lists (SetupTriangle::coverage).
inline constexpr int kCoverageBox = 4;
static_assert(kCoverageBox * kCoverageBox <= 16, "SetupTriangle::coverage holds one bit per centre");
static_assert(sizeof(SetupTriangle) == 96, "a set-up triangle is one and a half cache lines");

/// The colour of a set-up triangle, one rule for every rasterizer: the front end shades front
/// faces (SetupTriangle::color); a back face, mostly hidden, is shaded only when it shows.
inline Rgba8 triangleColor(const SetupTriangle& t, const TriangleShader& shade) {
  return t.frontFacing ? t.color : shade(t.triangle);
}

/// The depth buffer a frame is drawn into: its format and the camera's clipping range.
struct DepthSetup {
  DepthFormat format;
  double near = 0, far = 0;
  bool orthographic = false;
};

/// Homogeneous pixel coordinates of a vertex: pixel = (hx / w, hy / w), eye depth d (w > 0).
struct HVertex {
  double hx, hy, d, w;
};

/// A pixel coordinate snapped to 1/256 pixel: rounded to the nearest (|s| < 2^15 pixels after
/// clipping, so the result is exact in int64 and in double).
inline int64_t snapCoordinate(double s) { return int64_t(std::floor(s * kSubpixelOne + 0.5)); }

/// A vertex inside the clip volume, projected once and shared by all its triangles. 32 bytes (the
/// vertex pass writes one per scene vertex, set-up gathers them): the snapped position is not
/// stored but computed where it is needed, X() and Y().
struct ProjectedVertex {
  double sx, sy;   // pixel position (unsnapped)
  double num, den; // d/w and 1/w, both affine in screen space
  int64_t X() const { return snapCoordinate(sx); }  // snapped to 1/256 pixel
  int64_t Y() const { return snapCoordinate(sy); }
};
static_assert(sizeof(ProjectedVertex) == 32);

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

/// An allocator whose default construction writes nothing (for an aggregate, trivially copyable
/// type: the storage already holds such an object, whose values come later): a list that grows by
/// resize() and is then written in place, without a pass of zeros first (set-up's chunk lists).
template <class T>
struct UnwrittenAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UnwrittenAllocator<U>;
  };
  UnwrittenAllocator() = default;
  template <class U>
  UnwrittenAllocator(const UnwrittenAllocator<U>&) noexcept {}
  template <class U>
  void construct(U*) noexcept {
    static_assert(std::is_aggregate_v<U> && std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>);
  }
  template <class U, class... A>
  void construct(U* p, A&&... a) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
};
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
  /// raster/fragment_depth.hpp, bit for bit), for occlusion culling.
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

/// Called on a worker thread with each chunk's index as soon as the chunk is set up; chunks may
/// finish in any order and concurrently, so a consumer writes only to its chunk's own data.
using ChunkConsumer = std::function<void(size_t chunk)>;

/// Projects and snaps a vertex that lies inside the clip volume.
ProjectedVertex projectVertex(const HVertex& v);

/// Homogeneous pixel coordinates of world point p: M (p, 1), each row summed as
/// ((m0 x + m1 y) + m2 z) + m3 (M column-major, as glm stores it).
HVertex transformVertex(const dvec3& p, const dmat4& M);

/// The clipping planes (near, far, guard band) vertex v lies outside of, one bit each.
uint32_t clipOutcode(const HVertex& v, const Camera& cam);

/// The vertex pass of vertices [0, count), with SIMD (frontend/setup_batch.cpp): with h =
/// transformVertex(positions[i], M), outcodes[i] = clipOutcode(h) and, when that is 0,
/// projected[i] = projectVertex(h) — bit for bit those functions' results; `projected` null: the
/// outcodes only (a mesh's box corners: four divisions less per vertex). (The homogeneous
/// vertices themselves are not kept: the few triangles that need clipping transform theirs
/// again, to the same bits.)
void transformVertices(const dvec3* positions, size_t count, const dmat4& M, const Camera& cam, uint8_t* outcodes,
                       ProjectedVertex* projected);

/// The corners of `box` taken to homogeneous pixel coordinates by M (transformVertex's products
/// and sums, in its order), with SIMD (frontend/setup_batch.cpp): false unless every corner lies
/// inside each clipping half-space by more than `margin`; then `extent` holds the least w - wRoom
/// and the greatest w + wRoom, then the least and greatest pixel positions hx / w and hy / w,
/// as hx (1 / w) (x0, y0, x1, y1).
bool boxCornersInView(const Bounds3& box, const dmat4& M, const Camera& cam, double margin, double wRoom,
                      double* extent);

/// Sets up one triangle whose vertices are inside the clip volume: culls and fills `t`.
/// Returns false, counting the reason in `counters`, when it draws nothing.
bool setupTriangle(const ProjectedVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t);
/// The same from homogeneous coordinates (projects first).
bool setupTriangle(const HVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t);

/// Lanes of the batched set-up (at most; fewer on narrower instruction sets).
inline constexpr size_t kSetupBatch = 8;

/// setupTriangle() for `count` triangles inside the clip volume at once, with SIMD
/// (frontend/setup_batch.cpp): triangle i has vertices projected[vertex[0..2][i]], scene index
/// triIndex[i] and face face[i]. Writes the survivors to out[0, n), in order, and returns n;
/// the SetupTriangles (colour aside) and counters are bit for bit those of setupTriangle().
/// What else setupBatch computes, and how (see SetupBatchOptions' fields).
struct SetupBatchOptions {
  /// With `depth`, also nearest[0, n): nearestStored(out[i], *depth), bit for bit.
  const DepthSetup* depth = nullptr;
  double* nearest = nullptr;
  /// With `deferred` (and `depth`), the back faces whose pixel box lies in one kDeferTile
  /// square go to deferred[0, *deferredCount) as DeferredFaces instead (in order; not counted
  /// in the result).
  DeferredFace* deferred = nullptr;
  size_t* deferredCount = nullptr;
  /// With a cull: the facing test runs over all the triangles first and only those it keeps
  /// are set up. Faster when many are culled, slower when few are; the output is the same.
  bool cullFirst = false;
};
size_t setupBatch(const ProjectedVertex* projected, const uint32_t* const* vertex, const uint32_t* triIndex,
                  const uint32_t* face, size_t count, const Camera& cam, Cull cull, FrontEndCounters& counters,
                  SetupTriangle* out, const SetupBatchOptions& options = {});

/// Scene triangles [first, end).
struct TriangleRange {
  uint32_t first, end;
};

/// What runFrontEnd and runSetUp produce besides the set-up triangles, and which triangles they
/// set up. The defaults: set-up triangles only, for every scene triangle.
struct FrontEndOptions {
  /// Every chunk's `nearest` holds the triangles' nearest bounds in this depth setup.
  const DepthSetup* nearestFor = nullptr;
  /// With `nearestFor`: the back faces setupBatch can defer go to the chunks' `deferred` lists,
  /// and the clusters that face away from the eye (deferCluster) to their `clusters` lists,
  /// instead of `triangles`.
  bool deferBackFaces = false;
  /// Whether whole clusters are deferred (with deferBackFaces) or, with RenderOptions::cull ==
  /// Cull::Back, culled whole when cullCluster accepts them.
  bool deferClusters = true;
  /// Only these triangles are set up (sorted, disjoint ranges, each a union of whole meshes, so
  /// no cluster is split): the chunks stay the same, the others are left out as if culled,
  /// uncounted.
  const std::vector<TriangleRange>* only = nullptr;
};

/// Runs the front end over all scene triangles, in order, on up to options.threads threads; the
/// work is split into fixed chunks, so the output never depends on the thread count.
/// `out` is reused across frames. `consumer`, when given, is called once per chunk (see
/// ChunkConsumer), before runFrontEnd returns. `frontEnd`: see FrontEndOptions, e.g.
/// runFrontEnd(scene, cam, opt, fe, consumer, {.nearestFor = &depth, .deferBackFaces = true}).
void runFrontEnd(const Scene& scene, const Camera& camera, const RenderOptions& options, FrontEndOutput& out,
                 const ChunkConsumer& consumer = {}, const FrontEndOptions& frontEnd = {});

/// runFrontEnd in two steps: the vertex pass (every vertex transformed, projected where inside
/// the clip volume; meshes outside it culled whole), into `out`; then set-up (and the consumer)
/// reading `vertices`, the output of a vertex pass with the same scene, camera and options,
/// into `out`'s chunks and counters (`out` may be `vertices`), as FrontEndOptions asks.
/// `meshConsumer`, when given, is called with runs [first, last) of meshes whose view test
/// (FrontEndOutput::meshCulled) is done, on the worker that did it, while the vertex pass goes on.
/// With `vertices` false, only the meshes are tested: the caller transforms the vertices it
/// needs (transformVertices into `out.outcodes` and `out.projected`, sized here) before set-up.
using MeshConsumer = std::function<void(size_t first, size_t last)>;
void runVertexPass(const Scene& scene, const Camera& camera, const RenderOptions& options, FrontEndOutput& out,
                   const MeshConsumer& meshConsumer = {}, bool vertices = true);
void runSetUp(const Scene& scene, const Camera& camera, const RenderOptions& options, const FrontEndOutput& vertices,
              FrontEndOutput& out, const ChunkConsumer& consumer = {}, const FrontEndOptions& frontEnd = {});

/// What deciding about clusters needs from a camera, once per frame (deferCluster).
struct ClusterView {
  bool enabled = false;  // a perspective camera of the kind resolveCamera makes (no cluster is deferred otherwise)
  dvec3 eye{0.0};        // the centre of projection, in world space
  double fx = 0, fy = 0, skew = 0, cx = 0, cy = 0;  // the intrinsics (pixelFromCamera)
  /// 1/fx + |skew|/(fx fy) + 1/fy: see deferCluster.
  double gradient() const { return 1 / fx + std::abs(skew) / (fx * fy) + 1 / fy; }
};
ClusterView clusterView(const Camera& cam);

/// With Cull::Back: whether every triangle of `cluster` is a back face for setupTriangle (its
/// snapped signed area is > 0) and inside the clip volume, so runFrontEnd culls the cluster whole
/// (counted as kClusterTriangles back faces) without looking at its triangles (see frontend.cpp).
bool cullCluster(const TriangleCluster& cluster, const ClusterView& view, const Camera& cam,
                 const dmat4& pixelFromWorld);

/// Whether runFrontEnd(.deferBackFaces = true) defers cluster `cluster` of a scene (see
/// DeferredCluster), and if so its box and nearest bound in `out` (out.cluster is left to the
/// caller). Every triangle of a deferred cluster lies inside the clip volume (none is clipped)
/// and draws only inside the box, and no fragment it draws in `depth` is nearer than
/// out.nearest (see frontend.cpp for why). `pixelFromWorld`: cam.pixelFromCamera *
/// cam.cameraFromWorld.
bool deferCluster(const TriangleCluster& cluster, const ClusterView& view, const Camera& cam,
                  const dmat4& pixelFromWorld, const DepthSetup& depth, DeferredCluster& out);

/// Testing a mesh whole for occlusion (the occlusion buffer's mesh culling): a pixel box in the
/// image holding every pixel centre its triangles may cover, a stored value of the depth setup
/// that none of their fragments is nearer than, and the least eye depth of its box (conservative).
struct MeshBound {
  int16_t minX, minY, maxX, maxY;
  double nearest, zMin;
};
/// What meshBound needs from a camera and depth setup, once per frame.
struct MeshView {
  bool enabled = false;  // a perspective camera of the kind resolveCamera makes (ClusterView)
  dvec3 eye{0.0};
  double eyeLength = 0, gradient = 0;  // |eye|; ClusterView::gradient()
  dmat4 pixelFromWorld{1.0};
  // Its columns' positive and negative parts and magnitudes (the intervals of meshBound).
  dvec4 positive[4], negative[4], magnitude[4];
  const Camera* camera = nullptr;
  DepthSetup depth;
};
MeshView meshView(const Camera& cam, const DepthSetup& depth);
/// What meshBound found: no bound (None); none of the mesh's triangles covers a pixel centre of
/// the image (Outside: it draws nothing); or a MeshBound.
enum class MeshTest : uint8_t { None, Outside, Bounded };
/// Mesh `mesh` of `scene` bounded so (MeshBound, in `out`), when the camera is a perspective one
/// (view.enabled), the mesh has its planes (MeshRange::planeCount), its box lies inside the clip
/// volume (none of its triangles is clipped) and it is not seen too nearly edge on (see
/// frontend/mesh_bounds.cpp). meshBounds: the same for meshes [first, last) into tests[0,
/// last - first) and bounds[0, last - first), several at once with SIMD (a mesh's result does
/// not depend on the others).
MeshTest meshBound(const Scene& scene, size_t mesh, const MeshView& view, MeshBound& out);
void meshBounds(const Scene& scene, size_t first, size_t last, const MeshView& view, MeshTest* tests,
                MeshBound* bounds);
/// Eye depth d (perspective) as a stored value of `depth` that no fragment whose eye depth is
/// at least d stores nearer: mapped, moved 1e-9 of itself nearer, clamped and rounded to storage
/// (all monotone; the room is for the rounding of the planes, deferCluster's step 4).
double storedNearest(double d, const DepthSetup& depth);

}  // namespace hsr

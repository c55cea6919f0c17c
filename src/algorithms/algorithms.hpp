// What the visibility algorithms share (one per file, src/algorithms/NAME.cpp, each listed by one
// line in registry.cpp): the base of their objects, the painting-order capability, and helpers
// render() and the algorithms use. An algorithm object fills the whole Frame (visibility buffer +
// statistics) from its scene and a resolved camera; render() hands it sized but not cleared
// (Frame::allocate): it writes every pixel of the buffers present, or calls Frame::clear() first
// (the drawing service, draw.hpp, does).
#pragma once
#include <hsr/algorithm.hpp>
#include <hsr/bsp.hpp>
#include <hsr/options.hpp>

#include <memory>

#include "algorithms/bvh.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/polygon_split.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr::algo {

/// The base of the registry's algorithm objects: the scene and checked parameters it was made
/// with, and the drawing service's per-pixel buffers, kept from one view to the next.
class SceneAlgorithm : public Algorithm {
 public:
  SceneAlgorithm(const Scene& scene, const AlgorithmParams& params) : scene_(scene), params_(params) {}

 protected:
  const Scene& scene_;
  const AlgorithmParams params_;
  DrawBuffers buffers_;
};

/// The registry's factory of algorithm class A, made as A(scene, params).
template <class A>
AlgorithmFactory factoryOf() {
  return [](const Scene& scene, const AlgorithmParams& params) -> std::unique_ptr<Algorithm> {
    return std::make_unique<A>(scene, params);
  };
}

/// Whether any face of the scene has an opacity below 1 (alpha < 255) (abuffer.cpp): then the
/// list-priority algorithms blend in their order and the z-buffer family adds a transparent pass.
bool hasTransparency(const Scene& scene);

/// The colour error of `frame` against the A-buffer's `reference` (verify.cpp), over the pixels
/// whose face id is the reference's (the others are the id check's: wrong or ambiguous) and,
/// with `nearEdge`, that are not marked in it: per
/// channel the largest and the mean absolute difference, and the pixels where some channel
/// differs by more than one 8-bit step.
struct ColorError {
  uint64_t pixels = 0;    // compared
  uint64_t nearEdge = 0;  // not compared: a fragment's edge within 1/128 pixel of the centre (abufferFrame)
  int max[3] = {0, 0, 0};
  double mean[3] = {0, 0, 0};
  uint64_t beyondStep = 0;
};
ColorError colorError(const Frame& frame, const Frame& reference, const std::vector<uint8_t>* nearEdge = nullptr);
/// The A-buffer's frame (abuffer.cpp); with `nearEdge`, per pixel 1 where the centre is within
/// 1/128 pixel of a projected edge of one of its fragments' triangles (a rasterizer's snapped
/// coverage may differ there, as for --verify's ambiguous pixels).
void abufferFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame,
                  std::vector<uint8_t>* nearEdge);

/// A painting order as polygons, back to front: what painter, newell and bsp draw from a camera,
/// and what the vector output (io/svg.cpp) writes.
struct PaintedPolygons {
  std::vector<dvec3> vertices;       // world space
  std::vector<PolygonRef> polygons;  // back to front, each a part of (or all of) a scene face
  std::vector<uint32_t> triangles;   // per polygon: a scene triangle of its face (its shading)
};
/// The capability Capability::PaintsInOrder: an algorithm object that declares it also derives
/// from this, and gives its painting order for a camera.
class PaintsInOrder {
 public:
  virtual ~PaintsInOrder() = default;
  virtual void paintedPolygons(const Camera& camera, PaintedPolygons& out) = 0;
};

/// A scene's BSP tree with its fragments as a scene the drawing service draws (bsp.cpp): built
/// at the first frame that needs it and kept by the algorithm object that owns it (bsp, and
/// reverse-painter in the tree's order).
class BspDrawing {
 public:
  explicit BspDrawing(const BspBuildOptions& build);
  ~BspDrawing();
  /// The tree drawn in its order from the camera, back to front or front to back, under `rule`;
  /// fills the statistics and the tree's details (nodes, fragments, splits, depth, built, build_ms).
  void draw(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
            DrawRaster raster, bool frontToBack, DrawBuffers& buffers, Frame& frame);
  /// The tree's fragments back to front from the camera.
  void polygons(const Scene& scene, const Camera& camera, PaintedPolygons& out);

  struct Built;  // the tree and its fragments as a scene (bsp.cpp)

 private:
  bool build(const Scene& scene);  // true when it built now
  BspBuildOptions options_;
  std::unique_ptr<Built> built_;
};

/// What a list-priority algorithm ordering faces by one sort key fails on (painter.cpp): the
/// painter's with that key, and the reverse painter's with that order (the same image).
Guarantee listPriorityFailures(const std::string& key);
/// The scenes of the conformance suite where that order is wrong (failures.cpp).
std::vector<std::string> listPriorityFailureScenes(const std::string& key);

/// Temporal coherence of occlusion culling: the meshes that showed in the previous frame (per mesh,
/// 1 when a pixel showed it; empty before the first frame), kept by the algorithm object from
/// frame to frame and drawn first, untested, as occluders; every other mesh is tested as before.
/// Which meshes go first changes only what is culled, never the image.
struct MeshesShown {
  std::vector<uint8_t> shown;
};

/// The textbook z-buffer with occlusion culling (hzb.cpp: objects tested against the z-pyramid,
/// their triangles drawn with a depth test at every pixel); with `coherence`, the last frame's
/// meshes drawn first, and this frame's recorded there.
void zbufferOcclusionCulled(const Scene& scene, const Camera& camera, const RenderOptions& options,
                            MeshesShown* coherence, Frame& frame);

/// The production z-buffer: binned, tiled, SIMD, multithreaded (zbuffer_tiled.cpp), with the
/// bins, tile buffers and occlusion buffer it keeps from one frame to the next.
class TiledZBuffer {
 public:
  TiledZBuffer();
  ~TiledZBuffer();
  void draw(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame);

  /// What drawInOrder did: the kernel's comparisons and wins, the triangle-tile pairs it skipped
  /// whole (behind, or under firstWins after, everything the tile held), the pixels covered and
  /// the bytes it kept.
  struct InOrderCounts {
    uint64_t tests = 0, wins = 0, skippedPairs = 0, covered = 0, memoryBytes = 0;
  };
  /// The tile pass over set-up triangles given in drawing order instead of a scene's (drawScene
  /// with raster=tiled, draw.cpp), into the whole frame. `firstWins`: each pixel shows the first
  /// triangle of the list that covers it (the list-priority rules: WhereUnwritten in the list's
  /// order, Overwrite in reverse), for at most 2^24 - 2 triangles. Each triangle is then drawn at
  /// a constant stored value, its place in the list (a priority key), so the kernel's depth test
  /// applies the rule and a full tile or block rejects the rest at once; each pixel is resolved
  /// from its winner's own planes, ids and colour. Otherwise: the depth test in the frame's
  /// format, ties to the first in the list.
  /// drawInOrder's priority keys: the k-th triangle of a firstWins list stores (k + 1) 2^-24 at
  /// every pixel (setPriority makes its planes a constant and returns the value; linear mapping
  /// over [0, 1]): exact in f32 and in double, so distinct and increasing down the list, and nearer
  /// than the clear value 1. The value is also its nearest bound (nearestStored's margins round
  /// back to it in f32). Strictly farther than what a pixel holds, a later triangle loses there,
  /// and a full tile or block rejects it whole.
  static const DepthSetup kPriorityDepth;
  static double setPriority(SetupTriangle& t, size_t k);
  static constexpr size_t kMostFirstWins = (size_t(1) << 24) - 2;

  /// Mesh culling for a frame drawn in an order that keeps each pixel's nearest fragment (the
  /// depth test, or an exact priority order such as the BSP tree's): the scene triangles of the
  /// meshes neither outside the view nor hidden (ascending), or null when culling does not pay for
  /// this frame (as draw() decides) — a hidden mesh has no fragment nearest at any pixel, so
  /// leaving it out keeps the image. `meshesCulled`: how many were found hidden.
  const std::vector<TriangleRange>* visibleMeshes(const Scene& scene, const Camera& camera,
                                                  const RenderOptions& options, uint64_t& meshesCulled);
  InOrderCounts drawInOrder(std::span<const SetupTriangle> triangles, bool firstWins, const Camera& camera,
                            const RenderOptions& options, const TriangleShader& shade, Frame& frame);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// A scene's CSG tree (Scene::csg) as the algorithms evaluate it (csg.cpp): each triangle's solid,
/// and the tree's value at a point inside a set of solids.
class CsgTree {
 public:
  /// Throws InputError for a malformed tree (operands after their node, solids overlapping or
  /// outside the scene, more than kMaxCsgSolids solids).
  explicit CsgTree(const Scene& scene);
  /// The solid (0..solids() - 1) triangle t's face belongs to, or -1: a plain surface.
  int solidOf(uint32_t t) const { return solidOfTriangle_[t]; }
  /// Whether a point inside exactly the solids of `inside` (bit s: solid s) lies in the tree's result.
  bool contains(uint64_t inside) const;
  size_t solids() const { return solids_; }

 private:
  std::vector<CsgNode> nodes_;
  std::vector<uint8_t> solidOfNode_;
  std::vector<int8_t> solidOfTriangle_;
  size_t solids_ = 0;
};

/// The exact reference of a scene with a CSG tree (csg.cpp; raycast and --verify use it): per
/// pixel ray, every hit of the scene's triangles (the watertight test, bvh.hpp), sorted; the
/// solids holding the ray's start from the hits beyond it (past the far plane too); the visible
/// surface is the first hit of a plain surface, or the first at which the tree's value changes,
/// within the far plane. Queries are const and safe from many threads at once.
class CsgRays {
 public:
  CsgRays(const Scene& scene, const Camera& camera);
  /// What one thread's queries reuse.
  struct Scratch {
    std::vector<RayHit> hits;
    std::vector<int> solid, facing;
  };
  /// The visible surface through pixel position (px, py): its triangle and eye depth t.
  RayHit tracePixel(double px, double py, Scratch& scratch, TraceCounters& counters) const;
  uint64_t degenerateTriangles() const { return bvh_.degenerateTriangles(); }
  uint64_t memoryBytes() const { return bvh_.memoryBytes(); }

 private:
  const Scene& scene_;
  const Camera& camera_;
  const Camera unbounded_;  // the camera without its far plane
  const CameraSpaceBvh bvh_;
  const CsgTree tree_;
};
/// Whether every vertex of the tree's solids lies strictly between the near and far planes
/// (true without a tree): then every pixel's ray starts outside every solid.
bool csgSolidsWithinDepthRange(const Scene& scene, const Camera& camera);
/// Throws InputError when `options` cannot show the scene's CSG tree (culling removes the faces
/// it counts).
void checkCsgOptions(const Scene& scene, const RenderOptions& options);

/// Adds the frame's sized buffers to st.memory ("frame.depth", "frame.color", ...): part of every
/// algorithm's memory.
void addFrameMemory(Stats& st, const Frame& frame);

/// Starts a frame's statistics: image size, faces and triangles of the scene, all else zero
/// (frame_stats.cpp; render() starts every frame's statistics so, as does the occlusion buffer).
/// The storage of `st`'s lists is kept for the frame.
void beginStats(Stats& st, const Scene& scene, const Camera& camera);

/// Throws InputError unless the camera's image size is in 1..kMaxImageSize and the depth format
/// suits the camera (frame_stats.cpp; checked by render() and the occlusion buffer).
void checkImage(const Camera& camera, DepthFormat format);

/// Whether the occlusion buffer culls this scene mesh by mesh (occlusion.cpp: at least 64
/// meshes, a perspective camera, the switch mesh-culling on).
bool meshCullingApplies(const Scene& scene, const Camera& camera, const TiledSwitches& switches);
/// Whether a frame of this scene may gain from mesh culling's first pass (algo::cullMeshes):
/// meshCullingApplies, and the scene holds enough triangles for the pass over every tile of the
/// image (occlusion.cpp, kFrameWaitingPerTile); cullMeshes then decides by the meshes it can test.
bool meshCullingPaysForFrame(const Scene& scene, const Camera& camera, const TiledSwitches& switches);

}  // namespace hsr::algo

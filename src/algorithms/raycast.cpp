// Ray casting, the image-space algorithm of the KTH thesis and the exact reference of --verify:
// one ray per pixel centre, nearest hit in double precision with a watertight test, no
// sub-pixel snapping and no depth quantization. A scene with a CSG tree is cast as the tree's
// result (CsgRays, csg.cpp). Rows run in parallel; any thread count gives the same bits. Called
// through render() (registry.cpp).
#include "algorithms/algorithms.hpp"
#include "algorithms/bvh.hpp"
#include "core/parallel.hpp"
#include "scene/shading.hpp"
#include "core/timer.hpp"

#include <optional>

namespace hsr::algo {
namespace {

void raycast(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame) {
  Timer timer;
  checkCsgOptions(scene, options);
  frame.resize(camera.width, camera.height, options.background, resolveThreads(options.threads));
  std::optional<CameraSpaceBvh> bvh;
  std::optional<CsgRays> csg;
  if (scene.csg.empty()) bvh.emplace(scene, camera);
  else csg.emplace(scene, camera);
  Stats& st = frame.stats;
  st.addTime("build", timer.lap());

  // Per-row counters, summed afterwards, so that rows share nothing while they run.
  struct RowCounters {
    TraceCounters trace;
    uint64_t covered = 0;
  };
  std::vector<RowCounters> rows(size_t(camera.height));
  const TriangleShader shadeTriangleIndex(scene, camera, options.shading);
  parallelFor(0, size_t(camera.height), resolveThreads(options.threads), [&](size_t y) {
    RowCounters& row = rows[y];
    int32_t shadedTriangle = -1;  // neighbouring pixels mostly show the same triangle
    Rgba8 shade;
    CsgRays::Scratch scratch;
    for (int x = 0; x < camera.width; ++x) {
      const RayHit hit = csg ? csg->tracePixel(x + 0.5, double(y) + 0.5, scratch, row.trace)
                             : bvh->tracePixel(x + 0.5, double(y) + 0.5, options.cull, row.trace);
      if (!hit.found()) continue;
      if (hit.triangle != shadedTriangle) {
        shadedTriangle = hit.triangle;
        shade = shadeTriangleIndex(uint32_t(hit.triangle));
      }
      const size_t idx = frame.index(x, int(y));
      frame.faceId[idx] = int32_t(scene.triangles[size_t(hit.triangle)].face);
      frame.triangleId[idx] = hit.triangle;
      frame.depth[idx] = float(hit.t);
      frame.color[idx] = shade;
      if (!frame.writes.empty()) frame.writes[idx] = 1;  // each pixel is written once
      ++row.covered;
    }
  });
  st.addTime("trace", timer.lap());

  // (name, parameters, image size, faces and triangles: render() sets them)
  st.triangles_degenerate = csg ? csg->degenerateTriangles() : bvh->degenerateTriangles();
  st.depth_tests = st.depth_writes = st.covered_pixels = 0;
  for (const RowCounters& row : rows) {
    st.depth_tests += row.trace.tests;
    st.depth_writes += row.trace.hits;
    st.covered_pixels += row.covered;
  }
  st.color_writes = st.covered_pixels;  // each covered pixel is written once
  st.addMemory("bvh", csg ? csg->memoryBytes() : bvh->memoryBytes());
  addFrameMemory(st, frame);
}

// The reference keeps nothing between views: each builds its camera-space BVH anew.
class Raycast final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    raycast(scene_, camera, options, frame);
  }
};

}  // namespace

AlgorithmInfo raycastAlgorithm() {
  AlgorithmInfo a;
  a.name = "raycast";
  a.summary = "ray casting: one ray per pixel centre, the nearest hit in double precision (a CSG tree's result "
              "from all the hits); the exact reference";
  a.source = "KTH thesis";
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "it is the reference";
  a.capability = Capability::Csg;
  a.create = factoryOf<Raycast>();
  return a;
}

}  // namespace hsr::algo

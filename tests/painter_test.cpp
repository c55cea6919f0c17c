// The painter's family on the drawing service: the painter's declared failures per sort key, the
// reverse painter's zero overdraw, the sorted z-buffer's overdraw against submission order.
#include <gtest/gtest.h>

#include <hsr/hsr.hpp>

#include <algorithm>

#include "algorithms/algorithms.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr {
namespace {

Frame renderWith(const std::string& sceneName, const std::string& algorithm,
                 std::map<std::string, std::string> params, int w = 160, int h = 120, bool verify = true) {
  const Scene scene = loadScene(sceneName);
  const Camera cam = resolveCamera(scene.camera ? *scene.camera : frameBounds(scene.bounds()), w, h, scene.bounds());
  RenderOptions o;
  o.algorithm = algorithm;
  o.params = std::move(params);
  o.verify = verify;
  o.threads = 2;
  return render(scene, cam, o);
}

// Which key fails on which of the painter's failure scenes, with each scene's own camera: the
// record of a known, explained mismatch (docs/algorithms/painter.md), as the registry declares it.
TEST(Painter, EachKeyFailsWhereItIsDeclaredToAndOnlyThere) {
  const AlgorithmInfo& painter = *findAlgorithm("painter");
  for (const char* key : {"centroid", "max", "min", "mean-vertex"}) {
    const Guarantee g = painter.guaranteeWith(resolveParams(painter, {{"sort-key", key}}));
    for (const char* scene : {"builtin:painter-midpoint", "builtin:painter-cycle", "builtin:interpenetrate"}) {
      const bool declared = std::find(g.failsOn.begin(), g.failsOn.end(), scene) != g.failsOn.end();
      const Frame f = renderWith(scene, "painter", {{"sort-key", key}});
      EXPECT_EQ(*f.stats.wrong_pixels > 0, declared) << key << " on " << scene << ": " << *f.stats.wrong_pixels;
      EXPECT_EQ(f.stats.depth_tests, 0u);  // no depth buffer
    }
  }
  // The documents' own failure: the default key (the midpoint) is wrong on all three.
  EXPECT_EQ(painter.guarantee.failsOn.size(), 3u);
}

TEST(Painter, RasterizersPaintTheSameImage) {
  const Frame binned = renderWith("builtin:random?n=300&seed=2", "painter", {{"raster", "binned"}}, 200, 130, false);
  const Frame scalar = renderWith("builtin:random?n=300&seed=2", "painter", {{"raster", "halfspace"}}, 200, 130, false);
  EXPECT_EQ(binned.faceId, scalar.faceId);
  EXPECT_EQ(binned.depth, scalar.depth);
  EXPECT_EQ(binned.color, scalar.color);
  EXPECT_EQ(binned.stats.color_writes, scalar.stats.color_writes);
}

// Random intersecting triangles, a third opaque, a third at opacity 0.5 and a third at 0.15: an
// opaque fragment before, between and after translucent ones in every order.
Scene mixedOpacity() {
  Scene scene = loadScene("builtin:random?n=300&seed=7");
  for (size_t f = 0; f < scene.faceColors.size(); ++f) scene.faceColors[f].a = f % 3 == 0 ? 255 : f % 3 == 1 ? 128 : 38;
  return scene;
}

// raster=tiled (the z-buffer's tile kernel on priority keys) against the scalar binned form:
// the same face ids, triangle ids, depths and colours, for every algorithm of the family, on
// scenes of their own geometry and of derived fragments (bsp, newell), on 1 and 3 threads, with
// hidden meshes culled where the order allows; with transparency, blended over and under on the
// kernel (the sorted z-buffer's blending depth test falls back to the binned form).
TEST(Painter, TheTileKernelPaintsTheSameImageAsTheScalarForm) {
  for (const char* algorithm : {"painter", "reverse-painter", "newell", "bsp", "sorted-zbuffer"})
    for (const char* sceneName :
         {"builtin:random?n=300&seed=2", "builtin:city", "builtin:painter-cycle", "builtin:glass", "mixed"}) {
      const Scene scene = sceneName == std::string("mixed") ? mixedOpacity() : loadScene(sceneName);
      const Camera cam = resolveCamera(scene.camera ? *scene.camera : frameBounds(scene.bounds()), 200, 130, scene.bounds());
      RenderOptions o;
      o.algorithm = algorithm;
      o.outputs = FrameOutputs::All;
      o.params = {{"raster", "binned"}};
      o.threads = 2;
      const Frame scalar = render(scene, cam, o);
      o.params = {{"raster", "tiled"}};
      for (int threads : {1, 3}) {
        o.threads = threads;
        const Frame kernel = render(scene, cam, o);
        const std::string what = std::string(algorithm) + " on " + sceneName + ", threads " + std::to_string(threads);
        EXPECT_EQ(kernel.faceId, scalar.faceId) << what;
        EXPECT_EQ(kernel.triangleId, scalar.triangleId) << what;
        EXPECT_EQ(kernel.depth, scalar.depth) << what;
        EXPECT_EQ(kernel.color, scalar.color) << what;
        EXPECT_EQ(kernel.stats.covered_pixels, scalar.stats.covered_pixels) << what;
        const bool transparent = std::string(sceneName) == "builtin:glass" || std::string(sceneName) == "mixed";
        // (the sorted z-buffer's transparent pass, a depth test that blends, draws binned)
        const bool binned = transparent && std::string(algorithm) == "sorted-zbuffer";
        EXPECT_EQ(kernel.stats.detailText("rasterizer"), binned ? "binned" : "tiled") << what;
        // Orders that keep each pixel's nearest fragment (bsp's, the depth test) cull the city's
        // hidden meshes first: the images above are the same with them left out.
        const std::string name = algorithm;
        if (std::string(sceneName) == "builtin:city" && (name == "bsp" || name == "reverse-painter" || name == "sorted-zbuffer"))
          EXPECT_GT(kernel.stats.detailCount("meshes_culled_occlusion").value_or(0), 100u) << what;
        else
          EXPECT_FALSE(kernel.stats.detailCount("meshes_culled_occlusion")) << what;
      }
    }
}

// The priority keys: constant planes whose every fragment stores the key, whose nearest bound is
// the key itself (so a full tile rejects what follows), distinct and increasing down the list.
TEST(Painter, PriorityKeysAreExactAndTheirOwnBounds) {
  const DepthSetup& depth = algo::TiledZBuffer::kPriorityDepth;
  double last = 0;
  for (size_t k : {size_t(0), size_t(1), size_t(4095), size_t(4096), size_t(1) << 20, algo::TiledZBuffer::kMostFirstWins - 1}) {
    SetupTriangle t{};
    t.x[1] = 3 * kSubpixelOne, t.y[2] = 3 * kSubpixelOne, t.maxX = 2, t.maxY = 2;
    const double value = algo::TiledZBuffer::setPriority(t, k);
    EXPECT_GT(value, last) << k;
    EXPECT_LT(value, depth.format.clearValue()) << k;
    last = value;
    EXPECT_EQ(nearestStored(t, depth), value) << k;
    const MappedPlanes m = mapPlanes<DepthMapping::Linear>(t.depthNum, t.depthDen, depth.near, depth.far, false);
    for (double y : {0.5, 1.5, 999.5})
      EXPECT_EQ(fragmentStored<DepthStorage::F32>(m, 1.5, m.p.b * y, m.q.b * y), value) << k;
  }
}

TEST(ReversePainter, NeverOverdrawsAndStopsWhenFull) {
  for (const BuiltinInfo& b : builtinScenes()) {
    if (b.name == "sphere" || b.name == "random") continue;  // (large defaults; random below)
    for (const char* raster : {"binned", "halfspace"}) {
      const Frame f = renderWith("builtin:" + b.name, "reverse-painter", {{"raster", raster}}, 96, 72, false);
      // (With transparent faces a pixel takes fragments until it is opaque.)
      if (b.name == "glass") EXPECT_GT(f.stats.color_writes, f.stats.covered_pixels) << raster;
      else EXPECT_EQ(f.stats.color_writes, f.stats.covered_pixels) << b.name << " " << raster;
    }
  }
  // The layers fill the view: the first (nearest) layer fills it, the rest is skipped.
  const Frame layers = renderWith("builtin:layers?n=64", "reverse-painter", {{"raster", "halfspace"}}, 96, 72, false);
  EXPECT_EQ(layers.stats.covered_pixels, 96u * 72u);
  EXPECT_GT(layers.stats.detailCount("skipped_full").value_or(0), 100u);
  // Its image is the painter's with the same key.
  const Frame a = renderWith("builtin:random?n=500&seed=4", "reverse-painter", {{"order", "max"}}, 120, 90, false);
  const Frame b = renderWith("builtin:random?n=500&seed=4", "painter", {{"sort-key", "max"}}, 120, 90, false);
  EXPECT_EQ(a.faceId, b.faceId);
}

TEST(SortedZBuffer, ExactWithLessOverdrawThanSubmissionOrder) {
  const Frame sorted = renderWith("builtin:random?n=2000&seed=6", "sorted-zbuffer", {}, 320, 240);
  const Frame textbook = renderWith("builtin:random?n=2000&seed=6", "zbuffer", {{"raster", "halfspace"}}, 320, 240);
  EXPECT_EQ(*sorted.stats.wrong_pixels, 0u);
  EXPECT_EQ(*textbook.stats.wrong_pixels, 0u);
  EXPECT_EQ(sorted.stats.covered_pixels, textbook.stats.covered_pixels);
  EXPECT_EQ(sorted.stats.depth_tests, textbook.stats.depth_tests);  // every fragment tested either way
  EXPECT_LT(sorted.stats.color_writes, textbook.stats.color_writes);
}

}  // namespace
}  // namespace hsr

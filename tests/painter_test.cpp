// The painter's family on the drawing service: the painter's declared failures per sort key, the
// reverse painter's zero overdraw, the sorted z-buffer's overdraw against submission order.
#include <gtest/gtest.h>

#include <hsr/hsr.hpp>

#include <algorithm>

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

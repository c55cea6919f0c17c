// The hierarchical z-buffer (src/algorithms/hzb.cpp): exact at any image size (1x1 and 3x1000
// included), its pyramid's counters consistent, and fewer per-pixel depth tests than the
// textbook z-buffer on the stacked layers and the city.
#include <gtest/gtest.h>

#include <hsr/hsr.hpp>

#include <set>
#include <string>

namespace hsr {
namespace {

Frame renderWith(const Scene& scene, const std::string& algorithm, std::map<std::string, std::string> params, int w,
                 int h, bool verify = true) {
  const Camera cam = resolveCamera(scene.camera ? *scene.camera : frameBounds(scene.bounds()), w, h, scene.bounds());
  RenderOptions o;
  o.algorithm = algorithm;
  o.params = std::move(params);
  o.verify = verify;
  o.threads = 1;
  return render(scene, cam, o);
}

uint64_t detail(const Stats& st, const std::string& key) {
  const std::optional<uint64_t> v = st.detailCount(key);
  EXPECT_TRUE(v.has_value()) << key;
  return v.value_or(0);
}

// The counted property of the issue: on the stacked layers (submitted back to front) and the city
// the pyramid rejects hidden triangles before their pixels, so hzb tests fewer pixels than the
// textbook z-buffer tests fragments; with the same image.
TEST(Hzb, FewerPixelTestsThanTheTextbookZBufferOnLayersAndCity) {
  for (const char* name : {"builtin:layers", "builtin:city"}) {
    const Scene scene = loadScene(name);
    const Frame textbook = renderWith(scene, "zbuffer", {{"raster", "halfspace"}}, 320, 180, false);
    const Frame hzb = renderWith(scene, "hzb", {}, 320, 180);
    EXPECT_EQ(*hzb.stats.wrong_pixels, 0u) << name;
    EXPECT_LT(hzb.stats.depth_tests, textbook.stats.depth_tests) << name;
    EXPECT_EQ(hzb.stats.covered_pixels, textbook.stats.covered_pixels) << name;
    // Drawn in submission order, the layers come back to front: nothing is behind anything drawn
    // so far, and every fragment is tested, as in the textbook z-buffer.
    if (std::string(name) == "builtin:layers") {
      const Frame submission = renderWith(scene, "hzb", {{"order", "submission"}}, 320, 180);
      EXPECT_EQ(*submission.stats.wrong_pixels, 0u);
      EXPECT_EQ(submission.stats.depth_tests, textbook.stats.depth_tests);
    }
  }
}

// Odd image sizes: the pyramid folds single entries into the level above (1x1 has one level).
TEST(Hzb, ExactAtOddImageSizes) {
  const Scene city = loadScene("builtin:city");
  const Scene random = loadScene("builtin:random?n=400&seed=3");
  for (auto [w, h] : {std::pair{1, 1}, {3, 1000}, {1000, 3}, {37, 23}, {129, 67}, {9, 17}}) {
    for (const Scene* scene : {&city, &random}) {
      const Frame f = renderWith(*scene, "hzb", {}, w, h);
      EXPECT_EQ(*f.stats.wrong_pixels, 0u) << w << "x" << h;
    }
    // Levels: 8x8 tiles, then halved (rounding up) down to one entry.
    int tw = (w + 7) / 8, th = (h + 7) / 8, levels = 1;
    while (tw > 1 || th > 1) {
      tw = (tw + 1) / 2;
      th = (th + 1) / 2;
      ++levels;
    }
    const Frame f = renderWith(city, "hzb", {}, w, h, false);
    EXPECT_EQ(detail(f.stats, "levels"), uint64_t(levels)) << w << "x" << h;
  }
}

// Every entry tested is rejected or descended into; only the level-0 tiles descended into test
// pixels (at most 64 each); every rejection at a level saves a test of its children below.
TEST(Hzb, LevelCountersAddUp) {
  const Scene scene = loadScene("builtin:city");
  const Frame f = renderWith(scene, "hzb", {}, 640, 360, false);
  const uint64_t levels = detail(f.stats, "levels");
  ASSERT_EQ(levels, 8u);  // 80x45 tiles, 40x23, 20x12, 10x6, 5x3, 3x2, 2x1, 1x1
  uint64_t rejected = 0;
  for (uint64_t k = 0; k < levels; ++k) {
    const std::string level = "level" + std::to_string(k);
    EXPECT_EQ(detail(f.stats, level + "_tested"), detail(f.stats, level + "_rejected") + detail(f.stats, level + "_descended"))
        << level;
    rejected += detail(f.stats, level + "_rejected");
  }
  EXPECT_LE(f.stats.depth_tests, 64 * detail(f.stats, "level0_descended"));
  EXPECT_GT(f.stats.depth_tests, detail(f.stats, "level0_descended"));
  EXPECT_GT(rejected, 0u);  // the city hides much
  EXPECT_EQ(f.stats.detailText("pyramid_updates"), "exact");
}

// Occlusion culling (hzb's occlusion-cull=on, and zbuffer-culled on the textbook z-buffer): the same image as
// without, meshes dropped whole before set-up, and most of the city's hidden triangles among them.
TEST(Hzb, OcclusionCullingIsExactAndCullsMostOfTheCitysHiddenTriangles) {
  const Scene city = loadScene("builtin:city");
  const Frame plain = renderWith(city, "hzb", {}, 640, 360);
  const Frame culled = renderWith(city, "hzb", {{"occlusion-cull", "on"}}, 640, 360);
  const Frame textbook = renderWith(city, "zbuffer", {{"raster", "halfspace"}}, 640, 360, false);
  const Frame textbookCulled = renderWith(city, "zbuffer-culled", {}, 640, 360);
  EXPECT_EQ(*culled.stats.wrong_pixels, 0u);
  EXPECT_EQ(*textbookCulled.stats.wrong_pixels, 0u);
  EXPECT_EQ(culled.stats.covered_pixels, plain.stats.covered_pixels);
  EXPECT_EQ(textbookCulled.stats.covered_pixels, textbook.stats.covered_pixels);
  EXPECT_LT(textbookCulled.stats.depth_tests, textbook.stats.depth_tests);
  EXPECT_EQ(culled.stats.culled_occlusion, detail(culled.stats, "triangles_culled"));
  EXPECT_GT(detail(culled.stats, "objects_culled"), detail(culled.stats, "objects") / 2);
  // Hidden: the triangles set up without culling that show at no pixel. Culled among them: those
  // no longer set up.
  std::set<int32_t> shown(plain.triangleId.begin(), plain.triangleId.end());
  shown.erase(-1);
  const uint64_t setUp = detail(plain.stats, "triangles_drawn"), setUpCulled = detail(culled.stats, "triangles_drawn");
  const double fraction = double(setUp - setUpCulled) / double(setUp - shown.size());
  std::printf("city at 640x360: %llu of %llu hidden triangles culled before set-up (%.1f%%)\n",
              (unsigned long long)(setUp - setUpCulled), (unsigned long long)(setUp - shown.size()), 100 * fraction);
  EXPECT_GT(fraction, 0.75);
  // Odd sizes.
  for (auto [w, h] : {std::pair{1, 1}, {3, 1000}, {37, 23}}) {
    EXPECT_EQ(*renderWith(city, "hzb", {{"occlusion-cull", "on"}}, w, h).stats.wrong_pixels, 0u) << w << "x" << h;
    EXPECT_EQ(*renderWith(city, "zbuffer-culled", {}, w, h).stats.wrong_pixels, 0u) << w << "x" << h;
  }
}

// Temporal coherence (zbuffer-culled temporal=on): over an orbit, one object carries the meshes each
// frame showed into the next, drawn first; every frame is the same image as without it.
TEST(Hzb, TemporalCoherenceCarriesTheLastFramesMeshesAndKeepsTheImage) {
  const Scene city = loadScene("builtin:city");
  const Camera camera = resolveCamera(frameBounds(city.bounds()), 320, 240, city.bounds());
  const std::vector<Camera> orbit = orbitCameras(camera, city.bounds().center(), 24);
  RenderOptions options;
  options.algorithm = "zbuffer-culled";
  options.threads = 1;
  Renderer without(city, options);
  options.params = {{"temporal", "on"}};
  Renderer with(city, options);
  uint64_t setUpWithout = 0, setUpWith = 0;
  for (size_t i = 0; i < orbit.size(); ++i) {
    const Frame a = without.render(orbit[i]), b = with.render(orbit[i]);
    ASSERT_EQ(a.faceId, b.faceId) << "pose " << i;
    ASSERT_EQ(a.depth, b.depth) << "pose " << i;
    EXPECT_EQ(b.stats.detailText("temporal"), "on");
    // The first frame has no last frame; every later one starts from the meshes the last one showed.
    if (i == 0) EXPECT_EQ(detail(b.stats, "objects_carried"), 0u);
    else EXPECT_GT(detail(b.stats, "objects_carried"), 0u) << "pose " << i;
    setUpWithout += a.stats.triangles - a.stats.culled_frustum - a.stats.culled_occlusion;
    setUpWith += b.stats.triangles - b.stats.culled_frustum - b.stats.culled_occlusion;
  }
  std::printf("city 320x240, orbit of 24: %llu triangles set up without temporal coherence, %llu with\n",
              (unsigned long long)setUpWithout, (unsigned long long)setUpWith);
}

}  // namespace
}  // namespace hsr

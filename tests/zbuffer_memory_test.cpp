// The z-buffer's memory and clearing savers (src/algorithms/zbuffer_regions.cpp,
// zbuffer_half_range.cpp) and the memory
// statistics per buffer: the regional z-buffer gives the textbook z-buffer's image bit for bit
// with a region's buffer; the half-range z-buffer, never cleared between frames, gives over many
// frames what each frame drawn from a cleared buffer gives; the documents' memory figures are
// what the statistics report.
#include <gtest/gtest.h>

#include <hsr/hsr.hpp>
#include <hsr/orbit.hpp>

#include <cstring>
#include <string>

namespace hsr {
namespace {

Camera cameraFor(const Scene& scene, int w, int h) {
  return resolveCamera(scene.camera ? *scene.camera : frameBounds(scene.bounds()), w, h, scene.bounds());
}

RenderOptions optionsWith(std::map<std::string, std::string> params, const char* format = "f32:reversed",
                          const char* algorithm = "zbuffer") {
  RenderOptions o;
  o.algorithm = algorithm;
  o.params = std::move(params);
  o.depthFormat = DepthFormat::parse(format);
  o.threads = 1;
  return o;
}

uint64_t memoryOf(const Stats& st, std::string_view buffer) {
  for (const auto& [name, bytes] : st.memory)
    if (name == buffer) return bytes;
  return 0;
}

void expectSameImage(const Frame& a, const Frame& b, const std::string& what) {
  EXPECT_EQ(a.faceId, b.faceId) << what;
  EXPECT_EQ(a.triangleId, b.triangleId) << what;
  EXPECT_EQ(a.depth, b.depth) << what;
  EXPECT_EQ(a.color, b.color) << what;
}

TEST(RegionalZBuffer, SameImageAsTheWholeBufferWithARegionsMemory) {
  for (const char* name : {"builtin:city", "builtin:layers?n=12", "builtin:random?n=300&seed=4"}) {
    const Scene scene = loadScene(name);
    const Camera cam = cameraFor(scene, 203, 117);
    const Frame whole = render(scene, cam, optionsWith({{"raster", "halfspace"}}, "u16:z"));
    for (const char* region : {"1x1", "16x16", "50x7", "203x117", "999x999"}) {
      const Frame regional = render(scene, cam, optionsWith({{"region", region}}, "u16:z", "zbuffer-regions"));
      const std::string what = std::string(name) + " region=" + region;
      expectSameImage(regional, whole, what);
      EXPECT_EQ(regional.stats.depth_tests, whole.stats.depth_tests) << what;
      EXPECT_EQ(regional.stats.depth_writes, whole.stats.depth_writes) << what;
      EXPECT_EQ(regional.stats.covered_pixels, whole.stats.covered_pixels) << what;
      const int rw = std::min(std::stoi(region), 203), rh = std::min(std::stoi(std::strchr(region, 'x') + 1), 117);
      EXPECT_EQ(memoryOf(regional.stats, "depth_buffer"), uint64_t(rw) * uint64_t(rh) * 2) << what;
    }
  }
}

TEST(RegionalZBuffer, BadSizesAreRefused) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera cam = cameraFor(scene, 40, 30);
  for (const char* bad : {"0x4", "4x0", "4", "x4", "4x", "4.5x4", "-4x4", "4x4x4", "nanx4", "99999x4"})
    EXPECT_THROW(render(scene, cam, optionsWith({{"region", bad}}, "f32:reversed", "zbuffer-regions")), InputError)
        << bad;
  // The variants' parameters are their own: no combination to refuse by hand.
  try {
    render(scene, cam, optionsWith({{"region", "8x8"}}));
    ADD_FAILURE() << "zbuffer took region";
  } catch (const InputError& e) {  // the message says which algorithm has it
    EXPECT_NE(std::string(e.what()).find("zbuffer-regions take it"), std::string::npos) << e.what();
  }
  EXPECT_THROW(render(scene, cam, optionsWith({{"raster", "scanline"}}, "f32:reversed", "zbuffer-regions")),
               InputError);
  EXPECT_THROW(render(scene, cam, optionsWith({{"slices", "2"}}, "f32:reversed", "zbuffer-half-range")), InputError);
}

// Frames of an orbit drawn by one algorithm object without clearing its buffer: each the same bits as that frame drawn
// alone (from a cleared buffer), in every depth format; and exact against the ray caster.
TEST(HalfRangeZBuffer, ManyFramesWithoutClearingGiveTheClearedImages) {
  const Scene scene = loadScene("builtin:city");
  const Camera first = cameraFor(scene, 97, 61);
  const Bounds3 b = scene.bounds();
  const std::vector<Camera> orbit = orbitCameras(first, (b.lo + b.hi) * 0.5, 9);
  for (const char* format : {"f32:reversed", "u16:z", "u24:z", "u32:inv", "f32:linear"}) {
    RenderOptions o = optionsWith({}, format, "zbuffer-half-range");
    Renderer renderer(scene, o);  // keeps the half-range buffer from frame to frame
    Frame kept;
    for (size_t i = 0; i < orbit.size(); ++i) {
      renderer.render(orbit[i], kept);
      const Frame alone = render(scene, orbit[i], o);
      const std::string what = std::string(format) + " frame " + std::to_string(i);
      expectSameImage(kept, alone, what);
      EXPECT_EQ(kept.stats.depth_writes, alone.stats.depth_writes) << what;
      EXPECT_EQ(*kept.stats.detailCount("cleared"), i == 0 ? 1u : 0u) << what;
      EXPECT_EQ(kept.stats.detailText("half"), i % 2 ? "upper" : "lower") << what;
      if (i > 0) EXPECT_GT(*kept.stats.detailCount("pixels_reset") + kept.stats.covered_pixels, 0u) << what;
    }
  }
  RenderOptions verify = optionsWith({}, "f32:reversed", "zbuffer-half-range");
  verify.verify = true;
  Renderer verified(scene, verify);
  Frame kept;
  for (const Camera& cam : orbit) {
    verified.render(cam, kept);
    EXPECT_EQ(*kept.stats.wrong_pixels, 0u);
  }
}

// A pixel drawn two frames ago and not since must not show or occlude: the scene moves out of
// part of the image between frames.
TEST(HalfRangeZBuffer, NoStaleSurfaceSurvivesTwoFrames) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera near = cameraFor(scene, 80, 60);
  Camera far = near;
  const double size = glm::length(scene.bounds().hi - scene.bounds().lo);
  far.cameraFromWorld[3] += glm::dvec4(0.3 * size, 0, 0.5 * size, 0);  // the scene moved aside and away
  far.far += 0.5 * size;
  RenderOptions o = optionsWith({}, "f32:reversed", "zbuffer-half-range");
  Renderer renderer(scene, o);
  Frame kept;
  for (const Camera* cam : std::vector<const Camera*>{&near, &far, &far, &near, &far}) {
    renderer.render(*cam, kept);
    expectSameImage(kept, render(scene, *cam, o), "after a change of view");
  }
}

// The documents' figures, read off the statistics of real frames (docs/memory.md).
TEST(MemoryStatistics, TheDocumentsFiguresPerBuffer) {
  const Scene scene = loadScene("builtin:cubes");
  // A 16-bit z-buffer at 1024x768: 1.5 MiB (the Java chapter).
  const Frame u16 = render(scene, cameraFor(scene, 1024, 768), optionsWith({{"raster", "halfspace"}}, "u16:z"));
  EXPECT_EQ(memoryOf(u16.stats, "depth_buffer"), 1024u * 768u * 2u);
  // 32-bit colour and 32-bit z at 1024x768: 8 bytes per pixel, 6 MiB (the lecture notes).
  const Frame u32 = render(scene, cameraFor(scene, 1024, 768), optionsWith({{"raster", "halfspace"}}, "u32:z"));
  EXPECT_EQ(memoryOf(u32.stats, "depth_buffer") + memoryOf(u32.stats, "frame.color"), 1024u * 768u * 8u);
  // Every algorithm's memory_bytes is the sum of its buffers.
  for (const AlgorithmInfo& a : algorithms()) {
    RenderOptions o = optionsWith({});
    o.algorithm = a.name;
    const Frame f = render(scene, cameraFor(scene, 64, 48), o);
    uint64_t sum = 0;
    for (const auto& [name, bytes] : f.stats.memory) sum += bytes;
    EXPECT_EQ(sum, f.stats.memory_bytes) << a.name;
    EXPECT_GE(memoryOf(f.stats, "frame.depth"), 64u * 48u * 4u) << a.name;
  }
}

}  // namespace
}  // namespace hsr

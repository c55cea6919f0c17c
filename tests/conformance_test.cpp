// Conformance of the z-buffer against the exact reference (raycast): named scenes x camera
// poses x depth formats x rasterizers. A pixel may differ only where verify classifies it as
// ambiguous (depth closer than the format separates, or the centre on an edge); every other
// difference is a failure, printed with the pixel and a command that replays it.
#include <gtest/gtest.h>

#include <cmath>
#include <fmt/format.h>
#include <random>

#include "test_scenes.hpp"

namespace hsr {
namespace {

struct Pose {
  CameraSpec spec;
  std::string describe() const { return cameraSpecToJson(spec); }
};

// Seeded random poses around the scene: outside looking in, some close enough that geometry
// crosses the near plane, some orthographic, random field of view and roll.
std::vector<Pose> posesAround(const Scene& scene, int count, uint64_t seed) {
  Bounds3 b = scene.bounds();
  dvec3 c = b.center();
  double r = glm::length(b.hi - b.lo) * 0.5;
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  std::vector<Pose> poses;
  for (int i = 0; i < count; ++i) {
    double z = u() * 2 - 1, phi = u() * 2 * M_PI, s = std::sqrt(1 - z * z);
    dvec3 dir{s * std::cos(phi), z, s * std::sin(phi)};
    double dist = r * (0.4 + 2.6 * u());  // sometimes inside the bounds: near clipping
    Pose p;
    p.spec.eye = c + dir * dist;
    p.spec.target = c + dvec3(u() - 0.5, u() - 0.5, u() - 0.5) * r * 0.5;
    p.spec.up = glm::normalize(dvec3(u() - 0.5, 2, u() - 0.5));
    p.spec.fovyDeg = 25 + 70 * u();
    double eyeDist = glm::length(p.spec.eye - c);
    p.spec.near = std::max(r * 0.01, (eyeDist - r) * (0.5 + 0.6 * u()));  // cuts into the scene at times
    p.spec.far = (eyeDist + r) * (0.7 + 0.5 * u());                         // and at times cuts off its back
    if (i % 7 == 3) p.spec.orthoHeight = r * (1 + u());
    poses.push_back(p);
  }
  return poses;
}

struct Case {
  std::string scene;
  int poses;
};

Scene load(const std::string& name) {
  if (name == "test:boxes") return test::boxesScene();
  if (name == "test:soup") return test::randomSoup(200, 42);
  return loadScene(name);
}

const char* rasterName(RasterKind k) {
  switch (k) {
    case RasterKind::Tiled: return "tiled";
    case RasterKind::HalfSpace: return "halfspace";
    default: return "scanline";
  }
}

// Renders with verify and expects no wrong pixel; on failure prints a replay command.
void expectExact(const std::string& sceneName, const Scene& scene, const Pose& pose, const RenderOptions& opt,
                 int w, int h, uint64_t* ambiguous = nullptr) {
  Camera cam = resolveCamera(pose.spec, w, h, scene.bounds());
  RenderOptions o = opt;
  o.verify = true;
  o.threads = 1;
  Frame f = render(scene, cam, o);
  ASSERT_TRUE(f.stats.wrong_pixels.has_value());
  if (ambiguous) *ambiguous += *f.stats.ambiguous_pixels;
  EXPECT_EQ(*f.stats.wrong_pixels, 0u) << fmt::format(
      "scene {}, format {}, raster {}. Replay: save the camera below as cam.json, then\n"
      "  hsr render '{}' --camera cam.json --size {}x{} --depth-format {} --raster {} --verify --threads 1\n{}",
      sceneName, opt.depthFormat.name(), rasterName(opt.raster), sceneName, w, h, opt.depthFormat.name(),
      rasterName(opt.raster), pose.describe());
}

const std::vector<Case>& cases() {
  static const std::vector<Case> list = {
      {"test:boxes", 40},
      {"test:soup", 40},
      {"builtin:cubes", 40},
      {"builtin:random?n=400&seed=3", 30},
      {"builtin:painter-midpoint", 25},
      {"builtin:painter-cycle", 25},
      {"builtin:interpenetrate", 25},
      {"builtin:layers?n=12", 20},
      {"builtin:sphere?n=20000", 15},
      {"builtin:city", 12},
      {"builtin:zfight", 15},
  };
  return list;
}

// The z-buffer with the default format (f32:reversed), all three rasterizers: zero wrong pixels on
// every pose of every scene (287 poses in all).
TEST(Conformance, ZBufferF32ReversedIsExactOnAllPoses) {
  int poses = 0;
  for (const Case& c : cases()) {
    Scene scene = load(c.scene);
    for (const Pose& pose : posesAround(scene, c.poses, std::hash<std::string>{}(c.scene) & 0xffff)) {
      for (RasterKind raster : {RasterKind::Tiled, RasterKind::HalfSpace, RasterKind::Scanline}) {
        RenderOptions opt;
        opt.raster = raster;
        expectExact(c.scene, scene, pose, opt, 64, 48);
      }
      ++poses;
    }
  }
  EXPECT_GE(poses, 250);
}

// Every storage x mapping: no wrong pixels; differences only where the format's precision makes
// the pixel ambiguous. Low-precision formats must show such pixels on the z-fighting scene.
TEST(Conformance, EveryDepthFormatIsExactUpToItsPrecision) {
  const char* storages[] = {"u16", "u24", "u32", "f32"};
  const char* mappings[] = {"z", "reversed", "inv", "linear"};
  for (const char* sname : {"builtin:cubes", "builtin:random?n=300&seed=5", "builtin:zfight", "test:soup"}) {
    Scene scene = load(sname);
    auto poses = posesAround(scene, 6, 99);
    for (const char* st : storages)
      for (const char* m : mappings) {
        RenderOptions opt;
        opt.depthFormat = DepthFormat::parse(std::string(st) + ":" + m);
        for (const Pose& pose : poses) expectExact(sname, scene, pose, opt, 64, 48);
      }
  }
}

// The z-fighting scene with its own camera: u16:z cannot separate the two surfaces (many
// ambiguous pixels), f32:reversed can (none wrong, few ambiguous).
TEST(Conformance, ZFightingShowsAt16BitsNotWithReversedFloat) {
  Scene scene = loadScene("builtin:zfight");
  ASSERT_TRUE(scene.camera.has_value());
  Pose pose{*scene.camera};
  uint64_t amb16 = 0, amb32 = 0;
  RenderOptions opt;
  opt.depthFormat = DepthFormat::parse("u16:z");
  expectExact("builtin:zfight", scene, pose, opt, 128, 96, &amb16);
  opt.depthFormat = DepthFormat::parse("f32:reversed");
  expectExact("builtin:zfight", scene, pose, opt, 128, 96, &amb32);
  EXPECT_GT(amb16, 100u);
  EXPECT_LT(amb32 * 10, amb16);
}

// Same bits for any thread count.
TEST(Conformance, DeterministicAcrossThreadCounts) {
  Scene scene = load("builtin:random?n=400&seed=3");
  for (const Pose& pose : posesAround(scene, 5, 7)) {
    Camera cam = resolveCamera(pose.spec, 80, 60, scene.bounds());
    for (const char* algorithm : {"zbuffer", "raycast"}) {
      RenderOptions opt;
      opt.algorithm = algorithm;
      opt.threads = 1;
      Frame a = render(scene, cam, opt);
      opt.threads = 2;
      Frame b = render(scene, cam, opt);
      opt.threads = 3;
      Frame c = render(scene, cam, opt);
      EXPECT_EQ(a.faceId, b.faceId);
      EXPECT_EQ(a.depth, b.depth);
      EXPECT_EQ(a.faceId, c.faceId);
      EXPECT_EQ(a.depth, c.depth);
    }
  }
}

}  // namespace
}  // namespace hsr

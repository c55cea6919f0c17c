// Transparency: the A-buffer (abuffer.cpp) against a brute-force per-pixel blend; newell and bsp
// within rounding of it; the z-buffer family's sorted transparent pass visibly wrong on
// builtin:glass (a known, explained mismatch: one order per face cannot blend a cycle or an
// interpenetration); --verify's colour error; opaque scenes drawn as before.
#include <hsr/hsr.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "conformance.hpp"
#include "scene/shading.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

Frame renderWith(const Scene& scene, const Camera& camera, const std::string& algorithm) {
  RenderOptions options;
  options.algorithm = algorithm;
  options.threads = 1;
  return render(scene, camera, options);
}

// test:polygons with opacities 0.3 to 0.9 on every other face.
Scene translucentPolygons(uint64_t seed) {
  Scene s = test::randomPolygons(30, seed);
  for (size_t f = 0; f < s.faceColors.size(); f += 2) s.faceColors[f].a = uint8_t(77 + (f * 37) % 153);
  return s;
}

// Per pixel, by brute force in camera space: every triangle's hit by the centre's ray
// (Moller-Trumbore), one per face, nearest first, blended front to back in double. Returns
// false where a hit is within 1e-7 (barycentric) of a triangle's edge: there the exact test may
// decide either way.
bool bruteForcePixel(const Scene& scene, const Camera& camera, const TriangleShader& shade, int x, int y,
                     Rgba8& out) {
  dvec3 origin, dir;
  camera.cameraRay(x + 0.5, y + 0.5, origin, dir);
  std::vector<std::pair<double, uint32_t>> hits;
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    const Triangle& tri = scene.triangles[t];
    const dvec3 a = camera.toCamera(scene.positions[tri.v[0]]), b = camera.toCamera(scene.positions[tri.v[1]]),
                c = camera.toCamera(scene.positions[tri.v[2]]);
    const dvec3 e1 = b - a, e2 = c - a, p = glm::cross(dir, e2);
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) continue;
    const dvec3 s = origin - a, q = glm::cross(s, e1);
    const double u = glm::dot(s, p) / det, v = glm::dot(dir, q) / det, d = glm::dot(e2, q) / det;
    if (u < -1e-7 || v < -1e-7 || u + v > 1 + 1e-7) continue;
    if (u < 1e-7 || v < 1e-7 || u + v > 1 - 1e-7) return false;
    if (d < camera.near || d > camera.far) continue;
    hits.emplace_back(d, t);
  }
  std::sort(hits.begin(), hits.end());
  double r = 0, g = 0, b = 0, through = 1;
  std::vector<uint32_t> faces;
  for (const auto& [d, t] : hits) {
    const uint32_t face = scene.triangles[t].face;
    if (std::find(faces.begin(), faces.end(), face) != faces.end()) continue;
    faces.push_back(face);
    const Rgba8 c = shade(t);
    const double w = through * (c.a / 255.0);
    r += w * c.r;
    g += w * c.g;
    b += w * c.b;
    through *= 1 - c.a / 255.0;
  }
  // The background is opaque black.
  out = Rgba8{uint8_t(std::lround(r)), uint8_t(std::lround(g)), uint8_t(std::lround(b)), 255};
  return true;
}

TEST(Transparency, AbufferIsTheBruteForceBlend) {
  for (const Scene& scene : {loadScene("builtin:glass"), translucentPolygons(3), translucentPolygons(8)}) {
    std::vector<CameraSpec> cameras{conformance::ownPose(scene).spec};
    for (const conformance::Pose& p : conformance::posesAround(scene, 3, 21)) cameras.push_back(p.spec);
    for (const CameraSpec& spec : cameras) {
      const Camera camera = resolveCamera(spec, 48, 36, scene.bounds());
      const Frame a = renderWith(scene, camera, "abuffer");
      const TriangleShader shade(scene, camera, Shading::Lambert);
      uint64_t tested = 0, differ = 0;
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
          Rgba8 want;
          if (!bruteForcePixel(scene, camera, shade, x, y, want)) continue;
          ++tested;
          const Rgba8 got = a.color[a.index(x, y)];
          differ += got.r != want.r || got.g != want.g || got.b != want.b;
        }
      EXPECT_EQ(differ, 0u) << scene.source << "\n" << cameraSpecToJson(spec);
      EXPECT_GT(tested, uint64_t(camera.width * camera.height) / 2);
    }
  }
}

// The A-buffer's ids are the visibility reference's: the nearest fragment.
TEST(Transparency, AbufferIdsAreRaycasts) {
  const Scene scene = loadScene("builtin:glass");
  const Camera camera = resolveCamera(*scene.camera, 96, 72, scene.bounds());
  const Frame a = renderWith(scene, camera, "abuffer"), r = renderWith(scene, camera, "raycast");
  EXPECT_EQ(test::firstDifference(a.faceId, r.faceId), -1);
  EXPECT_EQ(test::firstDifference(a.depth, r.depth), -1);
}

// The glass scene and translucent polygons, each from its own camera and 4 around it, at 160x120,
// with the A-buffer's frame of each view.
template <class Check>
void forEachTranslucentView(Check&& check) {
  for (const Scene& scene : {loadScene("builtin:glass"), translucentPolygons(5)}) {
    std::vector<CameraSpec> cameras{conformance::ownPose(scene).spec};
    for (const conformance::Pose& p : conformance::posesAround(scene, 4, 9)) cameras.push_back(p.spec);
    for (const CameraSpec& spec : cameras) {
      const Camera camera = resolveCamera(spec, 160, 120, scene.bounds());
      check(scene, camera, spec, renderWith(scene, camera, "abuffer"));
    }
  }
}

TEST(Transparency, NewellAndBspBlendWithinRoundingOfTheAbuffer) {
  forEachTranslucentView([](const Scene& scene, const Camera& camera, const CameraSpec& spec, const Frame& reference) {
    for (const char* algorithm : {"newell", "bsp"}) {
      const algo::ColorError e = algo::colorError(renderWith(scene, camera, algorithm), reference);
      EXPECT_EQ(e.beyondStep, 0u) << algorithm << " on " << scene.source << "\n" << cameraSpecToJson(spec);
      EXPECT_LE(std::max({e.max[0], e.max[1], e.max[2]}), 1) << algorithm;
      EXPECT_GT(e.pixels, uint64_t(160 * 120) * 9 / 10) << algorithm;
    }
  });
}

// The reverse painter's front to back: each fragment composited under the nearer ones until the
// pixel is opaque, in float, rounded once as the A-buffer rounds: within one step of it (in the
// BSP tree's exact order); ids the nearest fragment's, as without transparency.
TEST(Transparency, ReversePainterBlendsFrontToBackWithinRoundingOfTheAbuffer) {
  forEachTranslucentView([](const Scene& scene, const Camera& camera, const CameraSpec& spec, const Frame& reference) {
    const Frame f = renderWith(scene, camera, "reverse-painter");
    EXPECT_EQ(f.stats.detailText("write_rule"), "blend-under");
    const algo::ColorError e = algo::colorError(f, reference);
    EXPECT_EQ(e.beyondStep, 0u) << scene.source << "\n" << cameraSpecToJson(spec);
    EXPECT_LE(std::max({e.max[0], e.max[1], e.max[2]}), 1) << scene.source;
    EXPECT_GT(e.pixels, uint64_t(160 * 120) * 9 / 10) << scene.source;
    RenderOptions idsOnly;
    idsOnly.algorithm = "reverse-painter";
    idsOnly.outputs = FrameOutputs::FaceIds;
    idsOnly.threads = 1;
    EXPECT_EQ(render(scene, camera, idsOnly).faceId, f.faceId) << scene.source;
  });
  // A sort key's front-to-back order is wrong on the glass scene's cycle and interpenetration:
  // the nearest face is not drawn first on hundreds of pixels.
  const Scene glass = loadScene("builtin:glass");
  const Camera camera = resolveCamera(*glass.camera, 160, 120, glass.bounds());
  const Frame reference = renderWith(glass, camera, "abuffer");
  for (const char* key : {"centroid", "max", "min", "mean-vertex"}) {
    RenderOptions byKey;
    byKey.algorithm = "reverse-painter";
    byKey.params = {{"order", key}};
    byKey.threads = 1;
    const Frame f = render(glass, camera, byKey);
    size_t wrongIds = 0;
    for (size_t i = 0; i < f.faceId.size(); ++i) wrongIds += f.faceId[i] != reference.faceId[i];
    EXPECT_GT(wrongIds, 100u) << key;
  }
}

// Many translucent layers: 300 random triangles at opacity 0.5, --verify's colour error (its
// ambiguous pixels left out) within one step for newell and bsp.
TEST(Transparency, NewellAndBspVerifyWithinOneStepOnTranslucentRandomTriangles) {
  Scene scene = loadScene("builtin:random?n=300&seed=5");
  for (Rgba8& c : scene.faceColors) c.a = 128;
  for (const conformance::Pose& pose : conformance::posesAround(scene, 3, 4)) {
    const Camera camera = resolveCamera(pose.spec, 160, 120, scene.bounds());
    for (const char* algorithm : {"newell", "bsp"}) {
      RenderOptions options;
      options.algorithm = algorithm;
      options.verify = true;
      const Frame f = render(scene, camera, options);
      EXPECT_EQ(f.stats.wrong_pixels.value_or(1), 0u) << algorithm;
      EXPECT_EQ(f.stats.detailCount("verify_color_beyond_step").value_or(1), 0u)
          << algorithm << "\n" << cameraSpecToJson(pose.spec);
      EXPECT_GT(f.stats.detailCount("verify_color_pixels").value_or(0), uint64_t(160 * 120) * 3 / 4) << algorithm;
    }
  }
}

// A known, explained mismatch: opaque first, then transparent faces sorted by one depth each,
// depth-tested without depth writes, blends the glass scene's cycle and interpenetration in the
// wrong order — while its ids (the nearest fragment) stay exact.
TEST(Transparency, ZbufferFamilysSortedPassIsWrongOnGlass) {
  const Scene scene = loadScene("builtin:glass");
  const Camera camera = resolveCamera(*scene.camera, 160, 120, scene.bounds());
  const Frame reference = renderWith(scene, camera, "abuffer");
  for (const char* algorithm : {"zbuffer", "sorted-zbuffer"}) {
    const Frame f = renderWith(scene, camera, algorithm);
    EXPECT_EQ(f.stats.detailText("write_rule"), "depth-test-blend");
    const algo::ColorError e = algo::colorError(f, reference);
    EXPECT_GT(e.beyondStep, 200u) << algorithm;
    EXPECT_GT(std::max({e.max[0], e.max[1], e.max[2]}), 20) << algorithm;
    RenderOptions options;
    options.algorithm = algorithm;
    options.verify = true;
    const Frame checked = render(scene, camera, options);
    EXPECT_EQ(checked.stats.wrong_pixels.value_or(1), 0u) << algorithm;
    // --verify leaves out the colour-ambiguous pixels (near an edge, coplanar fragments).
    const uint64_t verified = checked.stats.detailCount("verify_color_beyond_step").value_or(0);
    EXPECT_GT(verified, 200u) << algorithm;
    EXPECT_LE(verified, e.beyondStep) << algorithm;
    EXPECT_GT(checked.stats.detailCount("verify_color_near_edge").value_or(0), 0u) << algorithm;
  }
}

// No sort key of the z-buffer's transparent pass orders glass's cycle and interpenetration: each
// blends hundreds of pixels wrong, and each key gives its own order (not all the same image).
TEST(Transparency, NoSortKeyOfTheZbuffersPassIsRightOnGlass) {
  const Scene scene = loadScene("builtin:glass");
  const Camera camera = resolveCamera(*scene.camera, 160, 120, scene.bounds());
  const Frame reference = renderWith(scene, camera, "abuffer");
  std::vector<std::vector<Rgba8>> images;  // the distinct ones
  for (const char* key : {"centroid", "max", "min", "mean-vertex"}) {
    RenderOptions options;
    options.params = {{"sort-key", key}};
    options.threads = 1;
    const Frame f = render(scene, camera, options);
    EXPECT_GT(algo::colorError(f, reference).beyondStep, 200u) << key;
    std::vector<Rgba8> image(f.color.begin(), f.color.end());
    if (std::find(images.begin(), images.end(), image) == images.end()) images.push_back(std::move(image));
  }
  EXPECT_GT(images.size(), 1u);
}

TEST(Transparency, VerifyReportsColourErrorOnlyWithTransparency) {
  RenderOptions options;
  options.algorithm = "newell";
  options.verify = true;
  const Scene glass = loadScene("builtin:glass");
  const Frame g = render(glass, resolveCamera(*glass.camera, 64, 48, glass.bounds()), options);
  EXPECT_EQ(g.stats.detailCount("verify_color_beyond_step").value_or(99), 0u);
  EXPECT_EQ(g.stats.detailText("write_rule"), "blend");
  const Scene cubes = loadScene("builtin:cubes");
  const Frame c = render(cubes, resolveCamera(*cubes.camera, 64, 48, cubes.bounds()), options);
  EXPECT_FALSE(c.stats.detailCount("verify_color_beyond_step").has_value());
  EXPECT_EQ(c.stats.detailText("write_rule"), "overwrite");
}

TEST(Transparency, GlassHasTranslucentFacesOverAnOpaqueFloor) {
  const Scene scene = loadScene("builtin:glass");
  EXPECT_TRUE(algo::hasTransparency(scene));
  size_t opaque = 0;
  for (const Rgba8& c : scene.faceColors) opaque += c.a == 255;
  EXPECT_EQ(opaque, 1u);
  EXPECT_EQ(scene.faceCount(), 6u);
}

}  // namespace
}  // namespace hsr

// Clipping: triangles crossing the near plane (also with vertices behind the camera), wholly
// behind it, beyond the far plane, crossing it, and far past the guard band. Checked against an
// independent brute-force ray test per pixel centre, skipping only centres within 1/64 pixel of
// an edge or a clipping plane.
#include <gtest/gtest.h>

#include <cmath>

#include "test_scenes.hpp"

namespace hsr {
namespace {

constexpr int W = 80, H = 60;

Scene triangleScene(dvec3 a, dvec3 b, dvec3 c) {
  Scene s;
  s.source = "test:triangle";
  s.positions = {a, b, c};
  s.addFace({0, 1, 2}, {255, 255, 255, 255});
  s.finalize();
  return s;
}

// Camera at the origin looking down -z (OpenGL), near 1, far 10.
Camera originCamera() {
  CameraSpec spec = test::lookAt({0, 0, 0}, {0, 0, -1}, 60, 1, 10);
  return resolveCamera(spec, W, H, {});
}

// Eye depth at which the ray through pixel position (px, py) meets the triangle, or NaN.
double hitDepth(const Camera& cam, const Scene& s, double px, double py) {
  dvec3 o, d;
  cam.cameraRay(px, py, o, d);
  dvec3 a = cam.toCamera(s.positions[0]), b = cam.toCamera(s.positions[1]), c = cam.toCamera(s.positions[2]);
  // Moeller–Trumbore in double.
  dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  double det = glm::dot(e1, p);
  if (det == 0) return NAN;
  dvec3 tv = o - a;
  double u = glm::dot(tv, p) / det;
  dvec3 q = glm::cross(tv, e1);
  double v = glm::dot(d, q) / det;
  if (u < 0 || v < 0 || u + v > 1) return NAN;
  double t = glm::dot(e2, q) / det;
  double depth = o.z + t * d.z;
  return depth;
}

enum class Expect { In, Out, Unsure };
Expect expected(const Camera& cam, const Scene& s, int x, int y) {
  int inside = 0, outside = 0;
  const double e = 1.0 / 64;
  const double offsets[5][2] = {{0, 0}, {e, 0}, {-e, 0}, {0, e}, {0, -e}};
  for (auto& o : offsets) {
    double d = hitDepth(cam, s, x + 0.5 + o[0], y + 0.5 + o[1]);
    bool in = std::isfinite(d) && d >= cam.near && d <= cam.far;
    bool nearPlane = std::isfinite(d) && (std::abs(d - cam.near) < 1e-6 || std::abs(d - cam.far) < 1e-6);
    if (nearPlane) return Expect::Unsure;
    (in ? inside : outside)++;
  }
  if (inside == 5) return Expect::In;
  if (outside == 5) return Expect::Out;
  return Expect::Unsure;
}

struct Result {
  Frame frame;
  int in = 0, mismatches = 0;
};

Result check(const Scene& s) {
  Camera cam = originCamera();
  RenderOptions opt;
  opt.threads = 1;
  Result r{render(s, cam, opt)};
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      Expect e = expected(cam, s, x, y);
      bool drawn = r.frame.faceId[r.frame.index(x, y)] == 0;
      if (e == Expect::In) {
        ++r.in;
        r.mismatches += !drawn;
        if (drawn) {
          double d = hitDepth(cam, s, x + 0.5, y + 0.5);
          EXPECT_NEAR(r.frame.depth[r.frame.index(x, y)], d, 1e-5 * d);
        }
      }
      if (e == Expect::Out) r.mismatches += drawn;
    }
  return r;
}

TEST(Clip, CrossingTheNearPlane) {
  Result r = check(triangleScene({-1, -0.5, -0.5}, {1.5, -0.4, -0.6}, {0.2, 0.8, -6}));
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_GT(r.in, 200);
  EXPECT_EQ(r.frame.stats.triangles_clipped, 1u);
  for (float d : r.frame.depth)
    if (std::isfinite(d)) EXPECT_GE(d, 1.0f * (1 - 1e-6f));
}

TEST(Clip, VerticesBehindTheCamera) {
  // Two vertices behind the eye (w < 0): without clipping, the projection would wrap around.
  Result r = check(triangleScene({-2, -0.5, 3}, {2, -0.5, 3}, {0, 0.3, -5}));
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_GT(r.in, 100);
  EXPECT_EQ(r.frame.stats.triangles_clipped, 1u);
}

TEST(Clip, WhollyBehindTheCameraIsCulled) {
  Result r = check(triangleScene({-1, -1, 2}, {1, -1, 2}, {0, 1, 3}));
  EXPECT_EQ(r.frame.stats.covered_pixels, 0u);
  EXPECT_EQ(r.frame.stats.culled_frustum, 1u);
}

TEST(Clip, BeyondTheFarPlaneIsCulled) {
  Result r = check(triangleScene({-1, -1, -12}, {1, -1, -12}, {0, 1, -15}));
  EXPECT_EQ(r.frame.stats.covered_pixels, 0u);
  EXPECT_EQ(r.frame.stats.culled_frustum, 1u);
}

TEST(Clip, AMeshWhollyBehindTheCameraIsCulledWholeAndTheOtherDrawn) {
  // Mesh "behind" (two triangles) lies wholly behind the eye, mesh "front" (one) in view: only
  // the first is culled, by its box. Then a camera turned round sees both: nothing of the
  // previous frame's culling may stay (the tiled state is reused from frame to frame).
  Scene s;
  s.source = "test:two meshes";
  s.positions = {{1.5, -1, 3}, {3.5, -1, 3}, {2.5, 1, 4}, {1.5, 1, 3}, {-1, -0.5, -5}, {1, -0.5, -5}, {0, 0.8, -5}};
  s.beginMesh("behind");
  s.addFace({0, 1, 2}, {255, 0, 0, 255});
  s.addFace({0, 2, 3}, {255, 0, 0, 255});
  s.beginMesh("front");
  s.addFace({4, 5, 6}, {0, 255, 0, 255});
  s.finalize();
  ASSERT_EQ(s.meshes.size(), 2u);
  RenderOptions opt;
  opt.threads = 1;
  const Frame ahead = render(s, originCamera(), opt);
  EXPECT_EQ(ahead.stats.culled_frustum, 2u);
  uint64_t front = 0;
  for (int32_t id : ahead.faceId) {
    EXPECT_TRUE(id == -1 || id == 2) << id;
    front += id == 2;
  }
  EXPECT_GT(front, 100u);
  // From (0, 0, -10) looking down +z: both meshes in front of the eye, between near and far.
  const Camera back = resolveCamera(test::lookAt({0, 0, -10}, {0, 0, 1}, 60, 1, 20), W, H, {});
  const Frame both = render(s, back, opt);
  EXPECT_EQ(both.stats.culled_frustum, 0u);
  bool seen[3] = {};
  for (int32_t id : both.faceId)
    if (id >= 0 && id < 3) seen[id] = true;
  EXPECT_TRUE(seen[0] || seen[1]);
  EXPECT_TRUE(seen[2]);
}

TEST(Clip, CrossingTheFarPlane) {
  Result r = check(triangleScene({-3, -2, -4}, {3, -2, -4}, {0, 3, -20}));
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_GT(r.in, 300);
  EXPECT_EQ(r.frame.stats.triangles_clipped, 1u);
  for (float d : r.frame.depth)
    if (std::isfinite(d)) EXPECT_LE(d, 10.0f * (1 + 1e-6f));
}

TEST(Clip, HugeTriangleBeyondTheGuardBand) {
  // Reaches a million pixels past the image on every side: clipped to the guard band, and
  // still covers every pixel.
  Result r = check(triangleScene({-1e5, -1e5, -5}, {1e5, -1e5, -5}, {0, 1e5, -5}));
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_EQ(r.frame.stats.covered_pixels, uint64_t(W * H));
}

TEST(Clip, SidePlanesNeedNoClippingOnScreen) {
  // A triangle partly off screen but inside the guard band is not clipped, only bounded.
  Result r = check(triangleScene({-3, -0.5, -3}, {0.5, -0.5, -3}, {0, 0.5, -3}));
  EXPECT_EQ(r.mismatches, 0);
  EXPECT_EQ(r.frame.stats.triangles_clipped, 0u);
}

}  // namespace
}  // namespace hsr

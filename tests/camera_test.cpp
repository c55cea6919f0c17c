// Cameras: OpenGL conventions against glm's own lookAt/perspective, OpenCV cameras equivalent to
// OpenGL ones, projected points landing on the pixel the convention says, far-from-origin
// precision, and errors for degenerate cameras.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>

#include "test_scenes.hpp"

namespace hsr {
namespace {

TEST(Camera, OpenGLMatchesGlmLookAtPerspectiveAndViewport) {
  const int W = 320, H = 200;
  CameraSpec spec = test::lookAt({3, 2, 5}, {0.2, -0.1, 0}, 55, 0.5, 50);
  spec.up = {0.1, 1, 0};
  Camera cam = resolveCamera(spec, W, H, {});
  dmat4 view = glm::lookAt(spec.eye, spec.target, spec.up);
  dmat4 proj = glm::perspective(glm::radians(55.0), double(W) / H, 0.5, 50.0);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < 100; ++i) {
    dvec3 p{u(rng), u(rng), u(rng)};
    dvec4 clip = proj * view * dvec4(p, 1);
    dvec3 ndc = dvec3(clip) / clip.w;
    double wx = (ndc.x + 1) * 0.5 * W, wy = (1 - ndc.y) * 0.5 * H;  // row 0 at the top
    dvec4 h = cam.toPixelH(p);
    EXPECT_NEAR(h.x / h.w, wx, 1e-9);
    EXPECT_NEAR(h.y / h.w, wy, 1e-9);
    double eyeDepth = -(view * dvec4(p, 1)).z;
    EXPECT_NEAR(h.z, eyeDepth, 1e-12);
    // OpenGL window z is the "z" depth mapping.
    DepthFormat z = DepthFormat::parse("f32:z");
    EXPECT_NEAR(z.map(eyeDepth, 0.5, 50, false), std::clamp((ndc.z + 1) * 0.5, 0.0, 1.0), 1e-12);
  }
}

TEST(Camera, OrthographicMatchesGlmOrtho) {
  const int W = 160, H = 120;
  CameraSpec spec = test::lookAt({1, 1, 6}, {0, 0, 0}, 60, 1, 20);
  spec.orthoHeight = 4;
  Camera cam = resolveCamera(spec, W, H, {});
  EXPECT_TRUE(cam.orthographic);
  dmat4 view = glm::lookAt(spec.eye, spec.target, spec.up);
  double hw = 2.0 * W / H;
  dmat4 proj = glm::ortho(-hw, hw, -2.0, 2.0, 1.0, 20.0);
  for (dvec3 p : {dvec3(0.3, 0.2, 0.1), dvec3(-1, 0.5, 1), dvec3(1.5, -1.2, -0.4)}) {
    dvec4 clip = proj * view * dvec4(p, 1);
    dvec4 h = cam.toPixelH(p);
    EXPECT_NEAR(h.x / h.w, (clip.x + 1) * 0.5 * W, 1e-9);
    EXPECT_NEAR(h.y / h.w, (1 - clip.y) * 0.5 * H, 1e-9);
    EXPECT_NEAR(h.z, -(view * dvec4(p, 1)).z, 1e-12);
  }
}

// The OpenCV camera with K = (f, f, W/2 - 1/2, H/2 - 1/2) and pose = the OpenGL view with y
// and z flipped is the same camera: identical images, bit for bit.
TEST(Camera, OpenCVEqualsEquivalentOpenGL) {
  const int W = 96, H = 64;
  Scene scene = test::boxesScene();
  for (int k = 0; k < 5; ++k) {
    CameraSpec gl = test::lookAt({4.0 - k, 2.5, 6.0 + k * 0.3}, {0.1 * k, 0, -0.5}, 40 + 5 * k, 0.5, 30);
    Camera a = resolveCamera(gl, W, H, scene.bounds());
    CameraSpec cv;
    cv.kind = CameraSpec::Kind::OpenCV;
    double f = (H * 0.5) / std::tan(glm::radians(gl.fovyDeg) * 0.5);
    double K[3][3] = {{f, 0, W * 0.5 - 0.5}, {0, f, H * 0.5 - 0.5}, {0, 0, 1}};
    std::memcpy(cv.K, K, sizeof K);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) cv.worldToCamera[r][c] = a.cameraFromWorld[c][r];
    cv.near = gl.near;
    cv.far = gl.far;
    Camera b = resolveCamera(cv, W, H, scene.bounds());
    for (const char* algorithm : {"zbuffer", "raycast"}) {
      RenderOptions opt;
      opt.algorithm = algorithm;
      opt.threads = 1;
      Frame fa = render(scene, a, opt), fb = render(scene, b, opt);
      EXPECT_EQ(fa.faceId, fb.faceId) << algorithm;
      EXPECT_EQ(fa.depth, fb.depth) << algorithm;
      EXPECT_GT(fa.stats.covered_pixels, 100u);
    }
  }
}

// A point that K projects to (u, v) (OpenCV: pixel centres at integers) lands in pixel
// (floor(u + 0.5), floor(v + 0.5)). fx != fy, off-centre principal point, a rotated pose.
TEST(Camera, OpenCVProjectedPointLandsOnConventionPixel) {
  const int W = 200, H = 150;
  CameraSpec cv;
  cv.kind = CameraSpec::Kind::OpenCV;
  const double fx = 180, fy = 140, cx = 87.3, cy = 81.9;
  double K[3][3] = {{fx, 0, cx}, {0, fy, cy}, {0, 0, 1}};
  std::memcpy(cv.K, K, sizeof K);
  dmat3 R = dmat3(glm::rotate(dmat4(1), 0.3, glm::normalize(dvec3(0.2, 1, 0.1))));
  dvec3 t{0.3, -0.2, 2.0};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cv.worldToCamera[r][c] = R[c][r];
    cv.worldToCamera[r][3] = t[r];
  }
  cv.near = 0.1;
  cv.far = 100;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  int checked = 0;
  while (checked < 50) {
    dvec3 P{u(rng), u(rng), u(rng)};
    dvec3 pc = R * P + t;
    double pu = fx * pc.x / pc.z + cx, pv = fy * pc.y / pc.z + cy;
    double fu = pu + 0.5 - std::floor(pu + 0.5), fv = pv + 0.5 - std::floor(pv + 0.5);
    if (fu < 0.2 || fu > 0.8 || fv < 0.2 || fv > 0.8) continue;  // clear of pixel borders
    int px = int(std::floor(pu + 0.5)), py = int(std::floor(pv + 0.5));
    if (px < 0 || py < 0 || px >= W || py >= H) continue;
    // A square of +-0.45 pixel around P, parallel to the image plane: it contains the centre
    // of the pixel the convention names (at most 0.3 pixel away on each axis) and no other.
    Scene s;
    s.source = "test:dot";
    double a = 0.45 * pc.z / fx, b = 0.45 * pc.z / fy;
    dmat3 Rt = glm::transpose(R);
    s.positions = {P + Rt * dvec3(-a, -b, 0), P + Rt * dvec3(a, -b, 0), P + Rt * dvec3(a, b, 0), P + Rt * dvec3(-a, b, 0)};
    s.addFace({0, 1, 2, 3}, {255, 255, 255, 255});
    s.finalize();
    Camera cam = resolveCamera(cv, W, H, s.bounds());
    RenderOptions opt;
    opt.threads = 1;
    Frame f = render(s, cam, opt);
    ASSERT_EQ(f.stats.covered_pixels, 1u) << "u=" << pu << " v=" << pv;
    EXPECT_EQ(f.faceId[f.index(px, py)], 0) << "u=" << pu << " v=" << pv;
    ++checked;
  }
}

// Composing the transforms in double relative to the camera: a model a million units away from
// the origin, with its camera moved along, renders like the one at the origin.
TEST(Camera, MillionUnitsFromOriginRendersLikeAtOrigin) {
  const int W = 128, H = 96;
  const dvec3 offset{1e6, -2e6, 1.5e6};
  Scene near = test::boxesScene(), far = test::boxesScene(offset);
  CameraSpec a = test::lookAt({3.5, 2.5, 6}, {0, 0, -0.5}, 45, 0.5, 30);
  CameraSpec b = a;
  b.eye += offset;
  b.target += offset;
  RenderOptions opt;
  opt.threads = 1;
  Frame fa = render(near, resolveCamera(a, W, H, near.bounds()), opt);
  Frame fb = render(far, resolveCamera(b, W, H, far.bounds()), opt);
  EXPECT_EQ(fa.faceId, fb.faceId);
  for (size_t i = 0; i < fa.depth.size(); ++i)
    if (std::isfinite(fa.depth[i])) ASSERT_NEAR(fa.depth[i], fb.depth[i], 1e-5 * fa.depth[i]);
}

TEST(Camera, DegenerateCamerasAreInputErrors) {
  Bounds3 none;
  auto bad = [&](CameraSpec s) { EXPECT_THROW(resolveCamera(s, 64, 48, none, "cam.json"), InputError); };
  CameraSpec s = test::lookAt({0, 0, 5}, {0, 0, 5});
  bad(s);  // eye == target
  s = test::lookAt({0, 5, 0}, {0, 0, 0});
  bad(s);  // up parallel to the view direction
  s = test::lookAt({0, 0, 5}, {0, 0, 0}, 180);
  bad(s);
  s = test::lookAt({0, 0, 5}, {0, 0, 0}, 60, 0, 10);
  bad(s);  // near 0
  s = test::lookAt({0, 0, 5}, {0, 0, 0}, 60, 5, 1);
  bad(s);  // far < near
  s = test::lookAt({0, 0, NAN}, {0, 0, 0});
  bad(s);
  EXPECT_THROW(resolveCamera(test::lookAt({0, 0, 5}, {0, 0, 0}), 0, 48, none), InputError);
}

TEST(Camera, JsonParsingAndErrors) {
  CameraSpec s = parseCameraJson(R"({"eye":[1,2,3],"target":[0,0,0],"up":[0,0,1],"fovy_deg":30,"near":0.5,"far":9})", "c.json");
  EXPECT_EQ(s.kind, CameraSpec::Kind::OpenGL);
  EXPECT_EQ(s.eye, dvec3(1, 2, 3));
  EXPECT_EQ(s.up, dvec3(0, 0, 1));
  EXPECT_EQ(*s.near, 0.5);
  CameraSpec round = parseCameraJson(cameraSpecToJson(s), "again");
  EXPECT_EQ(round.eye, s.eye);
  EXPECT_EQ(round.fovyDeg, 30);
  CameraSpec cv = parseCameraJson(
      R"({"K":[[500,0,320],[0,480,240],[0,0,1]],"world_to_camera":[[1,0,0,0],[0,1,0,0],[0,0,1,3],[0,0,0,1]],"near":0.1,"far":50})",
      "cv.json");
  EXPECT_EQ(cv.kind, CameraSpec::Kind::OpenCV);
  EXPECT_EQ(cv.K[1][1], 480);
  EXPECT_EQ(cv.worldToCamera[2][3], 3);
  for (const char* text : {"{", "[]", R"({"eye":[1,2],"target":[0,0,0]})", R"({"eye":[1,2,3]})",
                           R"({"eye":[1,2,3],"target":[0,0,0],"fovy_deg":"wide"})", R"({"K":[[1,0,0],[0,1,0],[0,0,1]]})",
                           R"({"eye":[1,2,3],"target":[0,0,0],"colour":1})"}) {
    try {
      parseCameraJson(text, "cam.json");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cam.json", 0), 0u) << e.what();
    }
  }
  try {
    parseCameraJson("{\n\"eye\": [1,2,3],\n\"target\": [0,0,0\n}", "cam.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cam.json:4:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hsr

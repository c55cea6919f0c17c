// The pure parts of the llvmpipe peer benchmark (bench/peer), which run without Mesa: the GL
// projection lands hsr's pixels and depth order in GL window coordinates, and the face-id
// comparison tells edge disagreements from systematic ones (a flipped or shifted image).
#include <gtest/gtest.h>

#include "../bench/peer/gl_projection.hpp"
#include "../bench/peer/id_compare.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

// GL window coordinates (x, y up, depth) of a world point under clipFromCamera, viewport W x H.
dvec3 glWindow(const Camera& cam, const dvec3& world) {
  const dvec4 clip = peer::clipFromCamera(cam) * dvec4(cam.toCamera(world), 1.0);
  return {(clip.x / clip.w + 1) * 0.5 * cam.width, (clip.y / clip.w + 1) * 0.5 * cam.height, clip.z / clip.w};
}

void expectGlMatchesHsr(const Camera& cam, const dvec3& world) {
  const dvec4 h = cam.toPixelH(world);
  const dvec3 win = glWindow(cam, world);
  EXPECT_NEAR(win.x, h.x / h.w, 1e-9);
  EXPECT_NEAR(win.y, cam.height - h.y / h.w, 1e-9);  // upright in GL: row r from the bottom = hsr row H-1-r
  EXPECT_NEAR(peer::eyeDepthFromWindow(cam, win.z), h.z, 1e-9 * (cam.far - cam.near));
}

TEST(Peer, ProjectionMatchesHsrPixelsPerspective) {
  const Camera cam = resolveCamera(test::lookAt({3, 2, 5}, {0.2, -0.1, 0}, 55, 0.5, 50), 320, 200, {});
  for (const dvec3& p : {dvec3(0, 0, 0), dvec3(1, -0.5, 0.7), dvec3(-2, 1.5, -1)}) expectGlMatchesHsr(cam, p);
}

TEST(Peer, ProjectionMatchesHsrPixelsOpenCVWithSkew) {
  CameraSpec spec;
  spec.kind = CameraSpec::Kind::OpenCV;
  const double K[3][3] = {{400, 3, 150}, {0, 380, 95}, {0, 0, 1}};
  std::copy(&K[0][0], &K[0][0] + 9, &spec.K[0][0]);
  spec.worldToCamera[2][3] = 4;  // the camera 4 units in front of the origin, looking along +z
  spec.near = 1;
  spec.far = 9;
  const Camera cam = resolveCamera(spec, 300, 190, {});
  for (const dvec3& p : {dvec3(0, 0, 0), dvec3(0.4, -0.3, 1.2), dvec3(-1, 0.8, -2)}) expectGlMatchesHsr(cam, p);
}

TEST(Peer, ProjectionMatchesHsrPixelsOrthographic) {
  CameraSpec spec = test::lookAt({0, 0, 5}, {0, 0, 0}, 50, -2, 12);
  spec.orthoHeight = 3;
  const Camera cam = resolveCamera(spec, 160, 120, {});
  for (const dvec3& p : {dvec3(0, 0, 0), dvec3(1, -0.5, 6), dvec3(-1.2, 1, -6)}) expectGlMatchesHsr(cam, p);
}

TEST(Peer, DepthIsReversedAndClipsAtNearAndFar) {
  const Camera cam = resolveCamera(test::lookAt({0, 0, 10}, {0, 0, 0}, 50, 2, 30), 64, 64, {});
  // Points on the view axis at eye depth 2 (near), 10 and 30 (far).
  EXPECT_NEAR(glWindow(cam, {0, 0, 8}).z, 1.0, 1e-12);
  EXPECT_NEAR(glWindow(cam, {0, 0, -20}).z, 0.0, 1e-12);
  const double mid = glWindow(cam, {0, 0, 0}).z;
  EXPECT_GT(mid, 0.0);
  EXPECT_LT(mid, 1.0);
  EXPECT_GT(glWindow(cam, {0, 0, 0.1}).z, mid);  // nearer: greater (GL_GREATER wins)
  EXPECT_GT(glWindow(cam, {0, 0, 8.5}).z, 1.0);  // in front of near: clipped by GL (z > w)
  EXPECT_LT(glWindow(cam, {0, 0, -21}).z, 0.0);  // beyond far: clipped (z < 0)
}

// Two vertical faces split at column `split` (face 0 left, 1 right), background row at the top.
std::vector<int32_t> halves(int w, int h, int split) {
  std::vector<int32_t> ids(size_t(w) * size_t(h), -1);
  for (int y = 1; y < h; ++y)
    for (int x = 0; x < w; ++x) ids[size_t(y) * size_t(w) + size_t(x)] = x < split ? 0 : 1;
  return ids;
}

TEST(Peer, IdenticalImagesAgreeEverywhere) {
  const auto a = halves(8, 6, 3);
  const peer::IdAgreement r = peer::compareFaceIds(8, 6, a, a);
  EXPECT_EQ(r.covered, 8u * 5u);
  EXPECT_EQ(r.equal, r.covered);
  EXPECT_EQ(r.edgeMismatches + r.nonEdgeMismatches, 0u);
  EXPECT_DOUBLE_EQ(r.equalFraction(), 1.0);
}

TEST(Peer, BoundaryMovedByOnePixelIsEdgeOnly) {
  const peer::IdAgreement r = peer::compareFaceIds(8, 6, halves(8, 6, 3), halves(8, 6, 4));
  EXPECT_EQ(r.edgeMismatches, 5u);  // column 3 of the five covered rows
  EXPECT_EQ(r.nonEdgeMismatches, 0u);
  EXPECT_EQ(r.equal, r.covered - 5u);
}

TEST(Peer, WrongRegionCountsItsInterior) {
  const int w = 9, h = 9;
  std::vector<int32_t> a(size_t(w * h), 7), b = a;
  for (int y = 2; y < 7; ++y)
    for (int x = 2; x < 7; ++x) b[size_t(y * w + x)] = 8;  // a 5x5 block of another face
  const peer::IdAgreement r = peer::compareFaceIds(w, h, a, b);
  EXPECT_EQ(r.nonEdgeMismatches, 9u);  // its 3x3 interior
  EXPECT_EQ(r.edgeMismatches, 16u);    // its border ring
  ASSERT_FALSE(r.firstNonEdge.empty());
  EXPECT_EQ(r.firstNonEdge.front(), std::make_pair(3, 3));
}

TEST(Peer, FlippedImageIsASystematicMismatch) {
  // Face 0 on the top half, face 1 on the bottom; the other image upside down.
  const int w = 6, h = 8;
  std::vector<int32_t> a(size_t(w * h)), b(size_t(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      a[size_t(y * w + x)] = y < h / 2 ? 0 : 1;
      b[size_t(y * w + x)] = y < h / 2 ? 1 : 0;
    }
  const peer::IdAgreement r = peer::compareFaceIds(w, h, a, b);
  EXPECT_EQ(r.equal, 0u);
  EXPECT_EQ(r.edgeMismatches, 2u * w);  // the two rows at the boundary
  EXPECT_EQ(r.nonEdgeMismatches, uint64_t(w * h - 2 * w));
  EXPECT_EQ(r.firstNonEdge.size(), peer::IdAgreement::kMaxListed);
}

TEST(Peer, BackgroundAgainstFaceIsCoveredAndDiffers) {
  const std::vector<int32_t> a(9, -1);
  const std::vector<int32_t> b(9, 2);
  const peer::IdAgreement r = peer::compareFaceIds(3, 3, a, b);
  EXPECT_EQ(r.covered, 9u);
  EXPECT_EQ(r.equal, 0u);
  EXPECT_EQ(r.nonEdgeMismatches, 9u);  // uniform in both images: no edges at all
  EXPECT_EQ(peer::compareFaceIds(3, 3, a, a).covered, 0u);
  EXPECT_DOUBLE_EQ(peer::compareFaceIds(3, 3, a, a).equalFraction(), 1.0);
}

TEST(Peer, EdgePixelsAreThoseNextToAnotherIdInEitherImage) {
  const auto a = halves(8, 6, 3), b = halves(8, 6, 5);
  EXPECT_TRUE(peer::isEdgePixel(8, 6, a, a, 2, 3));   // left of a's boundary
  EXPECT_TRUE(peer::isEdgePixel(8, 6, a, a, 3, 3));   // right of it
  EXPECT_FALSE(peer::isEdgePixel(8, 6, a, a, 0, 5));  // image corner: only neighbours inside count
  EXPECT_FALSE(peer::isEdgePixel(8, 6, a, a, 4, 3));
  EXPECT_TRUE(peer::isEdgePixel(8, 6, a, b, 4, 3));  // next to b's boundary
  EXPECT_TRUE(peer::isEdgePixel(8, 6, a, a, 6, 1));  // below the background row
}

TEST(Peer, SizeMismatchThrows) {
  const std::vector<int32_t> a(6, 0), b(5, 0);
  EXPECT_THROW(peer::compareFaceIds(3, 2, a, b), std::invalid_argument);
  EXPECT_THROW(peer::compareFaceIds(2, 2, a, a), std::invalid_argument);
}

}  // namespace
}  // namespace hsr

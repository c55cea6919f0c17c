// Rasterizer conformance: fill rule and watertightness, coverage against a brute-force exact
// point-in-triangle test, and agreement of the half-space and scanline rasterizers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <hwy/targets.h>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "scene/shading.hpp"
#include "core/stream_fill.hpp"
#include "frontend/frontend.hpp"
#include "frontend/triangle_setup.hpp"
#include "frontend/vertices.hpp"
#include "raster/halfspace.hpp"
#include "raster/scanline.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr {
namespace {

constexpr int W = 64, H = 48;

Camera pixelCamera(int w = W, int h = H) {
  Camera cam;
  cam.width = w;
  cam.height = h;
  cam.near = 0.5;
  cam.far = 100;
  return cam;
}

// Sets up a screen-space triangle (pixel coordinates, eye depths) through the real front end.
bool setup(const dvec2 p[3], const double depth[3], SetupTriangle& t, FrontEndOutput& counters,
           int w = W, int h = H) {
  HVertex v[3];
  for (int i = 0; i < 3; ++i) v[i] = {p[i].x * depth[i], p[i].y * depth[i], depth[i], depth[i]};
  return setupTriangle(v, 0, 0, pixelCamera(w, h), Cull::None, counters, t);
}

// Random coordinate with a random number of sub-pixel bits, sometimes exactly on a pixel centre.
double randomCoord(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  double v = u(rng);
  switch (rng() % 4) {
    case 0: return std::floor(v) + 0.5;                 // exactly on a pixel centre
    case 1: return std::round(v * 2) / 2;               // on a pixel corner or centre
    default: return std::round(v * 256) / 256;          // any sub-pixel position
  }
}

// Independent reference: is pixel centre (x, y) inside the snapped triangle? Exact in double
// (coordinates are multiples of 1/256 below 2^15), with the top-left rule written from its
// geometric definition rather than from the edge-function bias.
bool insideReference(const SetupTriangle& t, int x, int y) {
  double px = x + 0.5, py = y + 0.5;
  double vx[3], vy[3];
  for (int i = 0; i < 3; ++i) {
    vx[i] = t.x[i] / 256.0;
    vy[i] = t.y[i] / 256.0;
  }
  for (int i = 0; i < 3; ++i) {
    int j = (i + 1) % 3, k = (i + 2) % 3;
    double side = (vx[j] - vx[i]) * (py - vy[i]) - (vy[j] - vy[i]) * (px - vx[i]);
    double third = (vx[j] - vx[i]) * (vy[k] - vy[i]) - (vy[j] - vy[i]) * (vx[k] - vx[i]);
    if (side * third < 0) return false;
    if (side == 0) {
      bool horizontal = vy[i] == vy[j];
      bool top = horizontal && vy[k] > vy[i];  // y down: the third vertex is below
      bool left = false;
      if (!horizontal) {  // interior to the right: third vertex right of the edge line at its y
        double xOnLine = vx[i] + (vx[j] - vx[i]) * (vy[k] - vy[i]) / (vy[j] - vy[i]);
        left = vx[k] > xOnLine;
      }
      if (!top && !left) return false;
    }
  }
  return true;
}

using Coverage = std::map<std::pair<int, int>, double>;

Coverage rasterize(const SetupTriangle& t, bool scanline) {
  Coverage c;
  auto visit = [&](int x, int y, double d) {
    bool fresh = c.emplace(std::make_pair(x, y), d).second;
    EXPECT_TRUE(fresh) << "pixel visited twice";
  };
  if (scanline) rasterizeScanline(t, visit);
  else rasterizeHalfSpace(t, visit);
  return c;
}

std::vector<std::array<dvec2, 3>> randomTriangles(int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::array<dvec2, 3>> out;
  while (int(out.size()) < count) {
    std::array<dvec2, 3> p;
    switch (rng() % 5) {
      case 0:  // sub-pixel
        p[0] = {randomCoord(rng, -1, W + 1), randomCoord(rng, -1, H + 1)};
        for (int i = 1; i < 3; ++i) p[i] = p[0] + dvec2(u(rng) - 0.5, u(rng) - 0.5) * 1.5;
        for (auto& q : p) q = glm::round(q * 256.0) / 256.0;
        break;
      case 1: {  // sliver: long and thin, sometimes nearly collinear
        p[0] = {randomCoord(rng, -4, W + 4), randomCoord(rng, -4, H + 4)};
        p[1] = {randomCoord(rng, -4, W + 4), randomCoord(rng, -4, H + 4)};
        dvec2 m = (p[0] + p[1]) * 0.5 + dvec2(u(rng) - 0.5, u(rng) - 0.5) * 0.3;
        p[2] = glm::round(m * 256.0) / 256.0;
        break;
      }
      case 2:  // huge: far beyond the image, inside the guard band
        for (auto& q : p) q = {randomCoord(rng, -4000, W + 4000), randomCoord(rng, -4000, H + 4000)};
        break;
      default:  // ordinary
        for (auto& q : p) q = {randomCoord(rng, -8, W + 8), randomCoord(rng, -8, H + 8)};
    }
    out.push_back(p);
  }
  return out;
}

TEST(Raster, CoverageMatchesBruteForceOn10000Triangles) {
  auto tris = randomTriangles(14000, 12345);
  const double depth[3] = {1, 2, 3};
  int drawn = 0, empty = 0, listed = 0;
  for (size_t n = 0; n < tris.size(); ++n) {
    SetupTriangle t;
    FrontEndOutput counters;
    if (!setup(tris[n].data(), depth, t, counters)) {
      // Dropped by the front end as covering no pixel centre of its (small) box: none indeed.
      if (counters.empty) {
        ++empty;
        for (int y = 0; y < H; ++y)
          for (int x = 0; x < W; ++x) ASSERT_FALSE(insideReference(t, x, y)) << "dropped triangle " << n;
      }
      continue;
    }
    ++drawn;
    // Set-up's list of covered centres (small boxes only): the reference's coverage of the box.
    const int boxW = t.maxX - t.minX + 1, boxH = t.maxY - t.minY + 1;
    ASSERT_EQ(t.coverage != 0, boxW <= kCoverageBox && boxH <= kCoverageBox) << "triangle " << n;
    if (t.coverage) {
      ++listed;
      for (int y = 0; y < kCoverageBox; ++y)
        for (int x = 0; x < kCoverageBox; ++x) {
          const bool in = x < boxW && y < boxH && insideReference(t, t.minX + x, t.minY + y);
          ASSERT_EQ(in, (t.coverage >> (y * kCoverageBox + x) & 1) != 0) << "triangle " << n << " " << x << "," << y;
        }
    }
    for (bool scan : {false, true}) {
      Coverage c = rasterize(t, scan);
      size_t expected = 0;
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          bool in = insideReference(t, x, y);
          expected += in;
          ASSERT_EQ(in, c.count({x, y}) == 1) << (scan ? "scanline" : "halfspace") << " triangle " << n << " pixel "
                                              << x << "," << y;
        }
      ASSERT_EQ(expected, c.size());
    }
  }
  EXPECT_GE(drawn, 10000);  // at least 10,000 triangles reached the rasterizers
  EXPECT_GE(empty, 100);     // and some were dropped for covering no pixel centre
  EXPECT_GE(listed, 100);    // and some came with their covered centres listed
}

TEST(Raster, ScanlineAndHalfSpaceAgreeOnDepth) {
  auto tris = randomTriangles(3000, 777);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(1, 50);
  for (auto& p : tris) {
    const double depth[3] = {u(rng), u(rng), u(rng)};
    SetupTriangle t;
    FrontEndOutput counters;
    if (!setup(p.data(), depth, t, counters)) continue;
    Coverage a = rasterize(t, false), b = rasterize(t, true);
    ASSERT_EQ(a.size(), b.size());
    for (auto& [px, d] : a) {
      ASSERT_TRUE(b.count(px));
      // Stepping accumulates rounding in double: agree to 1e-9 relative (documented tolerance).
      EXPECT_NEAR(d, b[px], 1e-9 * d);
    }
  }
}

// A mesh of triangles over a jittered grid: shared edges and vertices at random sub-pixel
// positions. Every pixel centre inside the outer rectangle is covered exactly once.
TEST(Raster, WatertightJitteredGrid) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> jitter(-0.25, 0.25);  // small enough that no cell folds
    const int N = 7;  // grid of N x N cells over [4, 60] x [4, 44]
    auto gx = [&](int i) { return 4.0 + i * (56.0 / N); };
    auto gy = [&](int j) { return 4.0 + j * (40.0 / N); };
    std::vector<dvec2> grid((N + 1) * (N + 1));
    for (int j = 0; j <= N; ++j)
      for (int i = 0; i <= N; ++i) {
        dvec2 p{gx(i), gy(j)};
        if (i > 0 && i < N) p.x += jitter(rng) * (56.0 / N);
        if (j > 0 && j < N) p.y += jitter(rng) * (40.0 / N);
        if (rng() % 3 == 0) p = glm::floor(p) + 0.5;  // some vertices exactly on pixel centres
        grid[j * (N + 1) + i] = glm::round(p * 256.0) / 256.0;
      }
    for (bool scan : {false, true}) {
      std::vector<int> count(W * H, 0);
      const double depth[3] = {1, 1, 1};
      for (int j = 0; j < N; ++j)
        for (int i = 0; i < N; ++i) {
          dvec2 a = grid[j * (N + 1) + i], b = grid[j * (N + 1) + i + 1];
          dvec2 c = grid[(j + 1) * (N + 1) + i], d = grid[(j + 1) * (N + 1) + i + 1];
          // Alternate the diagonal and the winding so both orientations are exercised.
          std::array<std::array<dvec2, 3>, 2> pair =
              (i + j) % 2 ? std::array<std::array<dvec2, 3>, 2>{{{a, b, d}, {a, d, c}}}
                          : std::array<std::array<dvec2, 3>, 2>{{{a, c, b}, {b, c, d}}};
          for (auto& tri : pair) {
            SetupTriangle t;
            FrontEndOutput counters;
            if (!setup(tri.data(), depth, t, counters)) continue;
            for (auto& [px, dd] : rasterize(t, scan)) ++count[px.second * W + px.first];
          }
        }
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          double cx = x + 0.5, cy = y + 0.5;
          bool strictlyInside = cx > 4 && cx < 60 && cy > 4 && cy < 44;
          bool outside = cx < 4 || cx > 60 || cy < 4 || cy > 44;
          if (strictlyInside) ASSERT_EQ(count[y * W + x], 1) << "seed " << seed << " pixel " << x << "," << y;
          if (outside) ASSERT_EQ(count[y * W + x], 0) << "seed " << seed << " pixel " << x << "," << y;
        }
    }
  }
}

// A fan of triangles around one vertex placed exactly on a pixel centre: the shared vertex's
// pixel is drawn exactly once, and so is every pixel of the union.
TEST(Raster, WatertightFanAroundPixelCentre) {
  const dvec2 c{32.5, 24.5};
  const int K = 13;
  for (bool scan : {false, true}) {
    std::vector<int> count(W * H, 0);
    for (int k = 0; k < K; ++k) {
      double a0 = 2 * M_PI * k / K, a1 = 2 * M_PI * (k + 1) / K;
      dvec2 p[3] = {c, glm::round((c + 20.0 * dvec2(std::cos(a0), std::sin(a0))) * 256.0) / 256.0,
                    glm::round((c + 20.0 * dvec2(std::cos(a1), std::sin(a1))) * 256.0) / 256.0};
      // Recompute the shared rim vertices identically for both neighbours.
      const double depth[3] = {1, 1, 1};
      SetupTriangle t;
      FrontEndOutput counters;
      ASSERT_TRUE(setup(p, depth, t, counters));
      for (auto& [px, dd] : rasterize(t, scan)) ++count[px.second * W + px.first];
    }
    EXPECT_EQ(count[24 * W + 32], 1);
    for (int v : count) EXPECT_LE(v, 1);
    // The inner disc (radius < 19 * cos(pi/K)) is fully covered.
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        if (glm::length(dvec2(x + 0.5, y + 0.5) - c) < 18) EXPECT_EQ(count[y * W + x], 1);
  }
}

TEST(Raster, DegenerateAfterSnappingIsCountedNotDrawn) {
  dvec2 p[3] = {{10, 10}, {20, 20}, {30, 30 + 1.0 / 1024}};  // collinear once snapped
  const double depth[3] = {1, 1, 1};
  SetupTriangle t;
  FrontEndOutput counters;
  EXPECT_FALSE(setup(p, depth, t, counters));
  EXPECT_EQ(counters.degenerate, 1u);
}

TEST(Raster, DepthIsPerspectiveCorrect) {
  // A triangle with depths 1 and 4: at the pixel halfway in screen space, 1/d interpolates
  // linearly, so d = 1 / ((1 + 1/4) / 2) = 1.6, not the screen-linear 2.5.
  dvec2 p[3] = {{0, 0}, {64, 0}, {0, 48}};
  const double depth[3] = {1, 4, 1};
  SetupTriangle t;
  FrontEndOutput counters;
  ASSERT_TRUE(setup(p, depth, t, counters));
  auto c = rasterize(t, false);
  ASSERT_TRUE(c.count({31, 0}));
  double x = 31.5, y = 0.5;
  double b1 = x / 64.0, b2 = y / 48.0, b0 = 1 - b1 - b2;
  double expected = 1.0 / (b0 / 1 + b1 / 4 + b2 / 1);
  EXPECT_NEAR(c[std::make_pair(31, 0)], expected, 1e-12);
}

}  // namespace

// The batched SIMD set-up gives bit for bit the scalar set-up's triangles and counts, on every
// instruction set: random triangles of every size, degenerate ones, slivers, off-screen ones,
// tiny ones covering no pixel centre, both cull modes.
// Random triangles for the set-up tests, projected: `count` of them over the image and a margin,
// each reshaped by shape(i, p), at random depths; triangle i has face 7 i.
struct ProjectedSoup {
  std::vector<ProjectedVertex> vertices;
  std::vector<uint32_t> index[3];
  std::vector<uint32_t> tri, face;
};

template <class Shape>
ProjectedSoup projectedSoup(uint64_t seed, int count, Shape&& shape) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> depthDist(0.6, 90);
  ProjectedSoup soup;
  for (int i = 0; i < count; ++i) {
    dvec2 p[3];
    for (int k = 0; k < 3; ++k) p[k] = {randomCoord(rng, -40, W + 40), randomCoord(rng, -40, H + 40)};
    shape(i, p);
    for (int k = 0; k < 3; ++k) {
      const double z = depthDist(rng);
      soup.index[k].push_back(uint32_t(soup.vertices.size()));
      soup.vertices.push_back(projectVertex({p[k].x * z, p[k].y * z, z, z}));
    }
    soup.tri.push_back(uint32_t(i));
    soup.face.push_back(uint32_t(7 * i));
  }
  return soup;
}

TEST(Raster, BatchedSetupEqualsScalarSetupOnEveryInstructionSet) {
  const ProjectedSoup soup = projectedSoup(77, 3000, [](int i, dvec2* p) {
    const int kind = i % 6;
    if (kind == 1) p[1] = p[0] + dvec2(0.3, 0.2), p[2] = p[0] + dvec2(-0.2, 0.4);  // tiny
    if (kind == 2) p[2] = p[1];                                                 // degenerate
    if (kind == 3) p[2] = p[0] + (p[1] - p[0]) * 0.5 + dvec2(0, 0.01);          // sliver
    if (kind == 4) {  // small: covered centres listed; every other one across the right or bottom edge
      if (i % 12 == 10) p[0] = i % 24 < 12 ? dvec2(100 - 0.2 * (i % 11), p[0].y) : dvec2(p[0].x, 80 - 0.2 * (i % 13));
      p[1] = p[0] + dvec2(2.7, 0.9), p[2] = p[0] + dvec2(0.8, 3.1);
    }
  });
  const auto& [vertices, index, tri, face] = soup;
  const Camera cam = pixelCamera(100, 80);  // (boxes of 64 x 64 pixels fit: counters.large)
  int targets = 0;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    ++targets;
    for (Cull cull : {Cull::None, Cull::Back, Cull::Front})
    for (bool cullFirst : {false, true}) {
      FrontEndCounters scalarCounts, batchCounts;
      size_t listed = 0;
      std::vector<SetupTriangle> scalar, batch(tri.size());
      for (size_t i = 0; i < tri.size(); ++i) {
        const ProjectedVertex v[3] = {vertices[index[0][i]], vertices[index[1][i]], vertices[index[2][i]]};
        SetupTriangle t;
        if (setupTriangle(v, tri[i], face[i], cam, cull, scalarCounts, t)) scalar.push_back(t);
      }
      const uint32_t* vertex[3] = {index[0].data(), index[1].data(), index[2].data()};
      batch.resize(setupBatch(vertices.data(), vertex, tri.data(), face.data(), tri.size(), cam, cull, batchCounts,
                              batch.data(), {.cullFirst = cullFirst}));
      const std::string what = std::string(hwy::TargetName(target)) + " cull " + std::to_string(int(cull)) +
                               (cullFirst ? " facing test first" : "");
      ASSERT_EQ(scalar.size(), batch.size()) << what;
      for (size_t i = 0; i < scalar.size(); ++i) {
        scalar[i].color = batch[i].color = Rgba8{};  // shaded by the caller
        ASSERT_EQ(std::memcmp(&scalar[i], &batch[i], offsetof(SetupTriangle, frontFacing)), 0) << what << " " << i;
        ASSERT_EQ(scalar[i].frontFacing, batch[i].frontFacing) << what << " " << i;
        ASSERT_EQ(scalar[i].coverage, batch[i].coverage) << what << " " << i;
        listed += scalar[i].coverage != 0;
      }
      EXPECT_EQ(scalarCounts.degenerate, batchCounts.degenerate) << what;
      EXPECT_EQ(scalarCounts.culledBackface, batchCounts.culledBackface) << what;
      EXPECT_EQ(scalarCounts.culledFrustum, batchCounts.culledFrustum) << what;
      EXPECT_EQ(scalarCounts.empty, batchCounts.empty) << what;
      EXPECT_EQ(scalarCounts.large, batchCounts.large) << what;
      if (cull == Cull::None) {
        EXPECT_GT(scalarCounts.degenerate, 100u);
        EXPECT_GT(scalarCounts.empty, 10u);
        EXPECT_GT(scalarCounts.large, 10u);
        EXPECT_GT(scalar.size(), 1000u);
        EXPECT_GT(listed, 200u);
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GE(targets, 2);
}

// Lambert shading is per face, from the view ray to the face's centroid: for a face of many
// vertices that centroid is summed once per frame, not once per triangle (which made a face of
// 100 000 vertices take seconds). Every triangle of such a face, and of faces just below and
// above the size where the per-frame sums start, gets 0.25 + 0.75 |cos| of its normal and the
// ray from the eye to its face's centroid.
TEST(Raster, LambertShadingOfLargeFacesUsesTheirCentroid) {
  Scene scene;
  const dvec3 centre{0.5, -0.25, 1}, axisU = glm::normalize(dvec3(1, 0.2, 0.3)),
              axisV = glm::normalize(glm::cross(dvec3(0.1, 0.3, 1), axisU));
  const int sizes[] = {15, 16, 17, 100000};
  for (int n : sizes) {
    std::vector<uint32_t> face;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n, r = 1 + 0.5 * (n - 15);  // (faces apart)
      face.push_back(uint32_t(scene.positions.size()));
      scene.positions.push_back(centre * double(n) + r * (std::cos(a) * axisU + 0.5 * std::sin(a) * axisV));
    }
    scene.addFace(face, {200, 100, 50, 255});
  }
  scene.finalize();
  CameraSpec spec;
  spec.eye = {3, -40, 90000};
  spec.target = {0, 0, 0};
  const Camera cam = resolveCamera(spec, 64, 48, scene.bounds());
  const TriangleShader shade(scene, cam, Shading::Lambert);
  std::vector<dvec3> view;  // per face: from the eye to its centroid
  for (size_t f = 0; f < scene.faceCount(); ++f) {
    dvec3 centroid{0.0};
    for (uint32_t v : scene.face(f)) centroid += scene.positions[v];
    view.push_back(glm::normalize(centroid / double(scene.face(f).size()) - spec.eye));
  }
  for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
    const Triangle& tri = scene.triangles[t];
    const dvec3 &a = scene.positions[tri.v[0]], &b = scene.positions[tri.v[1]], &c = scene.positions[tri.v[2]];
    const dvec3 normal = glm::normalize(glm::cross(b - a, c - a));  // the triangle's own, as shaded
    ASSERT_NEAR(shade.lambertFactor(t), 0.25 + 0.75 * std::abs(glm::dot(normal, view[tri.face])), 1e-12)
        << "triangle " << t;
  }
  size_t triangles = 0;
  for (int n : sizes) triangles += size_t(n - 2);
  EXPECT_EQ(scene.triangles.size(), triangles);
}

// The batched Lambert shading (TriangleShader::lambertFactors and shadeMany, SIMD) gives bit for
// bit the scalar factor and colour of every triangle, on every instruction set, perspective and
// orthographic, any count: triangles that are their own face (the SIMD path), quads' triangles
// (one by one), slivers; a scene with quads, and one of triangles only (every triangle its own
// face: a shortcut).
TEST(Raster, BatchedShadingEqualsScalarOnEveryInstructionSet) {
  for (bool quads : {true, false}) {
    std::mt19937_64 rng(83);
    std::uniform_real_distribution<double> u(-5, 5);
    std::uniform_int_distribution<int> c(0, 255);
    Scene scene;
    for (int i = 0; i < 300; ++i) {
      const uint32_t first = uint32_t(scene.positions.size());
      const dvec3 a{u(rng), u(rng), u(rng)};
      const int kind = i % (quads ? 5 : 4);
      scene.positions.push_back(a);
      scene.positions.push_back(a + dvec3(u(rng), u(rng), u(rng)));
      scene.positions.push_back(kind == 3 ? a + (scene.positions.back() - a) * 0.5 + dvec3(0, 1e-7, 0)  // sliver
                                          : a + dvec3(u(rng), u(rng), u(rng)));
      const Rgba8 color{uint8_t(c(rng)), uint8_t(c(rng)), uint8_t(c(rng)), uint8_t(c(rng))};
      if (kind == 4) {  // a planar quad: two triangles of a four-vertex face
        scene.positions.push_back(scene.positions[first + 2] + (scene.positions[first] - scene.positions[first + 1]));
        scene.addFace({first, first + 1, first + 2, first + 3}, color);
      } else {
        scene.addFace({first, first + 1, first + 2}, color);
      }
    }
    scene.finalize();
    ASSERT_EQ(scene.triangles.size(), quads ? 360u : 300u);
    std::vector<uint32_t> all(scene.triangles.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = uint32_t(all.size() - 1 - i);  // (any order)
    CameraSpec perspective;
    perspective.eye = {3, 4, 20};
    CameraSpec orthographic = perspective;
    orthographic.orthoHeight = 12;
    int targets = 0;
    for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
      hwy::SetSupportedTargetsForTest(target);
      ++targets;
      for (const CameraSpec& spec : {perspective, orthographic}) {
        const Camera cam = resolveCamera(spec, 64, 48, scene.bounds());
        const TriangleShader shade(scene, cam, Shading::Lambert);
        for (size_t count : {size_t(0), size_t(1), size_t(9), all.size()}) {
          std::vector<double> factors(count);
          std::vector<Rgba8> colors(count);
          shade.lambertFactors(all.data(), count, factors.data());
          shade.shadeMany(all.data(), count, colors.data());
          for (size_t i = 0; i < count; ++i) {
            const std::string what = std::string(hwy::TargetName(target)) +
                                     (cam.orthographic ? " orthographic" : " perspective") + " triangle " +
                                     std::to_string(all[i]);
            const double factor = shade.lambertFactor(all[i]);
            ASSERT_EQ(std::memcmp(&factor, &factors[i], sizeof factor), 0) << what;
            const Rgba8 color = shade(all[i]);
            ASSERT_EQ(std::memcmp(&color, &colors[i], sizeof color), 0) << what;
          }
        }
      }
    }
    hwy::SetSupportedTargetsForTest(0);
    EXPECT_GE(targets, 2);
  }
}

// A 640x480 perspective camera looking at the origin from (3, 4, 40), near 5 and far 60.
Camera viewOfTheOrigin() {
  CameraSpec spec;
  spec.eye = {3, 4, 40};
  spec.target = {0, 0, 0};
  spec.near = 5;
  spec.far = 60;
  return resolveCamera(spec, 640, 480, Bounds3{});
}

// The SIMD vertex pass gives bit for bit transformVertex, clipOutcode and projectVertex, on
// every instruction set: points in front of, behind and beside the camera, any count.
TEST(Raster, VertexPassEqualsScalarOnEveryInstructionSet) {
  std::mt19937_64 rng(79);
  std::uniform_real_distribution<double> u(-30, 30);
  std::vector<dvec3> points(1003);
  for (dvec3& p : points) p = {u(rng), u(rng), u(rng)};
  const Camera cam = viewOfTheOrigin();
  const dmat4 M = cam.pixelFromCamera * cam.cameraFromWorld;
  int inside = 0;
  const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  for (int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (size_t count : {size_t(1), size_t(7), size_t(8), points.size()}) {
      std::vector<uint8_t> codes(count);
      std::vector<ProjectedVertex> projected(count);
      transformVertices(points.data(), count, M, cam, codes.data(), projected.data());
      const std::string what = std::string(hwy::TargetName(target)) + " count " + std::to_string(count);
      for (size_t i = 0; i < count; ++i) {
        const HVertex h = transformVertex(points[i], M);
        ASSERT_EQ(uint32_t(codes[i]), clipOutcode(h, cam)) << what << " " << i;
        if (codes[i]) continue;
        const ProjectedVertex p = projectVertex(h);
        ASSERT_EQ(std::memcmp(&p, &projected[i], sizeof p), 0) << what << " " << i;
        inside += count == points.size() && target == targets.front();
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(inside, 200);  // some of each kind
  EXPECT_LT(inside, 1003);
}

// boxCornersInView (SIMD) decides and measures a box's eight corners as transformVertex and the
// clipping planes do, one corner at a time: inside every plane by more than the margin, and then
// bit for bit the extremes of w -+ room and of hx (1 / w), hy (1 / w) — on every instruction set,
// for boxes wholly in view, crossing a plane, behind the camera, flat and a point.
TEST(Raster, BoxCornersInViewEqualsScalarOnEveryInstructionSet) {
  std::mt19937_64 rng(80);
  std::uniform_real_distribution<double> centre(-12, 12), half(0, 6);
  const Camera cam = viewOfTheOrigin();
  const dmat4 M = cam.pixelFromCamera * cam.cameraFromWorld;
  std::vector<Bounds3> boxes(600);
  for (size_t i = 0; i < boxes.size(); ++i) {
    dvec3 c{centre(rng), centre(rng), 3 * centre(rng)}, r{half(rng), half(rng), half(rng)};
    if (i % 5 == 1) r.z = 0;                  // flat
    if (i % 7 == 2) r = dvec3(0.0);           // a point
    if (i % 11 == 3) c.z = 38;                // at the near plane, or behind the eye
    boxes[i] = {c - r, c + r};
  }
  const double margin = 1e-3, room = 1e-9;
  int inView = 0;
  const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  for (int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (size_t i = 0; i < boxes.size(); ++i) {
      const Bounds3& b = boxes[i];
      bool inside = true;
      const double inf = std::numeric_limits<double>::infinity();
      double want[6] = {inf, -inf, inf, inf, -inf, -inf};
      for (int c = 0; c < 8; ++c) {
        const HVertex h = transformVertex({c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z}, M);
        const double g = kGuardBandPixels;
        inside &= h.d - cam.near > margin && cam.far - h.d > margin && h.hx - -g * h.w > margin &&
                  (cam.width + g) * h.w - h.hx > margin && h.hy - -g * h.w > margin &&
                  (cam.height + g) * h.w - h.hy > margin;
        const double inverse = 1 / h.w;
        want[0] = std::min(want[0], h.w - room), want[1] = std::max(want[1], h.w + room);
        want[2] = std::min(want[2], h.hx * inverse), want[3] = std::min(want[3], h.hy * inverse);
        want[4] = std::max(want[4], h.hx * inverse), want[5] = std::max(want[5], h.hy * inverse);
      }
      double got[6];
      const std::string what = std::string(hwy::TargetName(target)) + " box " + std::to_string(i);
      ASSERT_EQ(boxCornersInView(b, M, cam, margin, room, got), inside) << what;
      if (!inside) continue;
      inView += target == targets.front();
      for (int k = 0; k < 6; ++k) EXPECT_EQ(got[k], want[k]) << what << " extent " << k;
    }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(inView, 100);  // some of each kind
  EXPECT_LT(inView, 550);
}

// The nearest bounds the batched set-up computes are bit for bit nearestStored() of the scalar
// path (raster/fragment_depth.hpp), for every depth format, perspective and orthographic, on
// every instruction set — and they are bounds: no covered pixel centre stores a nearer value.
TEST(Raster, BatchedNearestBoundsEqualScalarOnEveryInstructionSet) {
  const ProjectedSoup soup = projectedSoup(78, 900, [](int i, dvec2* p) {
    if (i % 3 == 1) p[1] = p[0] + dvec2(2.3, 0.2), p[2] = p[0] + dvec2(-0.2, 3.4);  // small
  });
  const auto& [vertices, index, tri, face] = soup;
  const Camera cam = pixelCamera();
  const uint32_t* vertex[3] = {index[0].data(), index[1].data(), index[2].data()};
  size_t checkedFragments = 0;
  const std::vector<int64_t> targets = hwy::SupportedAndGeneratedTargets();
  for (int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (const char* name : {"u16:z", "u16:reversed", "u16:inv", "u16:linear", "u24:z", "u24:reversed", "u24:inv",
                             "u24:linear", "u32:z", "u32:reversed", "u32:inv", "u32:linear", "f32:z", "f32:reversed",
                             "f32:inv", "f32:linear"})
      for (bool ortho : {false, true}) {
        const DepthSetup depth{DepthFormat::parse(name), 0.5, 100.0, ortho};
        FrontEndCounters counts;
        std::vector<SetupTriangle> batch(tri.size());
        std::vector<double> nearest(tri.size());
        batch.resize(setupBatch(vertices.data(), vertex, tri.data(), face.data(), tri.size(), cam, Cull::None, counts,
                                batch.data(), {.depth = &depth, .nearest = nearest.data()}));
        ASSERT_GT(batch.size(), 500u);
        const std::string what = std::string(hwy::TargetName(target)) + " " + name + (ortho ? " ortho" : "");
        for (size_t i = 0; i < batch.size(); ++i) {
          const double scalar = nearestStored(batch[i], depth);
          ASSERT_EQ(std::memcmp(&scalar, &nearest[i], sizeof scalar), 0) << what << " " << i;
        }
        if (target != targets.front() || ortho) continue;
        // A bound: every covered centre of the first triangles stores nothing nearer.
        visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
          for (size_t i = 0; i < std::min<size_t>(batch.size(), 60); ++i) {
            const SetupTriangle& t = batch[i];
            const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, false);
            for (const auto& [pixel, eye] : rasterize(t, false)) {
              const double Y = pixel.second + 0.5;
              const double z = fragmentStored<S>(m, pixel.first + 0.5, m.p.b * Y, m.q.b * Y);
              ASSERT_FALSE(storedNearer<M>(z, nearest[i])) << what << " " << i;
              ++checkedFragments;
            }
          }
        });
      }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GT(checkedFragments, 1000u);
}

// storedRangeOverRect (the kernel's block bounds) bounds every pixel centre of its rectangle, on
// each triangle's plane extended past its edges: random rectangles of a 160 x 120 image, the
// planes' errors taken over the whole image, every format, perspective and orthographic.
TEST(Raster, RectangleBoundsHoldEveryPixelCentre) {
  const ProjectedSoup soup = projectedSoup(91, 300, [](int, dvec2*) {});
  const auto& [vertices, index, tri, face] = soup;
  const Camera cam = pixelCamera();
  const uint32_t* vertex[3] = {index[0].data(), index[1].data(), index[2].data()};
  FrontEndCounters counts;
  std::vector<SetupTriangle> batch(tri.size());
  batch.resize(setupBatch(vertices.data(), vertex, tri.data(), face.data(), tri.size(), cam, Cull::None, counts,
                          batch.data()));
  ASSERT_GT(batch.size(), 100u);
  std::mt19937 rng(7);
  size_t bounded = 0, checked = 0;
  for (const char* name : {"u16:z", "u24:reversed", "u32:inv", "u32:linear", "f32:z", "f32:reversed", "f32:inv"})
    for (bool ortho : {false, true}) {
      const DepthSetup depth{DepthFormat::parse(name), 0.5, 100.0, ortho};
      visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
        for (const SetupTriangle& t : batch) {
          const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, ortho);
          const double pErr = planeError(m.p, cam.width, cam.height), qErr = planeError(m.q, cam.width, cam.height);
          for (int k = 0; k < 4; ++k) {
            const int x0 = int(rng() % uint32_t(cam.width)), y0 = int(rng() % uint32_t(cam.height));
            const int x1 = std::min(cam.width - 1, x0 + int(rng() % 12)), y1 = std::min(cam.height - 1, y0 + int(rng() % 12));
            const StoredRange r = storedRangeOverRect<S, M>(m, pErr, qErr, x0 + 0.5, x1 + 0.5, y0 + 0.5, y1 + 0.5);
            if (!std::isfinite(r.nearest) || !std::isfinite(r.farthest)) continue;  // "none": q not > 0 there
            ++bounded;
            for (int y = y0; y <= y1; ++y)
              for (int x = x0; x <= x1; ++x) {
                const double Y = y + 0.5;
                const double z = fragmentStored<S>(m, x + 0.5, m.p.b * Y, m.q.b * Y);
                ASSERT_FALSE(storedNearer<M>(z, r.nearest)) << name << " " << x << "," << y;
                ASSERT_FALSE(storedNearer<M>(r.farthest, z)) << name << " " << x << "," << y;
                ++checked;
              }
          }
        }
      });
    }
  EXPECT_GT(bounded, 5000u);
  EXPECT_GT(checked, 100000u);
}

// The frame's buffers start on a cache line, so that rows of a width divisible by 16 do too and
// the resolve can stream whole lines (core/stream-inl.h); std::allocator gives 16 bytes here.
TEST(Stream, FrameBuffersAreCacheLineAligned) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{333, 97}, std::pair{1920, 1080}}) {
    Frame frame;
    frame.allocate(w, h);
    for (const void* p : {static_cast<const void*>(frame.faceId.data()), static_cast<const void*>(frame.triangleId.data()),
                          static_cast<const void*>(frame.depth.data()), static_cast<const void*>(frame.color.data())})
      EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % 64, 0u) << w << "x" << h;
  }
}

// Buffers of at least 2 MiB (a 1920x1080 frame's) start on a 2 MiB page, and where Linux offers
// transparent huge pages for advised memory, their mapping is eligible for them (the kernel's
// THPeligible in /proc/self/smaps): the resolve's streaming stores then miss the TLB ~500 times
// less often.
TEST(Stream, LargeFrameBuffersAskForHugePages) {
  Frame frame;
  frame.allocate(1920, 1080);
  const void* buffers[] = {frame.faceId.data(), frame.triangleId.data(), frame.depth.data(), frame.color.data()};
  for (const void* p : buffers) EXPECT_EQ(reinterpret_cast<uintptr_t>(p) % detail::kHugePageBytes, 0u);
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(mode, modes);
  if (modes.find("[never]") != std::string::npos || modes.empty()) return;  // (not offered: nothing to check)
  {
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool reported = false;  // (kernels before 5.0 do not report THPeligible: nothing to check)
    while (!reported && std::getline(smaps, line)) reported = line.rfind("THPeligible:", 0) == 0;
    if (!reported) return;
  }
  for (const void* p : buffers) {
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool inside = false, found = false;
    while (std::getline(smaps, line)) {
      uintptr_t begin = 0, end = 0;
      char dash = 0;
      std::istringstream range(line);
      if (line.find(':') > line.find(' ') && (range >> std::hex >> begin >> dash >> end) && dash == '-') {
        inside = reinterpret_cast<uintptr_t>(p) >= begin && reinterpret_cast<uintptr_t>(p) < end;
        continue;
      }
      if (inside && line.rfind("THPeligible:", 0) == 0) {
        EXPECT_NE(line.find('1'), std::string::npos) << line;
        found = true;
      }
    }
    EXPECT_TRUE(found) << "no THPeligible line for the buffer's mapping";
  }
}

// streamFill writes its range and nothing else, from every offset into a cache line, for lengths
// shorter than a line, across one, and many lines, on every instruction set (streams for whole
// lines, ordinary stores for the rest).
TEST(Stream, FillWritesExactlyItsRangeOnEveryInstructionSet) {
  constexpr uint32_t kGuard = 0xAAAAAAAAu;
  FrameBuffer<uint32_t> buffer(400);
  int targets = 0;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    ++targets;
    for (size_t offset = 0; offset < 34; ++offset)
      for (size_t n : {0, 1, 3, 13, 15, 16, 17, 31, 32, 33, 48, 63, 64, 65, 100, 129, 300}) {
        std::fill(buffer.begin(), buffer.end(), kGuard);
        const uint32_t value = 0x12345600u + uint32_t(n);
        streamFill(buffer.data() + offset, value, n);
        for (size_t i = 0; i < buffer.size(); ++i)
          ASSERT_EQ(buffer[i], i >= offset && i < offset + n ? value : kGuard)
              << hwy::TargetName(target) << " offset " << offset << " n " << n << " at " << i;
      }
  }
  hwy::SetSupportedTargetsForTest(0);
  EXPECT_GE(targets, 2);
}

}  // namespace hsr

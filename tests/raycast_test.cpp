// The exact reference: ray casting against analytic results and brute force, watertightness on
// closed meshes (with rays deliberately through shared edges and vertices), tie-breaking,
// clipping, culling, thread determinism, and the --verify classification.
#include <gtest/gtest.h>

#include <hsr/render.hpp>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <tuple>

#include "algorithms/algorithms.hpp"
#include "algorithms/bvh.hpp"
#include "scene/shading.hpp"

namespace hsr {
namespace {

using Faces = std::vector<std::vector<uint32_t>>;

Scene makeScene(const std::vector<dvec3>& positions, const Faces& faces) {
  Scene s;
  s.source = "test";
  s.positions = positions;
  for (size_t f = 0; f < faces.size(); ++f)
    s.addFace(std::span<const uint32_t>(faces[f]), Rgba8{uint8_t(40 + 13 * f), 200, 90, 255});
  s.finalize();
  return s;
}

// A camera looking from `eye` at `target` (y up); orthographic when orthoHeight > 0.
Camera lookAt(dvec3 eye, dvec3 target, int w, int h, double near, double far, double orthoHeight = 0,
              double fovy = 60) {
  CameraSpec spec;
  spec.eye = eye;
  spec.target = target;
  spec.fovyDeg = fovy;
  if (orthoHeight > 0) spec.orthoHeight = orthoHeight;
  spec.near = near;
  spec.far = far;
  return resolveCamera(spec, w, h, Bounds3{});
}

RenderOptions rayOptions(Cull cull = Cull::None, int threads = 1) {
  RenderOptions o;
  o.algorithm = "raycast";
  o.cull = cull;
  o.threads = threads;
  return o;
}

// A closed cube [-1, 1]^3, each side an n x n grid of quads with shared vertices, wound
// counter-clockwise seen from outside.
Scene gridCube(int n) {
  std::vector<dvec3> pos;
  std::map<std::tuple<int, int, int>, uint32_t> index;
  auto vertex = [&](int i, int j, int k) {  // grid coordinates in 0..n
    auto [it, fresh] = index.emplace(std::make_tuple(i, j, k), uint32_t(pos.size()));
    if (fresh) pos.push_back(dvec3(i, j, k) * (2.0 / n) - 1.0);
    return it->second;
  };
  Faces faces;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          // Corner (a + da, b + db) of the quad on plane `axis` = side * n, in (u, v) axes such
          // that u x v points along +axis.
          auto corner = [&](int da, int db) {
            int c[3];
            c[axis] = side * n;
            c[(axis + 1) % 3] = a + da;
            c[(axis + 2) % 3] = b + db;
            return vertex(c[0], c[1], c[2]);
          };
          std::vector<uint32_t> q = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
          if (side == 0) std::swap(q[1], q[3]);  // the -axis side faces the other way
          faces.push_back(q);
        }
  return makeScene(pos, faces);
}

// Icosphere of radius 1 (subdivided icosahedron, shared vertices, outward winding).
Scene icosphere(int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<dvec3> pos = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                            {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (dvec3& p : pos) p = glm::normalize(p);
  Faces tris = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto [it, fresh] = mid.emplace(std::minmax(a, b), uint32_t(pos.size()));
      if (fresh) pos.push_back(glm::normalize(pos[a] + pos[b]));
      return it->second;
    };
    Faces next;
    for (auto& f : tris) {
      uint32_t ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.insert(next.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    tris = std::move(next);
  }
  return makeScene(pos, tris);
}

// Independent ray-triangle test (Moller-Trumbore): t and the smallest barycentric coordinate.
bool mollerTrumbore(const dvec3& o, const dvec3& d, const dvec3& a, const dvec3& b, const dvec3& c, double& t,
                    double& minBary) {
  dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  double det = glm::dot(e1, p);
  if (det == 0) return false;
  dvec3 s = o - a;
  double u = glm::dot(s, p) / det;
  dvec3 q = glm::cross(s, e1);
  double v = glm::dot(d, q) / det;
  t = glm::dot(e2, q) / det;
  minBary = std::min({u, v, 1 - u - v});
  return minBary >= 0;
}

// Brute-force nearest hit over all triangles with the same rules as the BVH.
algo::RayHit bruteForce(const std::vector<dvec3>& v, const std::vector<Triangle>& tris,
                        const algo::WatertightRay& ray, double tMin, double tMax, Cull cull) {
  algo::RayHit best;
  for (uint32_t i = 0; i < tris.size(); ++i) {
    double t = ray.intersect(v[tris[i].v[0]], v[tris[i].v[1]], v[tris[i].v[2]], cull);
    if (t >= tMin && t <= tMax && t < best.t) best = {t, int32_t(i)};  // strict: lowest index on ties
  }
  return best;
}

Scene randomSoup(int count, uint64_t seed, double size = 0.6) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> centre(-1, 1), offset(-size, size);
  std::vector<dvec3> pos;
  Faces faces;
  for (int i = 0; i < count; ++i) {
    dvec3 c(centre(rng), centre(rng), centre(rng));
    for (int k = 0; k < 3; ++k) pos.push_back(c + dvec3(offset(rng), offset(rng), offset(rng)));
    faces.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return makeScene(pos, faces);
}

// --- Coverage and depth ----------------------------------------------------------------------

TEST(Raycast, SingleTriangleMatchesAnalyticCoverageAndDepth) {
  const int W = 64, H = 48;
  Scene scene = makeScene({{-1.3, -0.9, 0.2}, {1.1, -0.7, -0.4}, {0.1, 1.2, 0.3}}, {{0, 1, 2}});
  Camera cam = lookAt({0, 0, 5}, {0, 0, 0}, W, H, 0.1, 100);
  RenderOptions opt = rayOptions();
  Frame frame = render(scene, cam, opt);

  const double fy = (H / 2.0) / std::tan(glm::radians(30.0));
  const Rgba8 shade = shadeTriangle(scene, cam, opt, 0);
  uint64_t expectedCovered = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      // World ray from the eye: camera x = world x, camera y = -world y, forward = -world z, so
      // the parameter along this direction is the eye depth.
      dvec3 dir((x + 0.5 - W / 2.0) / fy, -(y + 0.5 - H / 2.0) / fy, -1);
      double t, minBary;
      const dvec3* p = scene.positions.data();
      bool inside = mollerTrumbore({0, 0, 5}, dir, p[0], p[1], p[2], t, minBary);
      ASSERT_GT(std::abs(minBary), 1e-9) << "pixel centre on an edge: pick other vertices";
      const size_t i = frame.index(x, y);
      if (inside) {
        ++expectedCovered;
        EXPECT_EQ(frame.faceId[i], 0) << x << "," << y;
        EXPECT_EQ(frame.triangleId[i], 0);
        EXPECT_NEAR(frame.depth[i], t, 1e-6 * t);
        EXPECT_EQ(frame.color[i], shade);
      } else {
        EXPECT_EQ(frame.faceId[i], -1) << x << "," << y;
        EXPECT_EQ(frame.triangleId[i], -1);
        EXPECT_TRUE(std::isinf(frame.depth[i]));
        EXPECT_EQ(frame.color[i], opt.background);
      }
    }
  EXPECT_GT(expectedCovered, 100u);
  EXPECT_EQ(frame.stats.algorithm, "raycast");
  EXPECT_EQ(frame.stats.covered_pixels, expectedCovered);
  EXPECT_EQ(frame.stats.color_writes, expectedCovered);
  EXPECT_GE(frame.stats.depth_tests, expectedCovered);  // rays outside its box are not tested
  EXPECT_LT(frame.stats.depth_tests, uint64_t(W * H));
  EXPECT_EQ(frame.stats.depth_writes, expectedCovered);
  EXPECT_EQ(frame.stats.faces, 1u);
  EXPECT_EQ(frame.stats.triangles, 1u);
  EXPECT_GT(frame.stats.memory_bytes, uint64_t(W * H * 16));
}

TEST(Raycast, DegenerateTrianglesAreNeverHit) {
  // A zero-area triangle (collinear) and a repeated-vertex one, in front of a visible triangle.
  Scene scene = makeScene({{-2, -2, 0}, {2, -2, 0}, {0, 2, 0}, {-2, -2, 1}, {0, 0, 1}, {2, 2, 1}},
                          {{0, 1, 2}});
  scene.triangles.push_back({{3, 4, 5}, 0});
  scene.triangles.push_back({{3, 3, 4}, 0});
  Camera cam = lookAt({0, 0, 5}, {0, 0, 0}, 32, 32, 0.1, 100);
  Frame frame = render(scene, cam, rayOptions());
  EXPECT_EQ(frame.stats.triangles_degenerate, 2u);
  for (size_t i = 0; i < frame.triangleId.size(); ++i) EXPECT_LT(frame.triangleId[i], 1);
  EXPECT_EQ(frame.triangleId[frame.index(16, 16)], 0);
}

// --- Watertightness --------------------------------------------------------------------------

TEST(Raycast, WatertightWithPixelCentresOnSharedEdgesAndVertices) {
  // Orthographic, 1/16 world unit per pixel, shifted half a pixel so that pixel centres land
  // exactly on the grid lines, vertices and diagonals of the cube's 8 x 8 quads (all values
  // are exact in binary).
  Scene cube = gridCube(8);
  const int N = 64;
  for (Cull cull : {Cull::None, Cull::Back, Cull::Front}) {
    Camera cam = lookAt({-0.5 / 16, 0.5 / 16, 5}, {-0.5 / 16, 0.5 / 16, 0}, N, N, 1, 10, 4.0);
    Frame frame = render(cube, cam, rayOptions(cull));
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) {
        const double wx = (x - 32) / 16.0, wy = (32 - y) / 16.0;  // pixel centre in world units
        const bool inside = std::abs(wx) <= 1 && std::abs(wy) <= 1;
        const size_t i = frame.index(x, y);
        ASSERT_EQ(frame.faceId[i] >= 0, inside) << "cull " << int(cull) << " pixel " << x << "," << y;
        if (inside) {
          EXPECT_FLOAT_EQ(frame.depth[i], cull == Cull::Front ? 6.0f : 4.0f);
        }
      }
  }
}

TEST(Raycast, WatertightSphereFromRandomDirections) {
  Scene sphere = icosphere(3);
  // Inscribed radius: the nearest face plane. Rays closer than it to the centre must hit.
  double inscribed = 1;
  for (const Triangle& t : sphere.triangles) {
    const dvec3 &a = sphere.positions[t.v[0]], &b = sphere.positions[t.v[1]], &c = sphere.positions[t.v[2]];
    inscribed = std::min(inscribed, std::abs(glm::dot(glm::normalize(glm::cross(b - a, c - a)), a)));
  }
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  const int N = 48;
  for (int view = 0; view < 24; ++view) {
    dvec3 eye = glm::normalize(dvec3(g(rng), g(rng), 0.3 + g(rng))) * 3.5;  // never along 'up'
    if (std::abs(eye.y) > 3.4) continue;
    Camera cam = lookAt(eye, {0, 0, 0}, N, N, 0.5, 10, 0, 40);
    for (Cull cull : {Cull::None, Cull::Back}) {
      Frame frame = render(sphere, cam, rayOptions(cull));
      uint64_t interior = 0;
      for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x) {
          dvec3 o, d;
          cam.cameraRay(x + 0.5, y + 0.5, o, d);
          // Distance from the sphere centre (camera space) to the ray.
          const dvec3 c = cam.toCamera({0, 0, 0});
          const double dist = glm::length(glm::cross(c - o, glm::normalize(d)));
          const bool hit = frame.faceId[frame.index(x, y)] >= 0;
          if (dist < inscribed) {
            ++interior;
            ASSERT_TRUE(hit) << "view " << view << " pixel " << x << "," << y;
          }
          if (dist > 1) {
            ASSERT_FALSE(hit);
          }
        }
      EXPECT_GT(interior, 500u);
    }
  }
}

TEST(Raycast, RaysThroughEveryVertexAndEdgeHitAClosedMesh) {
  // Rays aimed exactly at mesh vertices and edge points from outside, roughly along the surface
  // normal there, must hit the mesh at that point. (From a point where the target lies on the
  // silhouette, a ray may graze the mesh and legitimately miss it.)
  Scene sphere = icosphere(2);
  Camera identity;  // camera space = world space
  algo::CameraSpaceBvh bvh(sphere, identity);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  algo::TraceCounters counters;
  auto check = [&](const dvec3& target) {
    for (int k = 0; k < 4; ++k) {
      const dvec3 origin = target * 3.0 + dvec3(g(rng), g(rng), g(rng)) * 0.3;
      algo::RayHit hit =
          bvh.closestHit(algo::WatertightRay(origin, target - origin), 0, 1e30, Cull::Back, counters);
      ASSERT_TRUE(hit.found()) << "target " << target.x << "," << target.y << "," << target.z;
      EXPECT_NEAR(hit.t, 1.0, 1e-9);  // the target is at t = 1
    }
  };
  for (const dvec3& p : sphere.positions) check(p);
  for (const Triangle& t : sphere.triangles)
    for (int e = 0; e < 3; ++e) {
      const dvec3 &a = sphere.positions[t.v[e]], &b = sphere.positions[t.v[(e + 1) % 3]];
      check(a + (b - a) * 0.5);
      check(a + (b - a) * 0.25);
    }
}

// --- Nearest hit -----------------------------------------------------------------------------

TEST(Raycast, NearestHitMatchesBruteForceOnRandomSoups) {
  Camera identity;
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  for (int soup = 0; soup < 3; ++soup) {
    Scene scene = randomSoup(500, 100 + soup);
    algo::CameraSpaceBvh bvh(scene, identity);
    uint64_t hits = 0;
    for (int r = 0; r < 1500; ++r) {
      const dvec3 origin = glm::normalize(dvec3(g(rng), g(rng), g(rng))) * 3.0;
      const dvec3 dir = dvec3(u(rng), u(rng), u(rng)) * 0.7 - origin;
      const double tMin = r % 3 == 0 ? 0.6 : 0.0, tMax = r % 5 == 0 ? 0.9 : 1e30;
      const Cull cull = Cull(r % 3);
      algo::WatertightRay ray(origin, dir);
      algo::TraceCounters counters;
      algo::RayHit got = bvh.closestHit(ray, tMin, tMax, cull, counters);
      algo::RayHit want = bruteForce(scene.positions, scene.triangles, ray, tMin, tMax, cull);
      ASSERT_EQ(got.triangle, want.triangle) << "soup " << soup << " ray " << r;
      if (!got.found()) continue;
      ++hits;
      EXPECT_EQ(got.t, want.t);
      EXPECT_LT(counters.tests, 500u);  // the hierarchy prunes
      // Independent check of the distance with Moller-Trumbore.
      const Triangle& t = scene.triangles[size_t(got.triangle)];
      double tm, bary;
      mollerTrumbore(origin, dir, scene.positions[t.v[0]], scene.positions[t.v[1]], scene.positions[t.v[2]], tm, bary);
      EXPECT_NEAR(got.t, tm, 1e-9 * std::abs(tm));
      EXPECT_GT(bary, -1e-9);
    }
    EXPECT_GT(hits, 300u);
  }
}

TEST(Raycast, FrameMatchesBruteForcePerPixel) {
  Scene scene = randomSoup(300, 77);
  Camera cam = lookAt({0.4, 0.7, 3.2}, {0, 0, 0}, 40, 30, 1.5, 4.5);  // near/far cut the soup
  Frame frame = render(scene, cam, rayOptions());
  std::vector<dvec3> v;
  for (const dvec3& p : scene.positions) v.push_back(cam.toCamera(p));
  uint64_t covered = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      dvec3 o, d;
      cam.cameraRay(x + 0.5, y + 0.5, o, d);
      algo::RayHit want = bruteForce(v, scene.triangles, algo::WatertightRay(o, d), cam.near, cam.far, Cull::None);
      const size_t i = frame.index(x, y);
      ASSERT_EQ(frame.triangleId[i], want.triangle) << x << "," << y;
      if (want.found()) {
        ++covered;
        EXPECT_EQ(frame.depth[i], float(want.t));
        EXPECT_GE(want.t, cam.near);
        EXPECT_LE(want.t, cam.far);
      }
    }
  EXPECT_EQ(frame.stats.covered_pixels, covered);
  EXPECT_GT(covered, 300u);
}

TEST(Raycast, CoplanarDuplicatesGoToTheLowerTriangleIndex) {
  // Faces 0..2: the same triangle three times (shared vertices, copied vertices), and a
  // fourth copy behind them. Every covered pixel must show face 0.
  std::vector<dvec3> pos = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
  pos.insert(pos.end(), pos.begin(), pos.end());
  pos.push_back({-1, -1, -0.5});
  pos.push_back({1, -1, -0.5});
  pos.push_back({0, 1, -0.5});
  Scene scene = makeScene(pos, {{0, 1, 2}, {0, 1, 2}, {3, 4, 5}, {6, 7, 8}});
  // Straight on, orthographic, binary-exact pixel positions: every copy's depth is exactly 4,
  // whatever the order in which the triangulation lists its vertices.
  Camera cam = lookAt({0, 0, 4}, {0, 0, 0}, 32, 32, 0.1, 100, 4.0);
  Frame frame = render(scene, cam, rayOptions());
  uint64_t covered = 0;
  for (int32_t f : frame.faceId) {
    if (f < 0) continue;
    ++covered;
    EXPECT_EQ(f, 0);
  }
  EXPECT_GT(covered, 50u);

  // With the copies listed first, the first listed (now index 0) still wins.
  Scene reversed = makeScene(pos, {{3, 4, 5}, {0, 1, 2}, {6, 7, 8}});
  Frame second = render(reversed, cam, rayOptions());
  for (int32_t f : second.faceId)
    if (f >= 0) {
      EXPECT_EQ(f, 0);
    }
}

// --- Clipping and culling ---------------------------------------------------------------------

TEST(Raycast, HitsOutsideNearFarAreIgnoredAndTheRayContinues) {
  // Two big quads at eye depths 2 and 4 (camera at z = 5 looking down -z).
  Scene scene = makeScene({{-9, -9, 3}, {9, -9, 3}, {9, 9, 3}, {-9, 9, 3}, {-9, -9, 1}, {9, -9, 1}, {9, 9, 1}, {-9, 9, 1}},
                          {{0, 1, 2, 3}, {4, 5, 6, 7}});
  auto centre = [&](double near, double far) {
    // 17 x 17: the centre pixel's ray is the view axis, so the depths are exact.
    Frame f = render(scene, lookAt({0, 0, 5}, {0, 0, 0}, 17, 17, near, far), rayOptions());
    return std::make_pair(f.faceId[f.index(8, 8)], f.depth[f.index(8, 8)]);
  };
  EXPECT_EQ(centre(1, 10), std::make_pair(0, 2.0f));
  EXPECT_EQ(centre(2, 10), std::make_pair(0, 2.0f));  // exactly at near: kept
  EXPECT_EQ(centre(2.5, 10), std::make_pair(1, 4.0f));
  EXPECT_EQ(centre(2.5, 4), std::make_pair(1, 4.0f));  // exactly at far: kept
  EXPECT_EQ(centre(1, 1.9).first, -1);
  EXPECT_EQ(centre(2.5, 3.9).first, -1);

  // A plane tilted through the near plane: visible exactly where its depth is >= near.
  Scene tilted = makeScene({{-4, -4, 2}, {4, -4, 2}, {4, 4, -2}, {-4, 4, -2}}, {{0, 1, 2, 3}});
  Camera cam = lookAt({0, 0, 5}, {0, 0, 0}, 32, 32, 5, 100);
  Frame frame = render(tilted, cam, rayOptions());
  int shown = 0, clipped = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      dvec3 o, d;
      cam.cameraRay(x + 0.5, y + 0.5, o, d);
      // Camera (cx, cy, z) -> world (cx, -cy, 5 - z); plane: world z = -world y / 2.
      const double depth = 5 / (1 + d.y / 2);  // solve 5 - z = z * d.y / 2
      const bool visible = frame.faceId[frame.index(x, y)] == 0;
      if (std::abs(depth - 5) < 1e-9) continue;
      EXPECT_EQ(visible, depth >= 5) << x << "," << y;
      (visible ? shown : clipped)++;
    }
  EXPECT_GT(shown, 100);
  EXPECT_GT(clipped, 100);
}

TEST(Raycast, CullingFollowsWindingAsSeen) {
  // Counter-clockwise as seen from +z (the camera): a front face.
  Scene ccw = makeScene({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}}, {{0, 1, 2}});
  Scene cw = makeScene({{-1, -1, 0}, {0, 1, 0}, {1, -1, 0}}, {{0, 1, 2}});
  Camera cam = lookAt({0, 0, 5}, {0, 0, 0}, 16, 16, 0.1, 100);
  auto shows = [&](const Scene& s, Cull c) { return render(s, cam, rayOptions(c)).faceId[8 * 16 + 8] == 0; };
  EXPECT_TRUE(shows(ccw, Cull::None));
  EXPECT_TRUE(shows(ccw, Cull::Back));
  EXPECT_FALSE(shows(ccw, Cull::Front));
  EXPECT_TRUE(shows(cw, Cull::None));
  EXPECT_FALSE(shows(cw, Cull::Back));
  EXPECT_TRUE(shows(cw, Cull::Front));

  // A closed cube: culling back faces shows the near side, culling front faces the far side,
  // from any direction (the facing does not depend on which axis the ray is sheared along).
  // The view axis points 50 degrees away from the cube and the field of view is wide, so the
  // cube is seen by rays whose largest component is x or y: the shear runs along those axes.
  Scene cube = gridCube(2);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  const int N = 48;
  uint64_t offAxis = 0;
  for (int view = 0; view < 10; ++view) {
    const dvec3 eye = glm::normalize(dvec3(g(rng), 0.5 * g(rng), g(rng))) * 4.0;
    const dvec3 toCube = -glm::normalize(eye);
    const dvec3 side = glm::normalize(glm::cross(toCube, dvec3(g(rng), g(rng), g(rng))));
    const dvec3 forward = std::cos(glm::radians(50.0)) * toCube + std::sin(glm::radians(50.0)) * side;
    Camera c = lookAt(eye, eye + forward, N, N, 0.5, 20, 0, 120);
    Frame none = render(cube, c, rayOptions(Cull::None));
    Frame back = render(cube, c, rayOptions(Cull::Back));
    Frame front = render(cube, c, rayOptions(Cull::Front));
    for (int y = 0; y < N; ++y)
      for (int x = 0; x < N; ++x) {
        const size_t i = none.index(x, y);
        EXPECT_EQ(none.depth[i], back.depth[i]);
        EXPECT_EQ(none.faceId[i] >= 0, front.faceId[i] >= 0);
        if (front.faceId[i] < 0) continue;
        EXPECT_GT(front.depth[i], back.depth[i]);
        dvec3 o, d;
        c.cameraRay(x + 0.5, y + 0.5, o, d);
        if (std::max(std::abs(d.x), std::abs(d.y)) > 1) ++offAxis;
      }
  }
  EXPECT_GT(offAxis, 200u);
}

// --- Determinism -------------------------------------------------------------------------------

TEST(Raycast, IdenticalBitsForAnyThreadCount) {
  Scene scene = randomSoup(2000, 9, 0.3);
  Camera cam = lookAt({0.5, 1, 3.5}, {0, 0, 0}, 96, 64, 0.5, 10);
  Frame one = render(scene, cam, rayOptions(Cull::None, 1));
  for (int threads : {2, 3}) {
    Frame many = render(scene, cam, rayOptions(Cull::None, threads));
    EXPECT_EQ(one.faceId, many.faceId);
    EXPECT_EQ(one.triangleId, many.triangleId);
    EXPECT_EQ(0, std::memcmp(one.depth.data(), many.depth.data(), one.depth.size() * sizeof(float)));
    EXPECT_EQ(one.color, many.color);
    EXPECT_EQ(one.stats.depth_tests, many.stats.depth_tests);
    EXPECT_EQ(one.stats.depth_writes, many.stats.depth_writes);
    EXPECT_EQ(one.stats.covered_pixels, many.stats.covered_pixels);
  }
}

// --- Verify classification ---------------------------------------------------------------------

// A front square [-1, 1]^2 at world z = 0.5 (face 0) over a back square [-3, 3]^2 at z = -1
// (face 1), seen orthographically at 1/16 world unit per pixel, shifted half a pixel so that
// the front square's edges pass exactly through pixel centres (columns 16 and 48, rows 16, 48).
struct VerifyFixture {
  Scene scene = makeScene({{-1, -1, 0.5}, {1, -1, 0.5}, {1, 1, 0.5}, {-1, 1, 0.5},
                           {-3, -3, -1}, {3, -3, -1}, {3, 3, -1}, {-3, 3, -1}},
                          {{0, 1, 2, 3}, {4, 5, 6, 7}});
  Camera cam = lookAt({-0.5 / 16, 0.5 / 16, 5}, {-0.5 / 16, 0.5 / 16, 0}, 64, 64, 1, 10, 4.0);
  RenderOptions opt = rayOptions();
  Frame reference = render(scene, cam, opt);

  // Shows face `face` (through its first triangle) at pixel (x, y) of `frame`.
  void show(Frame& frame, int x, int y, int32_t face) const {
    const size_t i = frame.index(x, y);
    frame.faceId[i] = face;
    frame.triangleId[i] = -1;
    for (size_t t = 0; t < scene.triangles.size(); ++t)
      if (int32_t(scene.triangles[t].face) == face) {
        frame.triangleId[i] = int32_t(t);
        break;
      }
  }
};

TEST(Verify, IdenticalFramesHaveNothingWrongOrAmbiguous) {
  VerifyFixture f;
  VerifyResult r = verifyAgainstReference(f.scene, f.cam, f.opt, f.reference, f.reference);
  EXPECT_EQ(r.wrong_pixels, 0u);
  EXPECT_EQ(r.ambiguous_pixels, 0u);
  EXPECT_TRUE(r.first_wrong.empty());
}

TEST(Verify, SwappedFaceDeepInsideIsWrongAndEdgePixelsAreAmbiguous) {
  VerifyFixture f;
  ASSERT_EQ(f.reference.faceId[f.reference.index(16, 30)], 0);  // centre exactly on the left edge
  ASSERT_EQ(f.reference.faceId[f.reference.index(15, 30)], 1);
  Frame frame = f.reference;
  f.show(frame, 30, 30, 1);  // deep inside the front square: the back square is 1.5 behind
  f.show(frame, 16, 30, 1);  // on the front square's edge: snapping may move it either way
  f.show(frame, 15, 31, 0);  // a whole pixel outside the edge: wrong
  VerifyResult r = verifyAgainstReference(f.scene, f.cam, f.opt, frame, f.reference);
  EXPECT_EQ(r.wrong_pixels, 2u);
  EXPECT_EQ(r.ambiguous_pixels, 1u);
  ASSERT_EQ(r.first_wrong.size(), 2u);
  EXPECT_EQ(r.first_wrong[0], std::make_pair(30, 30));
  EXPECT_EQ(r.first_wrong[1], std::make_pair(15, 31));

  // Background instead of a surface in the middle of the front square: wrong.
  Frame empty = f.reference;
  empty.faceId[empty.index(20, 40)] = -1;
  empty.triangleId[empty.index(20, 40)] = -1;
  EXPECT_EQ(verifyAgainstReference(f.scene, f.cam, f.opt, empty, f.reference).wrong_pixels, 1u);
}

TEST(Verify, EdgeAmbiguityReachesAbout1Over128Pixel) {
  // The front square's left edge `inside` pixels to the left of pixel column 16's centres: the
  // centres see the front square, a frame showing the back square there is ambiguous only when
  // the edge is within reach of snapping.
  for (double inside : {1.0 / 300, 1.0 / 50}) {
    const double x0 = -1 - inside / 16;
    VerifyFixture f;
    f.scene = makeScene({{x0, -1, 0.5}, {1, -1, 0.5}, {1, 1, 0.5}, {x0, 1, 0.5},
                         {-3, -3, -1}, {3, -3, -1}, {3, 3, -1}, {-3, 3, -1}},
                        {{0, 1, 2, 3}, {4, 5, 6, 7}});
    f.reference = render(f.scene, f.cam, f.opt);
    ASSERT_EQ(f.reference.faceId[f.reference.index(16, 30)], 0);
    Frame frame = f.reference;
    f.show(frame, 16, 30, 1);
    VerifyResult r = verifyAgainstReference(f.scene, f.cam, f.opt, frame, f.reference);
    EXPECT_EQ(r.ambiguous_pixels, inside < 1.0 / 128 ? 1u : 0u) << inside;
    EXPECT_EQ(r.wrong_pixels, inside < 1.0 / 128 ? 0u : 1u) << inside;
  }
}

TEST(Verify, SurfacesCloserThanTheDepthFormatResolvesAreAmbiguous) {
  // Two overlapping squares 1e-7 apart in depth: 16-bit depth cannot order them.
  auto scene = [](double gap) {
    return makeScene({{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0},
                      {-1, -1, -gap}, {1, -1, -gap}, {1, 1, -gap}, {-1, 1, -gap}},
                     {{0, 1, 2, 3}, {4, 5, 6, 7}});
  };
  Camera cam = lookAt({0.1, 0.2, 5}, {0, 0, 0}, 32, 32, 1, 10, 0, 45);
  RenderOptions opt = rayOptions();
  opt.depthFormat = DepthFormat::parse("u16:z");
  for (double gap : {1e-7, 0.3}) {
    Scene s = scene(gap);
    Frame reference = render(s, cam, opt);
    Frame frame = reference;
    const size_t i = frame.index(16, 16);
    ASSERT_EQ(reference.faceId[i], 0);
    frame.faceId[i] = 1;
    frame.triangleId[i] = reference.triangleId[i] + 2;  // face 1's triangles follow face 0's two
    ASSERT_EQ(s.triangles[size_t(frame.triangleId[i])].face, 1u);
    VerifyResult r = verifyAgainstReference(s, cam, opt, frame, reference);
    EXPECT_EQ(r.ambiguous_pixels, gap < 1e-3 ? 1u : 0u) << gap;
    EXPECT_EQ(r.wrong_pixels, gap < 1e-3 ? 0u : 1u) << gap;
  }
}

TEST(Verify, SurfaceAtAClipPlaneOrTheClearValueMayBeMissing) {
  // A square at world height z, seen from z = 5 (near 1, far 5: eye depth 5 - z), missing from
  // the frame. Exactly at a clipping plane (the reference keeps it: both are inclusive) or
  // within two 16-bit steps of the clear value, a z-buffer may drop it: ambiguous. Otherwise:
  // wrong. With "inv" the far plane maps to n/f = 0.2, far from the clear value 0.
  struct Case {
    double z;
    const char* format;
    bool ambiguous;
  };
  for (Case c : {Case{0, "u16:z", true}, Case{1e-4, "u16:z", true}, Case{0.1, "u16:z", false},
                 Case{0, "u16:inv", true}, Case{4, "u16:z", true}, Case{3.9, "u16:z", false}}) {
    Scene scene = makeScene({{-1, -1, c.z}, {1, -1, c.z}, {1, 1, c.z}, {-1, 1, c.z}}, {{0, 1, 2, 3}});
    Camera cam = lookAt({0, 0, 5}, {0, 0, 0}, 16, 16, 1, 5, 4.0);
    RenderOptions opt = rayOptions();
    opt.depthFormat = DepthFormat::parse(c.format);
    Frame reference = render(scene, cam, opt);
    ASSERT_EQ(reference.faceId[reference.index(8, 8)], 0);
    Frame frame = reference;
    for (size_t i = 0; i < frame.faceId.size(); ++i) frame.faceId[i] = frame.triangleId[i] = -1;
    VerifyResult r = verifyAgainstReference(scene, cam, opt, frame, reference);
    EXPECT_EQ(r.wrong_pixels, c.ambiguous ? 0u : reference.stats.covered_pixels) << c.z << " " << c.format;
    EXPECT_EQ(r.ambiguous_pixels, c.ambiguous ? reference.stats.covered_pixels : 0u) << c.z << " " << c.format;
  }
}

TEST(Verify, ZbufferAgreesWithTheReference) {
  // The whole pipeline: render() with verify on closed and interpenetrating geometry.
  for (const char* format : {"f32:reversed", "u24:z", "u16:inv"}) {
    RenderOptions opt;
    opt.algorithm = "zbuffer";
    opt.verify = true;
    opt.threads = 1;
    opt.depthFormat = DepthFormat::parse(format);
    for (int s = 0; s < 2; ++s) {
      Scene scene = s == 0 ? icosphere(2) : randomSoup(400, 21, 0.4);
      Camera cam = lookAt({1.3, 0.9, 3.1}, {0, 0, 0}, 80, 60, 1, 8);
      Frame frame = render(scene, cam, opt);
      ASSERT_TRUE(frame.stats.wrong_pixels.has_value());
      EXPECT_EQ(*frame.stats.wrong_pixels, 0u) << format << " scene " << s;
    }
  }
}

}  // namespace
}  // namespace hsr

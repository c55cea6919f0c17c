// Tests of the scene model: Scene::finalize() validation, triangulation (fans, ear clipping of
// concave and self-intersecting polygons, degenerate and non-planar faces), mesh ranges, bounds.
#include <gtest/gtest.h>
#include <hsr/scene.hpp>

#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

namespace hsr {
namespace {

double cross2(dvec2 a, dvec2 b) { return a.x * b.y - a.y * b.x; }

/// Twice the signed area of a 2D polygon (shoelace).
double signedArea2(const std::vector<dvec2>& poly) {
  double s = 0;
  for (size_t i = 0; i < poly.size(); ++i) s += cross2(poly[i], poly[(i + 1) % poly.size()]);
  return s;
}

/// Even-odd point-in-polygon test.
bool inside(const std::vector<dvec2>& poly, dvec2 p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const dvec2 &a = poly[i], &b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

/// A scene holding one polygon given in 2D, placed in 3D by `place`.
template <class Place>
Scene polygonScene(const std::vector<dvec2>& poly, Place&& place) {
  Scene s;
  s.source = "test:polygon";
  std::vector<uint32_t> idx;
  for (const dvec2& p : poly) {
    idx.push_back(uint32_t(s.positions.size()));
    s.positions.push_back(place(p));
  }
  s.addFace(idx, {255, 255, 255, 255});
  s.finalize();
  return s;
}
Scene polygonScene(const std::vector<dvec2>& poly) {
  return polygonScene(poly, [](dvec2 p) { return dvec3(p, 0); });
}

/// Checks that the triangles of face 0 tile the simple polygon `poly` exactly: same winding as
/// the polygon, areas summing to the polygon's area, and every triangle inside it.
void expectExactTiling(const Scene& s, const std::vector<dvec2>& poly) {
  double polyArea = std::abs(signedArea2(poly)) / 2;
  double polySign = signedArea2(poly) > 0 ? 1 : -1;
  double sum = 0;
  ASSERT_FALSE(s.triangles.empty());
  for (const Triangle& t : s.triangles) {
    EXPECT_EQ(t.face, 0u);
    dvec2 a = poly[t.v[0]], b = poly[t.v[1]], c = poly[t.v[2]];
    double area2 = cross2(b - a, c - a);
    EXPECT_GT(area2 * polySign, 0) << "triangle wound against the polygon";
    sum += std::abs(area2) / 2;
    // The centroid and points just inside each corner must be inside the polygon.
    dvec2 centroid = (a + b + c) / 3.0;
    EXPECT_TRUE(inside(poly, centroid)) << "triangle outside the polygon";
    for (dvec2 corner : {a, b, c}) EXPECT_TRUE(inside(poly, corner + (centroid - corner) * 1e-3));
  }
  EXPECT_NEAR(sum, polyArea, 1e-9 * polyArea);
}

std::vector<dvec2> star(int points, double outer, double inner) {
  std::vector<dvec2> p;
  for (int i = 0; i < 2 * points; ++i) {
    double r = i % 2 ? inner : outer, a = std::numbers::pi * i / points;
    p.push_back({r * std::cos(a), r * std::sin(a)});
  }
  return p;
}

TEST(Scene, TriangleKeepsIndicesAndFace) {
  Scene s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};
  s.addFace({0, 1, 2}, {1, 2, 3, 4});
  s.addFace({2, 1, 3}, {5, 6, 7, 8});
  s.finalize();
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[0].v[0], 0u);
  EXPECT_EQ(s.triangles[0].v[2], 2u);
  EXPECT_EQ(s.triangles[1].face, 1u);
  EXPECT_EQ(s.faceColors[1], (Rgba8{5, 6, 7, 8}));
  EXPECT_EQ(s.problems.degenerateFaces, 0u);
}

TEST(Scene, ConvexQuadIsAFanWithTheQuadsWinding) {
  Scene s = polygonScene({{0, 0}, {2, 0}, {2, 1}, {0, 1}});
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.problems.concaveFaces, 0u);
  expectExactTiling(s, {{0, 0}, {2, 0}, {2, 1}, {0, 1}});
}

TEST(Scene, ConcaveLShapeTilesExactly) {
  std::vector<dvec2> l = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  Scene s = polygonScene(l);
  EXPECT_EQ(s.problems.concaveFaces, 1u);
  EXPECT_EQ(s.triangles.size(), 4u);
  expectExactTiling(s, l);
  // Clockwise too: the triangles follow the polygon's winding.
  std::reverse(l.begin(), l.end());
  expectExactTiling(polygonScene(l), l);
}

TEST(Scene, StarFarFromOriginInATiltedPlaneTilesExactly) {
  std::vector<dvec2> st = star(7, 3.0, 1.0);
  // A rigid placement: tilted plane, a million units from the origin. Areas are preserved.
  const dvec3 origin{1e6, -2e6, 3e6};
  const dvec3 u = glm::normalize(dvec3(1, 2, 0.5)), v = glm::normalize(glm::cross(dvec3(0.3, -0.2, 1), u));
  Scene s = polygonScene(st, [&](dvec2 p) { return origin + p.x * u + p.y * v; });
  EXPECT_EQ(s.problems.concaveFaces, 1u);
  EXPECT_EQ(s.problems.nonPlanarFaces, 0u);
  EXPECT_EQ(s.triangles.size(), st.size() - 2);
  expectExactTiling(s, st);
}

TEST(Scene, RandomStarShapedPolygonsTileExactly) {
  // Star-shaped around the origin (random radius per vertex at increasing angles) is always
  // simple; radii repeat now and then, so straight and nearly straight vertices occur too.
  std::mt19937_64 rng(12345);
  for (int trial = 0; trial < 200; ++trial) {
    int n = 3 + int(rng() % 60);
    std::vector<dvec2> p;
    for (int i = 0; i < n; ++i) {
      double a = 2 * std::numbers::pi * (i + 0.3 * std::uniform_real_distribution<double>(0, 1)(rng)) / n;
      double r = rng() % 4 == 0 ? 1.0 : std::uniform_real_distribution<double>(0.2, 3.0)(rng);
      p.push_back({r * std::cos(a), r * std::sin(a)});
    }
    SCOPED_TRACE("trial " + std::to_string(trial));
    Scene s = polygonScene(p);
    expectExactTiling(s, p);
  }
}

TEST(Scene, CombWithManyReflexVerticesTilesExactly) {
  // A comb: 400 teeth, 800 reflex corners; exercises the reflex-vertex grid.
  std::vector<dvec2> comb;
  const int teeth = 400;
  for (int i = 0; i < teeth; ++i) {
    comb.push_back({i * 2.0, 0});
    comb.push_back({i * 2.0 + 1, 0});
    comb.push_back({i * 2.0 + 1, -5});
    comb.push_back({i * 2.0 + 2, -5});
  }
  comb.push_back({teeth * 2.0, 1});
  comb.push_back({0, 1});
  std::reverse(comb.begin(), comb.end());  // clockwise
  Scene s = polygonScene(comb);
  EXPECT_EQ(s.triangles.size(), comb.size() - 2);
  expectExactTiling(s, comb);
}

TEST(Scene, SpiralTilesExactly) {
  std::vector<dvec2> outer, innerRev;
  for (int i = 0; i <= 300; ++i) {
    double a = i * 0.05, r = 1 + 0.2 * a;
    outer.push_back({r * std::cos(a), r * std::sin(a)});
    innerRev.push_back({(r - 0.1) * std::cos(a), (r - 0.1) * std::sin(a)});
  }
  std::vector<dvec2> spiral = outer;
  spiral.insert(spiral.end(), innerRev.rbegin(), innerRev.rend());
  Scene s = polygonScene(spiral);
  expectExactTiling(s, spiral);
}

TEST(Scene, StraightVerticesLeaveNoTJunctions) {
  // Extra vertices in the middle of straight edges: convex, but a fan from vertex 0 would make
  // a zero-area triangle and leave vertex 1 on another triangle's edge. Every vertex must be a
  // corner of a triangle, and no triangle may be degenerate (n - 2 triangles).
  std::vector<dvec2> p = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2}, {1, 2}, {0, 2}};
  Scene s = polygonScene(p);
  EXPECT_EQ(s.problems.concaveFaces, 0u);
  EXPECT_EQ(s.triangles.size(), p.size() - 2);
  expectExactTiling(s, p);
  std::vector<bool> used(p.size(), false);
  for (const Triangle& t : s.triangles)
    for (uint32_t v : t.v) used[v] = true;
  for (size_t v = 0; v < p.size(); ++v) EXPECT_TRUE(used[v]) << "vertex " << v << " is a T-junction";
}

// A polygon of many vertices has tiny turns and tiny ears, well-shaped for their size: a convex
// one of 100 000 vertices is a fan of n - 2 triangles (it used to be called too tangled and lose
// half its triangles), and a simple concave one is n - 2 triangles tiling it, with true notes.
TEST(Scene, LargeSimplePolygonsGiveNMinusTwoTriangles) {
  auto expectTiled = [](const Scene& s, const std::vector<dvec2>& poly, bool concave) {
    EXPECT_EQ(s.triangles.size(), poly.size() - 2);
    EXPECT_EQ(s.problems.concaveFaces, concave ? 1u : 0u);
    EXPECT_EQ(s.problems.degenerateFaces, 0u);
    for (const std::string& note : s.problems.notes) EXPECT_EQ(note.find("tangled"), std::string::npos) << note;
    double sum = 0;
    for (const Triangle& t : s.triangles) {
      const double area2 = cross2(poly[t.v[1]] - poly[t.v[0]], poly[t.v[2]] - poly[t.v[0]]);
      EXPECT_GT(area2, 0) << "triangle wound against the polygon";
      sum += area2 / 2;
    }
    const double area = signedArea2(poly) / 2;
    EXPECT_NEAR(sum, area, 1e-9 * area);
  };
  std::vector<dvec2> circle;
  for (int i = 0; i < 100000; ++i) {
    const double a = 2 * std::numbers::pi * i / 100000;
    circle.push_back({std::cos(a), std::sin(a)});
  }
  expectTiled(polygonScene(circle), circle, false);
  const std::vector<dvec2> fineStar = star(10000, 1.0, 0.999);  // 20 000 vertices, half reflex
  expectTiled(polygonScene(fineStar), fineStar, true);
}

TEST(Scene, DegenerateFacesAreCountedNotDrawn) {
  Scene s;
  s.source = "test:degenerate";
  s.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  s.addFace({0, 1, 2}, {});     // collinear
  s.addFace({0, 1, 1}, {});     // two distinct vertices
  s.addFace({0, 1, 1, 0}, {});  // quad of two vertices
  s.addFace({0, 1, 1, 3}, {});  // a repeated vertex, but still a triangle
  s.addFace({0, 1}, {});        // too few vertices
  s.finalize();
  EXPECT_EQ(s.problems.degenerateFaces, 4u);
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.triangles[0].face, 3u);
  ASSERT_GE(s.problems.notes.size(), 4u);
  EXPECT_NE(s.problems.notes[0].find("face 0"), std::string::npos);
  EXPECT_NE(s.problems.notes[0].find("zero area"), std::string::npos);
  EXPECT_NE(s.problems.notes[1].find("fewer than 3 distinct"), std::string::npos);
}

TEST(Scene, NonPlanarQuadIsCountedAndTriangulated) {
  Scene s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.2}, {0, 1, 0}};
  s.addFace({0, 1, 2, 3}, {});
  s.finalize();
  EXPECT_EQ(s.problems.nonPlanarFaces, 1u);
  EXPECT_EQ(s.triangles.size(), 2u);
  // Within 1e-6 of the plane size it counts as planar.
  s.positions[2].z = 1e-8;
  s.problems = {};
  s.finalize();
  EXPECT_EQ(s.problems.nonPlanarFaces, 0u);
}

TEST(Scene, SelfIntersectingPentagramTerminatesWithTriangles) {
  std::vector<dvec2> pentagram;
  for (int i = 0; i < 5; ++i) {
    double a = 2 * std::numbers::pi * (2 * i) / 5;
    pentagram.push_back({std::cos(a), std::sin(a)});
  }
  Scene s = polygonScene(pentagram);
  EXPECT_EQ(s.problems.concaveFaces, 1u);  // all turns agree, but it winds twice
  EXPECT_GE(s.triangles.size(), 1u);
  EXPECT_LE(s.triangles.size(), 3u);
}

TEST(Scene, TangledPolygonsFinishQuicklyWithANote) {
  // 20000 random vertices: a polygon crossing itself everywhere. Ear clipping must not spend a
  // lap around the polygon per triangle (minutes); it finishes and says so.
  std::mt19937_64 rng(7);
  std::vector<dvec2> p;
  for (int i = 0; i < 20000; ++i) p.push_back({double(rng() % 100000), double(rng() % 100000)});
  auto start = std::chrono::steady_clock::now();
  Scene s = polygonScene(p);
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(ms, 3000.0);  // ~70 ms in a release build
  EXPECT_GT(s.triangles.size(), 1000u);
  ASSERT_FALSE(s.problems.notes.empty());
  EXPECT_NE(s.problems.notes.back().find("too tangled"), std::string::npos);
}

TEST(Scene, NonFiniteAndOutOfRangeInputThrows) {
  Scene s;
  s.source = "model.xyz";
  s.positions = {{0, 0, 0}, {1, std::nan(""), 0}, {0, 1, 0}};
  s.addFace({0, 1, 2}, {});
  try {
    s.finalize();
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "model.xyz: vertex 1 has a non-finite coordinate");
  }
  s.positions[1] = {1, 0, std::numeric_limits<double>::infinity()};
  EXPECT_THROW(s.finalize(), InputError);
  s.positions[1] = {1, 0, 1e300};  // finite, but cross products would overflow
  EXPECT_THROW(s.finalize(), InputError);
  s.positions[1] = {1, 0, 0};
  s.addFace({0, 1, 7}, {});
  try {
    s.finalize();
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model.xyz: face 1: vertex index 7 out of range"), std::string::npos);
  }
}

TEST(Scene, MeshRangesCoverAllFaces) {
  Scene s;
  s.source = "dir/thing.obj";
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < 3; ++i) s.addFace({0, 1, 2}, {});
  s.finalize();  // no mesh begun: one mesh over everything
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_EQ(s.meshes[0].name, "thing");
  EXPECT_EQ(s.meshes[0].faceCount, 3u);

  Scene t;
  t.positions = s.positions;
  t.addFace({0, 1, 2}, {});  // before any mesh
  t.beginMesh("a");
  t.addFace({0, 1, 2}, {});
  t.addFace({0, 1, 2}, {});
  t.beginMesh("empty");
  t.beginMesh("b");
  t.addFace({0, 1, 2}, {});
  t.finalize();
  ASSERT_EQ(t.meshes.size(), 3u);
  EXPECT_EQ(t.meshes[0].firstFace, 0u);
  EXPECT_EQ(t.meshes[0].faceCount, 1u);
  EXPECT_EQ(t.meshes[1].name, "a");
  EXPECT_EQ(t.meshes[1].faceCount, 2u);
  EXPECT_EQ(t.meshes[2].name, "b");
  EXPECT_EQ(t.meshes[2].firstFace, 3u);
  EXPECT_EQ(t.meshes[2].faceCount, 1u);
}

TEST(Scene, BoundsCoverOnlyUsedVertices) {
  Scene s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 2}, {100, 100, 100}};
  EXPECT_TRUE(s.bounds().empty());
  s.addFace({0, 1, 2}, {});
  Bounds3 b = s.bounds();
  EXPECT_EQ(b.lo, dvec3(0, 0, 0));
  EXPECT_EQ(b.hi, dvec3(1, 1, 2));
}

TEST(Scene, MillionFacesFinalizeQuickly) {
  // 500k triangles and 250k quads on a grid: a smoke test of the per-face cost.
  Scene s;
  const int n = 500;
  for (int y = 0; y <= 2 * n; ++y)
    for (int x = 0; x <= n; ++x) s.positions.push_back({x, y, 0.001 * ((x * 7 + y * 3) % 5)});
  auto at = [&](int x, int y) { return uint32_t(y * (n + 1) + x); };
  for (int y = 0; y < 2 * n; ++y)
    for (int x = 0; x < n; ++x) {
      if (y % 2) {
        s.addFace({at(x, y), at(x + 1, y), at(x + 1, y + 1)}, {});
        s.addFace({at(x, y), at(x + 1, y + 1), at(x, y + 1)}, {});
      } else {
        s.addFace({at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)}, {});
      }
    }
  auto start = std::chrono::steady_clock::now();
  s.finalize();
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(s.triangles.size(), size_t(4 * n * n));
  EXPECT_LT(ms, 3000.0);  // typically ~100 ms in a release build; generous for shared machines
}

}  // namespace
}  // namespace hsr

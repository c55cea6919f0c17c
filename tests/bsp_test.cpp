// The BSP tree (include/hsr/bsp.hpp) and the `bsp` algorithm beyond what the conformance suite
// checks: split fragments, deep trees, the fragment limit, the cached tree, the heuristics.
#include <hsr/bsp.hpp>
#include <hsr/hsr.hpp>

#include <gtest/gtest.h>

#include <string_view>

#include <cmath>

#include "algorithms/polygon_split.hpp"
#include "conformance.hpp"

namespace hsr {
namespace {

// Which pixels a scene's faces cover (the textbook z-buffer on the reference rasterizer).
std::vector<bool> coverage(const Scene& scene, const Camera& camera) {
  RenderOptions options;
  options.params["raster"] = "halfspace";
  options.threads = 1;
  const Frame frame = render(scene, camera, options);
  std::vector<bool> covered(frame.faceId.size());
  for (size_t i = 0; i < covered.size(); ++i) covered[i] = frame.faceId[i] >= 0;
  return covered;
}

Scene polygonScene(const std::vector<std::vector<dvec3>>& polygons) {
  Scene s;
  s.source = "test:polygons";
  s.beginMesh("polygons");
  for (const auto& p : polygons) {
    std::vector<uint32_t> indices;
    for (const dvec3& v : p) {
      indices.push_back(uint32_t(s.positions.size()));
      s.positions.push_back(v);
    }
    s.addFace(indices, Rgba8{200, 100, 50, 255});
  }
  s.finalize();
  return s;
}

TEST(PolygonSplit, PiecesArePlanarAndCoverExactlyTheOriginal) {
  // A tilted convex octagon cut by three planes into up to eight pieces.
  std::vector<dvec3> octagon;
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * M_PI * (k + 0.3) / 8;
    octagon.emplace_back(std::cos(a), std::sin(a), 0.3 * std::cos(a) - 0.2 * std::sin(a));
  }
  algo::SplitPlane own;
  ASSERT_TRUE(algo::planeOfPolygon(octagon, own));
  std::vector<std::vector<dvec3>> pieces{octagon}, next;
  const algo::SplitPlane cuts[3] = {{glm::normalize(dvec3(1, 0.2, 0.1)), 0.13},
                                    {glm::normalize(dvec3(-0.3, 1, 0.4)), -0.21},
                                    {glm::normalize(dvec3(0.7, -0.6, 1)), 0.05}};
  std::vector<dvec3> front, back;
  for (const algo::SplitPlane& cut : cuts) {
    next.clear();
    for (const auto& p : pieces) {
      algo::splitPolygon(p, cut, 1e-12, front, back);
      if (!front.empty()) next.push_back(front);
      if (!back.empty()) next.push_back(back);
    }
    pieces.swap(next);
    if (&cut == &cuts[0]) ASSERT_EQ(pieces.size(), 2u);
  }
  EXPECT_GE(pieces.size(), 6u);
  for (const auto& p : pieces)
    for (const dvec3& v : p) EXPECT_LT(std::abs(own.distance(v)), 1e-12);
  const Camera camera = resolveCamera(frameBounds(polygonScene({octagon}).bounds()), 157, 111,
                                      polygonScene({octagon}).bounds());
  const std::vector<bool> whole = coverage(polygonScene({octagon}), camera);
  EXPECT_EQ(whole, coverage(polygonScene(pieces), camera));
  EXPECT_GT(std::count(whole.begin(), whole.end(), true), 2000);
}

TEST(Bsp, FragmentsKeepTheirFaceAndCoverExactlyIt) {
  const Scene scene = loadScene("builtin:random?n=60&seed=7");
  const BspTree tree = BspTree::build(scene);
  ASSERT_GT(tree.splits(), 0u);
  std::vector<std::vector<std::vector<dvec3>>> byFace(scene.faceCount());
  for (const BspTree::Fragment& f : tree.fragments()) {
    ASSERT_LT(f.face, scene.faceCount());
    EXPECT_EQ(scene.triangles[f.triangle].face, f.face);
    const auto p = tree.polygon(f);
    byFace[f.face].emplace_back(p.begin(), p.end());
    // Planar, in its face's plane.
    std::vector<dvec3> original;
    for (uint32_t v : scene.face(f.face)) original.push_back(scene.positions[v]);
    algo::SplitPlane plane;
    ASSERT_TRUE(algo::planeOfPolygon(original, plane));
    for (const dvec3& v : p) EXPECT_LT(std::abs(plane.distance(v)), 1e-9);
  }
  const Camera camera = resolveCamera(frameBounds(scene.bounds()), 200, 150, scene.bounds());
  int compared = 0;
  for (uint32_t f = 0; f < scene.faceCount() && compared < 12; ++f) {
    if (byFace[f].size() < 2) continue;
    std::vector<dvec3> original;
    for (uint32_t v : scene.face(f)) original.push_back(scene.positions[v]);
    EXPECT_EQ(coverage(polygonScene({original}), camera), coverage(polygonScene(byFace[f]), camera)) << "face " << f;
    ++compared;
  }
  EXPECT_GE(compared, 5);
}

TEST(Bsp, DeepChainOfAConvexMeshBuildsAndTraversesIteratively) {
  const Scene sphere = loadScene("builtin:sphere?n=20000");
  BspBuildOptions options;
  options.heuristic = BspHeuristic::First;
  const BspTree tree = BspTree::build(sphere, options);
  EXPECT_EQ(tree.splits(), 0u);
  EXPECT_EQ(tree.fragments().size(), tree.inputPolygons());
  EXPECT_GT(tree.depth(), 19000u);  // every face behind every other's plane: a chain
  std::vector<uint32_t> order;
  tree.backToFront(dvec4(0, 0, 10, 1), order);
  EXPECT_EQ(order.size(), tree.fragments().size());
}

TEST(Bsp, MaxFragmentsExceededIsAnInputError) {
  const Scene scene = loadScene("builtin:random?n=400&seed=3");
  BspBuildOptions options;
  options.maxFragments = scene.faceCount() + 10;
  EXPECT_THROW(BspTree::build(scene, options), InputError);
  RenderOptions render_;
  render_.algorithm = "bsp";
  render_.params["max-fragments"] = "100";
  try {
    render(scene, resolveCamera(frameBounds(scene.bounds()), 32, 24, scene.bounds()), render_);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("max-fragments=100"), std::string::npos) << e.what();
  }
}

TEST(Bsp, OneTreeFromTwentyPosesDrawsAsATreePerPose) {
  const Scene scene = loadScene("builtin:random?n=300&seed=11");
  const std::vector<conformance::Pose> poses = conformance::posesAround(scene, 20, 5);
  RenderOptions kept;
  kept.algorithm = "bsp";
  kept.threads = 1;
  Renderer renderer(scene, kept);  // builds its tree at the first pose, keeps it for the rest
  for (size_t i = 0; i < poses.size(); ++i) {
    const Camera camera = resolveCamera(poses[i].spec, 96, 64, scene.bounds());
    const Frame a = renderer.render(camera);
    EXPECT_EQ(a.stats.detailCount("built"), std::optional<uint64_t>(i == 0 ? 1 : 0));
    // A fresh tree: render() makes an algorithm object for the one view.
    const Frame b = render(scene, camera, kept);
    EXPECT_EQ(b.stats.detailCount("built"), std::optional<uint64_t>(1));
    EXPECT_TRUE(a.faceId == b.faceId) << "pose " << i;
    EXPECT_TRUE(a.color == b.color) << "pose " << i;
  }
}

// Both scoring heuristics beat the first polygon; on intersecting soup, weighing splits by area
// and trying the largest polygons makes clearly fewer fragments than scoring evenly spaced ones.
TEST(Bsp, ScoredHeuristicsMakeFewerFragmentsThanFirst) {
  for (const char* name : {"builtin:city", "builtin:random?n=2000", "builtin:random?n=5000"}) {
    const Scene scene = loadScene(name);
    BspBuildOptions first, scored, area;
    first.heuristic = BspHeuristic::First;
    scored.heuristic = BspHeuristic::Scored;
    area.heuristic = BspHeuristic::Area;
    const size_t byFirst = BspTree::build(scene, first).fragments().size();
    const size_t byScore = BspTree::build(scene, scored).fragments().size();
    const size_t byArea = BspTree::build(scene, area).fragments().size();
    EXPECT_LT(byScore, byFirst) << name;
    EXPECT_LT(byArea, byFirst) << name;
    if (std::string_view(name).starts_with("builtin:random")) EXPECT_LT(byArea, byScore * 85 / 100) << name;
    std::printf("%s: %zu faces, fragments first %zu, scored %zu, area %zu\n", name, scene.faceCount(), byFirst,
                byScore, byArea);
  }
}

}  // namespace
}  // namespace hsr

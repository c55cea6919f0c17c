// Newell's depth sort (src/algorithms/newell.cpp) beyond the registry-driven suite: its own run
// of the conformance plan (so it can be run alone), and the counts that say how each scene was
// ordered: cycles and interpenetration split, separable scenes never split.
#include <hsr/hsr.hpp>

#include <gtest/gtest.h>

#include "conformance.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

Frame renderNewell(const Scene& scene, const CameraSpec& spec, int w = 160, int h = 120) {
  RenderOptions options;
  options.algorithm = "newell";
  options.threads = 1;
  return render(scene, resolveCamera(spec, w, h, scene.bounds()), options);
}

uint64_t count(const Frame& f, const char* key) { return f.stats.detailCount(key).value_or(UINT64_MAX); }

// The whole conformance plan, for newell alone: the suite's test checks it among all algorithms.
TEST(Newell, KeepsItsGuaranteeOnTheConformancePlan) {
  const AlgorithmInfo* newell = findAlgorithm("newell");
  ASSERT_NE(newell, nullptr);
  EXPECT_EQ(newell->guarantee.kind, Guarantee::Kind::Exact);
  for (const conformance::Variant& variant : conformance::variantsOf(*newell)) {
    const std::vector<std::string> failures = conformance::check(variant, conformance::suitePlan());
    for (size_t i = 0; i < failures.size() && i < 5; ++i) ADD_FAILURE() << failures[i];
    EXPECT_TRUE(failures.empty()) << variant.describe() << ": " << failures.size() << " violations";
  }
}

// Random interpenetrating quads and pentagons, many seeds and poses, at a larger size than the
// plan's: zero wrong pixels, and the sort had to split.
TEST(Newell, ExactOnSeededInterpenetratingPolygons) {
  const conformance::Variant newell{findAlgorithm("newell"), {}};
  uint64_t splits = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const Scene scene = test::randomPolygons(40, seed);
    for (const conformance::Pose& pose : conformance::posesAround(scene, 6, seed * 7)) {
      const conformance::Outcome o =
          conformance::run(newell, "test:polygons", scene, pose, 96, 72, DepthFormat::parse("f32:reversed"));
      EXPECT_EQ(o.wrong, 0u) << "seed " << seed << "\n" << o.replay;
      splits += count(renderNewell(scene, pose.spec, 96, 72), "splits");
    }
  }
  EXPECT_GT(splits, 0u);
}

// The painter's failure scenes need a split; parallel layers never do (their planes decide);
// every pair is decided by one of the six tests, or moved a polygon, or split one.
TEST(Newell, CountsSayHowTheOrderWasFound) {
  const Scene cycle = loadScene("builtin:painter-cycle");
  const Frame c = renderNewell(cycle, *cycle.camera);
  EXPECT_GT(count(c, "splits"), 0u);
  EXPECT_GT(count(c, "fragments"), count(c, "polygons"));

  const Scene through = loadScene("builtin:interpenetrate");
  const Frame t = renderNewell(through, *through.camera);
  EXPECT_GT(count(t, "splits"), 0u);

  const Scene layers = loadScene("builtin:layers?n=12&order=front-to-back");
  const Frame l = renderNewell(layers, conformance::ownPose(layers).spec);
  EXPECT_EQ(count(l, "splits"), 0u);
  EXPECT_EQ(count(l, "fragments"), count(l, "polygons"));
  EXPECT_GT(count(l, "by_depth"), 0u);

  const Scene boxes = test::boxesScene();
  const Frame b = renderNewell(boxes, conformance::ownPose(boxes).spec);
  for (const Frame* f : {&c, &t, &l, &b}) {
    const uint64_t undecided = count(*f, "pairs") - count(*f, "by_depth") - count(*f, "by_x") - count(*f, "by_y") -
                               count(*f, "by_behind") - count(*f, "by_in_front") - count(*f, "by_disjoint");
    EXPECT_EQ(undecided, count(*f, "reorders") + count(*f, "splits"));
    EXPECT_LE(count(*f, "cycles"), count(*f, "splits"));
  }
  bool objectTime = false;
  for (const auto& [stage, ms] : c.stats.time_ms) objectTime |= stage == "depth_sort";
  EXPECT_TRUE(objectTime);
}

TEST(Newell, MaxFragmentsExceededIsAnInputError) {
  const Scene scene = test::randomPolygons(40, 3);
  RenderOptions options;
  options.algorithm = "newell";
  options.params["max-fragments"] = "5";
  const Camera camera = resolveCamera(conformance::ownPose(scene).spec, 64, 48, scene.bounds());
  EXPECT_THROW(render(scene, camera, options), InputError);
}

}  // namespace
}  // namespace hsr

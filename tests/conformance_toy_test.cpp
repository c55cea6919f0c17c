// The conformance suite picks up an algorithm registered only here, with no test code of its
// own, and its checker catches an algorithm whose declared guarantee is false.
#include <gtest/gtest.h>

#include <algorithm>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "conformance.hpp"

namespace hsr {
namespace {

// A toy: the front-to-back + z-buffer combination, in a few lines on the drawing service.
double nearestDepth(const SetupTriangle& t) {
  double d = t.eyeDepth(t.x[0] / 256.0, t.y[0] / 256.0);
  for (int k = 1; k < 3; ++k) d = std::min(d, t.eyeDepth(t.x[k] / 256.0, t.y[k] / 256.0));
  return d;
}

class FrontToBack final : public algo::SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    algo::drawScene(scene_, camera, options, algo::WriteRule::DepthTest, algo::drawRasterOf(params_),
                    [](std::vector<SetupTriangle>& tris) {
                      std::stable_sort(tris.begin(), tris.end(), [](const SetupTriangle& a, const SetupTriangle& b) {
                        return nearestDepth(a) < nearestDepth(b);
                      });
                    },
                    buffers_, frame);
  }
};

// Submission order under a write rule (a template parameter: the object is made from a scene
// and parameters only).
template <algo::WriteRule Rule>
class InSubmissionOrder final : public algo::SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    algo::drawScene(scene_, camera, options, Rule, algo::drawRasterOf(params_), {}, buffers_, frame);
  }
};

AlgorithmInfo toy(const std::string& name, algo::WriteRule rule, bool sorted) {
  AlgorithmInfo a;
  a.name = name;
  a.summary = "a test's toy";
  a.source = "tests/conformance_toy_test.cpp";
  a.params = {algo::drawRasterParam("halfspace")};
  if (sorted) a.create = algo::factoryOf<FrontToBack>();
  else if (rule == algo::WriteRule::DepthTest) a.create = algo::factoryOf<InSubmissionOrder<algo::WriteRule::DepthTest>>();
  else a.create = algo::factoryOf<InSubmissionOrder<algo::WriteRule::Overwrite>>();
  return a;
}

// Registered before main() by this one line: the registry-driven suite (conformance_test.cpp)
// checks it too.
const bool kToyRegistered = (registerAlgorithm(toy("test-front-to-back", algo::WriteRule::DepthTest, true)), true);

TEST(ConformanceToy, RegisteredToyIsInTheSuitesList) {
  ASSERT_TRUE(kToyRegistered);
  const AlgorithmInfo* found = findAlgorithm("test-front-to-back");
  ASSERT_NE(found, nullptr);
  bool listed = false;
  for (const AlgorithmInfo& a : algorithms()) listed |= &a == found;
  EXPECT_TRUE(listed);
  // Its variants: the default raster and the two others, each checked by the suite.
  EXPECT_EQ(conformance::variantsOf(*found).size(), 3u);
  // And it renders through render() like any other algorithm, its parameters recorded.
  const Scene scene = loadScene("builtin:cubes");
  RenderOptions options;
  options.algorithm = "test-front-to-back";
  options.params["raster"] = "binned";
  options.verify = true;
  const Frame frame = render(scene, resolveCamera(*scene.camera, 96, 64, scene.bounds()), options);
  EXPECT_EQ(frame.stats.algorithm, "test-front-to-back");
  ASSERT_EQ(frame.stats.params.size(), 1u);
  EXPECT_EQ(frame.stats.params[0], (std::pair<std::string, std::string>("raster", "binned")));
  EXPECT_EQ(frame.stats.wrong_pixels, 0u);
}

// A small plan around the painter's cycle scene, whose three polygons no order draws right.
conformance::Plan cyclePlan() {
  conformance::Plan plan;
  plan.cases = {{"builtin:painter-cycle", 4}, {"builtin:cubes", 4}};
  plan.determinismScenes = {"builtin:painter-cycle"};
  plan.determinismPoses = 1;
  return plan;
}

TEST(ConformanceToy, CheckerCatchesAFalseGuarantee) {
  // Painting in submission order with no depth test, declared exact: caught.
  AlgorithmInfo painter = toy("test-unsorted-painter", algo::WriteRule::Overwrite, false);
  const conformance::Variant variant{&painter, {}};
  EXPECT_FALSE(conformance::check(variant, cyclePlan()).empty());
  // Declared approximate within 0 wrong pixels: caught too.
  painter.guarantee.kind = Guarantee::Kind::Approximate;
  painter.guarantee.condition = "nothing";
  EXPECT_FALSE(conformance::check(variant, cyclePlan()).empty());
}

TEST(ConformanceToy, FailureByDesignIsCheckedBothWays) {
  AlgorithmInfo painter = toy("test-unsorted-painter", algo::WriteRule::Overwrite, false);
  painter.guarantee.kind = Guarantee::Kind::FailsByDesign;
  painter.guarantee.failsOn = {"builtin:painter-cycle"};
  const conformance::Variant variant{&painter, {}};
  conformance::Plan plan = cyclePlan();
  plan.cases = {{"builtin:painter-cycle", 4}};
  EXPECT_TRUE(conformance::check(variant, plan).empty());  // wrong there, as declared
  // The exact z-buffer in submission order, declared to fail on the cycle: it does not, which
  // the checker reports.
  AlgorithmInfo zbuffer = toy("test-zbuffer", algo::WriteRule::DepthTest, false);
  zbuffer.guarantee = painter.guarantee;
  EXPECT_FALSE(conformance::check({&zbuffer, {}}, plan).empty());
}

TEST(ConformanceToy, ExactWhenIsJudgedOnlyWhereItsConditionHolds) {
  AlgorithmInfo painter = toy("test-unsorted-painter", algo::WriteRule::Overwrite, false);
  painter.guarantee.kind = Guarantee::Kind::ExactWhen;
  painter.guarantee.condition = "never";
  painter.guarantee.holds = [](const Scene&, const Camera&, const RenderOptions&) { return false; };
  EXPECT_TRUE(conformance::check({&painter, {}}, cyclePlan()).empty());
  painter.guarantee.holds = [](const Scene&, const Camera&, const RenderOptions&) { return true; };
  EXPECT_FALSE(conformance::check({&painter, {}}, cyclePlan()).empty());
}

}  // namespace
}  // namespace hsr

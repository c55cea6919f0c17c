// Conformance of every registered algorithm against the exact reference (raycast), driven by
// the registry: each algorithm, at its defaults and with every other value of its choice
// parameters, on named scenes x seeded poses x image sizes x depth formats, checked by what its
// guarantee declares (conformance.hpp), and for the same bits with 1, 2 and 3 threads. A pixel
// may differ from the reference only where verify classifies it as ambiguous (depth closer than
// the format separates, or the centre on an edge); every failure prints a replay command.
#include <gtest/gtest.h>

#include "conformance.hpp"

namespace hsr {
namespace {

TEST(Conformance, EveryRegisteredAlgorithmKeepsItsGuarantee) {
  const conformance::Plan plan = conformance::fullPlan();
  size_t variants = 0;
  for (const AlgorithmInfo& algorithm : algorithms())
    for (const conformance::Variant& variant : conformance::variantsOf(algorithm)) {
      const std::vector<std::string> failures = conformance::check(variant, plan);
      // The first few in full (with their replay commands), then one line each.
      std::string rest;
      for (size_t i = 0; i < failures.size(); ++i)
        if (i < 5) ADD_FAILURE() << failures[i];
        else rest += failures[i].substr(0, failures[i].find('\n')) + "\n";
      EXPECT_TRUE(failures.empty()) << variant.describe() << ": " << failures.size() << " violations\n" << rest;
      ++variants;
    }
  EXPECT_GE(variants, 4u);  // zbuffer's three rasterizers and raycast at least
}

// The z-fighting scene with its own camera: u16:z cannot separate the two surfaces (many
// ambiguous pixels), f32:reversed can (none wrong, few ambiguous).
TEST(Conformance, ZFightingShowsAt16BitsNotWithReversedFloat) {
  const Scene scene = loadScene("builtin:zfight");
  ASSERT_TRUE(scene.camera.has_value());
  const conformance::Pose pose{*scene.camera};
  const conformance::Variant zbuffer{findAlgorithm("zbuffer"), {}};
  const conformance::Outcome u16 =
      conformance::run(zbuffer, "builtin:zfight", scene, pose, 128, 96, DepthFormat::parse("u16:z"));
  const conformance::Outcome f32 =
      conformance::run(zbuffer, "builtin:zfight", scene, pose, 128, 96, DepthFormat::parse("f32:reversed"));
  EXPECT_EQ(u16.wrong, 0u) << u16.replay;
  EXPECT_EQ(f32.wrong, 0u) << f32.replay;
  EXPECT_GT(u16.ambiguous, 100u);
  EXPECT_LT(f32.ambiguous * 10, u16.ambiguous);
}

}  // namespace
}  // namespace hsr

// Conformance of every registered algorithm against the exact reference (raycast), driven by
// the registry: each algorithm, at its defaults and with every other value of its choice
// parameters, on named scenes x seeded poses x image sizes x depth formats, checked by what its
// guarantee declares (conformance.hpp), and for the same bits with 1, 2 and 3 threads. A pixel
// may differ from the reference only where verify classifies it as ambiguous (depth closer than
// the format separates, or the centre on an edge); every failure prints a replay command.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <string>
#include <vector>

#include "conformance.hpp"

namespace hsr {
namespace {

// One test per algorithm of the built-in registry (so ctest runs them in parallel), each over
// every variant of its choice parameters.
class ConformanceOf : public ::testing::TestWithParam<std::string> {};

std::vector<std::string> registeredNames() {
  std::vector<std::string> names;
  for (const AlgorithmInfo& a : algorithms()) names.push_back(a.name);
  return names;
}

TEST_P(ConformanceOf, KeepsItsGuarantee) {
  const AlgorithmInfo* algorithm = findAlgorithm(GetParam());
  ASSERT_NE(algorithm, nullptr);
  const conformance::Plan plan = conformance::suitePlan();
  for (const conformance::Variant& variant : conformance::variantsOf(*algorithm)) {
    const std::vector<std::string> failures = conformance::check(variant, plan);
    // The first few in full (with their replay commands), then one line each.
    std::string rest;
    for (size_t i = 0; i < failures.size(); ++i)
      if (i < 5) ADD_FAILURE() << failures[i];
      else rest += failures[i].substr(0, failures[i].find('\n')) + "\n";
    EXPECT_TRUE(failures.empty()) << variant.describe() << ": " << failures.size() << " violations\n" << rest;
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, ConformanceOf, ::testing::ValuesIn(registeredNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

TEST(Conformance, TheBuiltInAlgorithmsAreAllCovered) {
  EXPECT_GE(registeredNames().size(), 6u);  // zbuffer, raycast and the painter's family at least
}

// The depth range drawn in parts (an int parameter, so variantsOf does not vary it): as exact as
// drawing it at once, with no crack or double cover where the parts' planes cut the triangles.
TEST(Conformance, TheZbufferDrawnInDepthSlicesIsExact) {
  const conformance::Plan plan = conformance::suitePlan();
  for (const std::map<std::string, std::string>& params :
       {std::map<std::string, std::string>{{"raster", "halfspace"}, {"slices", "3"}},
        std::map<std::string, std::string>{{"raster", "binned"}, {"slices", "7"}},
        std::map<std::string, std::string>{{"raster", "binned"}, {"slices", "16"}}}) {
    const conformance::Variant variant{findAlgorithm("zbuffer-sliced"), params};
    const std::vector<std::string> failures = conformance::check(variant, plan);
    for (size_t i = 0; i < std::min<size_t>(failures.size(), 5); ++i) ADD_FAILURE() << failures[i];
    EXPECT_TRUE(failures.empty()) << variant.describe() << ": " << failures.size() << " violations";
  }
}

// The image drawn region by region (a size parameter, not varied by variantsOf): exact at region
// sizes that do and do not divide the conformance suite's odd image sizes.
TEST(Conformance, TheZbufferDrawnRegionByRegionIsExact) {
  const conformance::Plan plan = conformance::suitePlan();
  for (const char* region : {"1x1", "7x5", "64x64", "1000x3"}) {
    const conformance::Variant variant{findAlgorithm("zbuffer-regions"), {{"region", region}}};
    const std::vector<std::string> failures = conformance::check(variant, plan);
    for (size_t i = 0; i < std::min<size_t>(failures.size(), 5); ++i) ADD_FAILURE() << failures[i];
    EXPECT_TRUE(failures.empty()) << variant.describe() << ": " << failures.size() << " violations";
  }
}

// Drawing the range in parts removes the z-fighting of a 16-bit z-buffer (KTH thesis).
TEST(Conformance, DepthSlicesRemoveZFighting) {
  const Scene scene = loadScene("builtin:zfight");
  const conformance::Pose pose{*scene.camera};
  const DepthFormat u16 = DepthFormat::parse("u16:z");
  auto ambiguous = [&](const char* slices) {
    const conformance::Variant v{findAlgorithm("zbuffer-sliced"), {{"raster", "binned"}, {"slices", slices}}};
    const conformance::Outcome o = conformance::run(v, "builtin:zfight", scene, pose, 128, 96, u16);
    EXPECT_EQ(o.wrong, 0u) << o.replay;
    return o.ambiguous;
  };
  const uint64_t once = ambiguous("1"), inParts = ambiguous("16");
  EXPECT_GT(once, 100u);
  EXPECT_LT(inParts * 10, once);
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

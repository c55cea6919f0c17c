// The algorithm contract: the registry's declarations, parameter checking, and the statistics
// recording which algorithm ran with which parameters.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <hsr/hsr.hpp>

namespace hsr {
namespace {

TEST(Algorithms, RegistryDeclaresZBufferAndRaycast) {
  const AlgorithmInfo* z = findAlgorithm("zbuffer");
  const AlgorithmInfo* r = findAlgorithm("raycast");
  ASSERT_NE(z, nullptr);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(z->guarantee.kind, Guarantee::Kind::Exact);
  ASSERT_EQ(z->params.size(), 2u);
  EXPECT_EQ(z->params[0].name, "raster");
  EXPECT_EQ(z->params[0].defaultValue, "tiled");
  EXPECT_EQ(z->params[0].choices, (std::vector<std::string>{"tiled", "halfspace", "scanline", "binned"}));
  EXPECT_EQ(z->params[1].name, "sort-key");
  // The documents' variants of the z-buffer are algorithms of their own, each with only the
  // parameters it uses.
  const AlgorithmInfo* sliced = findAlgorithm("zbuffer-sliced");
  ASSERT_NE(sliced, nullptr);
  ASSERT_EQ(sliced->params.size(), 2u);
  EXPECT_EQ(sliced->params[0].name, "slices");
  EXPECT_EQ(sliced->params[0].defaultValue, "4");
  EXPECT_EQ(sliced->params[1].choices, (std::vector<std::string>{"halfspace", "scanline", "binned"}));
  const AlgorithmInfo* regions = findAlgorithm("zbuffer-regions");
  ASSERT_NE(regions, nullptr);
  ASSERT_EQ(regions->params.size(), 1u);
  EXPECT_EQ(regions->params[0].type, ParamType::Size);
  EXPECT_EQ(regions->params[0].defaultValue, "64x64");
  ASSERT_NE(findAlgorithm("zbuffer-half-range"), nullptr);
  EXPECT_TRUE(findAlgorithm("zbuffer-half-range")->params.empty());
  ASSERT_NE(findAlgorithm("zbuffer-culled"), nullptr);
  ASSERT_EQ(findAlgorithm("zbuffer-culled")->params.size(), 1u);
  EXPECT_EQ(findAlgorithm("zbuffer-culled")->params[0].name, "temporal");
  EXPECT_EQ(findAlgorithm("zbuffer-culled")->params[0].defaultValue, "off");
  EXPECT_TRUE(r->params.empty());
  for (const AlgorithmInfo& a : algorithms()) {
    EXPECT_FALSE(a.summary.empty()) << a.name;
    EXPECT_FALSE(a.source.empty()) << a.name;
    EXPECT_FALSE(a.guarantee.describe().empty()) << a.name;
  }
  EXPECT_EQ(findAlgorithm("no-such"), nullptr);
}

TEST(Algorithms, ParametersAreCheckedAndDefaulted) {
  const AlgorithmInfo& z = *findAlgorithm("zbuffer");
  EXPECT_EQ(resolveParams(z, {}).text("raster"), "tiled");
  EXPECT_EQ(resolveParams(z, {{"raster", "scanline"}}).text("raster"), "scanline");
  try {
    resolveParams(z, {{"rastr", "halfspace"}});
    FAIL() << "a misspelt parameter was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rastr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("raster"), std::string::npos) << e.what();  // the right name offered
  }
  EXPECT_THROW(resolveParams(z, {{"raster", "fast"}}), InputError);
  EXPECT_THROW(resolveParams(*findAlgorithm("raycast"), {{"raster", "tiled"}}), InputError);
}

TEST(Algorithms, NumericAndBoolParametersAreTyped) {
  AlgorithmInfo a;
  a.name = "test-typed";
  a.params = {{"depth", ParamType::Int, "2", {}, 0, 8, "a whole number"},
              {"ratio", ParamType::Real, "0.5", {}, 0, 1, "a fraction"},
              {"split", ParamType::Bool, "on", {}, 0, 0, "a switch"}};
  const AlgorithmParams p = resolveParams(a, {{"depth", "3"}, {"split", "false"}});
  EXPECT_EQ(p.integer("depth"), 3);
  EXPECT_DOUBLE_EQ(p.real("ratio"), 0.5);
  EXPECT_FALSE(p.flag("split"));
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"depth", "2.5"}, {"depth", "9"}, {"depth", "x"}, {"ratio", "nan"}, {"ratio", "inf"}, {"ratio", "-0.1"},
           {"split", "maybe"}, {"depth", ""}})
    EXPECT_THROW(resolveParams(a, {{key, value}}), InputError) << key << "=" << value;
}

TEST(Algorithms, MalformedOrDuplicateDeclarationsAreRefused) {
  AlgorithmInfo copy = *findAlgorithm("zbuffer");
  EXPECT_THROW(registerAlgorithm(copy), std::invalid_argument);  // the name is taken
  AlgorithmInfo bad = copy;
  bad.name = "test-bad-default";
  bad.params[0].defaultValue = "nonsense";
  EXPECT_THROW(registerAlgorithm(bad), std::invalid_argument);
  AlgorithmInfo fails = copy;
  fails.name = "test-fails-nowhere";
  fails.guarantee.kind = Guarantee::Kind::FailsByDesign;  // but names no scene
  EXPECT_THROW(registerAlgorithm(fails), std::invalid_argument);
  EXPECT_EQ(findAlgorithm("test-bad-default"), nullptr);
}

TEST(Algorithms, StatisticsRecordTheAlgorithmItsParametersAndItsOwnCounters) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera cam = resolveCamera(*scene.camera, 64, 48, scene.bounds());
  for (const char* raster : {"tiled", "halfspace", "scanline"}) {
    RenderOptions o;
    o.params["raster"] = raster;
    const Frame f = render(scene, cam, o);
    const nlohmann::json j = nlohmann::json::parse(f.stats.toJson());
    EXPECT_EQ(j["algorithm"], "zbuffer");
    EXPECT_EQ(j["params"]["raster"], raster);
    // Which rasterizer ran is said in the algorithm's own object.
    EXPECT_EQ(j["zbuffer"]["rasterizer"], raster);
  }
  RenderOptions o;
  const nlohmann::json j = nlohmann::json::parse(render(scene, cam, o).stats.toJson());
  EXPECT_EQ(j["params"]["raster"], "tiled");  // the default, recorded
  EXPECT_TRUE(j["zbuffer"].contains("triangles_deferred"));
  EXPECT_FALSE(j.contains("triangles_deferred"));  // no longer a common key
}

TEST(Algorithms, TextbookZBufferCountsOneTestPerFragmentAndItsWrites) {
  const Scene scene = loadScene("builtin:painter-cycle");
  const Camera cam = resolveCamera(*scene.camera, 80, 60, scene.bounds());
  RenderOptions o;
  o.params["raster"] = "halfspace";
  o.countWrites = true;
  const Frame f = render(scene, cam, o);
  uint64_t writes = 0, covered = 0;
  for (size_t i = 0; i < f.writes.size(); ++i) {
    writes += f.writes[i];
    covered += f.faceId[i] >= 0;
    EXPECT_EQ(f.writes[i] > 0, f.faceId[i] >= 0) << i;
  }
  EXPECT_EQ(writes, f.stats.depth_writes);
  EXPECT_EQ(f.stats.color_writes, f.stats.depth_writes);
  EXPECT_EQ(covered, f.stats.covered_pixels);
  EXPECT_GE(f.stats.depth_tests, f.stats.depth_writes);
  EXPECT_GT(f.stats.depth_writes, f.stats.covered_pixels);  // the polygons overlap: some overdraw
  // The tiled z-buffer cannot count writes per pixel, and says so.
  o.params["raster"] = "tiled";
  EXPECT_THROW(render(scene, cam, o), InputError);
}

}  // namespace
}  // namespace hsr

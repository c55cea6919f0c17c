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
  ASSERT_EQ(z->params.size(), 6u);
  EXPECT_EQ(z->params[0].name, "raster");
  EXPECT_EQ(z->params[0].defaultValue, "tiled");
  EXPECT_EQ(z->params[0].choices, (std::vector<std::string>{"tiled", "halfspace", "scanline", "binned"}));
  EXPECT_EQ(z->params[1].name, "depth-slices");
  EXPECT_EQ(z->params[1].defaultValue, "1");
  EXPECT_EQ(z->params[2].name, "occlusion-cull");
  EXPECT_EQ(z->params[2].type, ParamType::Bool);
  EXPECT_EQ(z->params[2].defaultValue, "off");
  EXPECT_EQ(z->params[3].name, "region");
  EXPECT_EQ(z->params[3].type, ParamType::Size);
  EXPECT_EQ(z->params[3].defaultValue, "full");
  EXPECT_EQ(z->params[4].name, "sort-key");
  EXPECT_EQ(z->params[5].name, "clear");
  EXPECT_EQ(z->params[5].choices, (std::vector<std::string>{"every-frame", "half-range"}));
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

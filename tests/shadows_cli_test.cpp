// Tests of `hsr render --shadows` as scripts use it (as tests/cli_test.cpp does for the rest of the
// command line): the shadowed colour output, the statistics, --verify's shadow counts, the
// scene JSON's light and the flags that override it, and one-line errors with exit status 2.
#include <gtest/gtest.h>

#include "cli_runner.hpp"
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace {

using hsr::test::readText;
using Result = hsr::test::CliResult;

class ShadowsCommandLine : public hsr::test::CliTest {
 protected:
  // The sum of the red channel of a PNG written in the scratch directory.
  uint64_t redSum(const std::string& name) const {
    int w = 0, h = 0, channels = 0;
    uint8_t* pixels = stbi_load((dir_ / name).c_str(), &w, &h, &channels, 4);
    EXPECT_NE(pixels, nullptr) << name;
    uint64_t sum = 0;
    for (int i = 0; pixels && i < w * h; ++i) sum += pixels[4 * i];
    stbi_image_free(pixels);
    return sum;
  }
};

TEST_F(ShadowsCommandLine, ShadowsDarkenTheImageAndAreCounted) {
  const std::string common = "render builtin:city?blocks=4 --size 160x90 --threads 2 ";
  ASSERT_EQ(hsr(common + "-o plain.png --quiet").status, 0);
  Result r = hsr(common + "--shadows --light-dir 0.6,-1,0.4 --shadow-map-size 1024 -o shadowed.png --stats s.json --verify");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("shadows: directional 0.6,-1,0.4, cascaded, 4 map(s) of 1024x1024"), std::string::npos) << r;
  EXPECT_NE(r.out.find("shadow verify: "), std::string::npos) << r;
  EXPECT_LT(redSum("shadowed.png"), redSum("plain.png"));

  const nlohmann::json s = nlohmann::json::parse(readText(dir_ / "s.json"));
  const nlohmann::json& d = s.at("zbuffer");
  EXPECT_GT(d.at("shadow_shadowed_pixels").get<uint64_t>(), 0u);
  EXPECT_EQ(d.at("shadow_lit_pixels").get<uint64_t>() + d.at("shadow_shadowed_pixels").get<uint64_t>(),
            s.at("covered_pixels").get<uint64_t>());
  EXPECT_EQ(d.at("shadow_map_size"), 1024);
  EXPECT_EQ(d.at("shadow_method"), "cascaded");
  EXPECT_EQ(d.at("shadow_maps"), 4);
  EXPECT_TRUE(s.at("time_ms").contains("shadow_fit"));
  EXPECT_GT(s.at("memory").at("shadow_map").get<uint64_t>(), 1024u * 1024u * 4u - 1);
  EXPECT_TRUE(s.at("time_ms").contains("shadow_map"));
  EXPECT_TRUE(s.at("time_ms").contains("shadow_test"));
  EXPECT_TRUE(d.contains("shadow_wrong_away_from_edges"));
  EXPECT_LE(d.at("shadow_wrong_away_from_edges").get<uint64_t>(), d.at("shadow_wrong_pixels").get<uint64_t>());
}

TEST_F(ShadowsCommandLine, TheMethodAndCascadesAreFlags) {
  const std::string common = "render builtin:city?blocks=4 --size 160x90 --threads 2 --shadows --json ";
  Result r = hsr(common + "--shadow-method single --shadow-map-size 512");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s.at("zbuffer").at("shadow_method"), "single");
  EXPECT_EQ(s.at("zbuffer").at("shadow_maps"), 1);
  EXPECT_FALSE(s.at("time_ms").contains("shadow_fit"));
  r = hsr(common + "--shadow-method cascaded --shadow-cascades 2 --shadow-map-size 512");
  ASSERT_EQ(r.status, 0) << r;
  s = nlohmann::json::parse(r.out);
  EXPECT_EQ(s.at("zbuffer").at("shadow_method"), "cascaded");
  EXPECT_EQ(s.at("zbuffer").at("shadow_maps"), 2);
}

TEST_F(ShadowsCommandLine, BenchTimesTheShadowPass) {
  Result r = hsr("bench builtin:city?blocks=4 --size 160x90 --threads 2 --frames 2 --warmup 0 --warmup-time 0 "
                 "--shadows --light-dir 0.6,-1,0.4 --shadow-map-size 512");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("shadow pass (cascaded, 4 map(s) of 512x512, directional 0.6,-1,0.4) on builtin:city"),
            std::string::npos) << r;
  EXPECT_NE(r.out.find("shadow_fit"), std::string::npos) << r;
  EXPECT_NE(r.out.find("shadow_map"), std::string::npos) << r;
  EXPECT_NE(r.out.find("shadow_test"), std::string::npos) << r;
  r = hsr("bench builtin:cubes --size 64x64 --frames 1 --warmup 0 --warmup-time 0 --shadows --shadow-method single "
          "--shadow-map-size 256 --json");
  ASSERT_EQ(r.status, 0) << r;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("timed").get<std::string>().rfind("shadow pass (single, 1 map(s) of 256x256", 0), 0u) << r;
  EXPECT_TRUE(j.at("stage_median_ms").contains("shadow_map")) << r;
  EXPECT_TRUE(j.at("stage_median_ms").contains("shadow_test")) << r;
}

TEST_F(ShadowsCommandLine, TheSceneLightIsUsedAndFlagsOverrideIt) {
  writeFile("lit.json", R"({"meshes": [{"builtin": "cubes"}], "light": {"direction": [0.5, -1, -0.3]}})");
  Result r = hsr("render lit.json --size 96x64 --threads 1 --shadows --shadow-map-size 256 --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("zbuffer").at("shadow_light"), "directional 0.5,-1,-0.3") << r;
  r = hsr("render lit.json --size 96x64 --threads 1 --shadows --shadow-map-size 256 --light-pos 0,30,0 --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("zbuffer").at("shadow_light"), "point 0,30,0") << r;
}

TEST_F(ShadowsCommandLine, BadShadowInputIsExitTwoWithOneLine) {
  writeFile("bad.json", "{\n  \"meshes\": [{\"builtin\": \"cubes\"}],\n  \"light\": {\"direction\": [0, 0, 0]}\n}\n");
  struct Case {
    std::string args, says;
  };
  const std::string base = "render builtin:cubes --size 32x32 -o x.png ";
  for (const Case& c : {Case{base + "--shadows --light-dir 0,0,0", "--light-dir '0,0,0'"},
                        Case{base + "--shadows --light-dir 1,nan,0", "--light-dir"},
                        Case{base + "--shadows --light-dir 1,2", "x,y,z"},
                        Case{base + "--shadows --light-pos 0,0,0", "inside the scene's bounds"},
                        Case{base + "--shadows --shadow-map-size 8", "--shadow-map-size 8"},
                        Case{base + "--shadows --shadow-map-size 100000", "--shadow-map-size"},
                        Case{base + "--shadows --shadow-bias -1", "--shadow-bias"},
                        Case{base + "--shadows --shadow-bias nan", "--shadow-bias"},
                        Case{base + "--shadows --shadow-method fancy", "--shadow-method 'fancy': expected single or cascaded"},
                        Case{base + "--shadows --shadow-method ''", "--shadow-method"},
                        Case{base + "--shadows --shadow-cascades 0", "--shadow-cascades"},
                        Case{base + "--shadows --shadow-cascades 17", "--shadow-cascades"},
                        Case{base + "--shadows --shadow-cascades two", "--shadow-cascades"},
                        Case{base + "--shadows --shadow-method single --shadow-cascades 2", "--shadow-cascades"},
                        Case{base + "--shadows --shadow-cascades 16 --shadow-map-size 16384", "2^32"},
                        Case{base + "--shadow-cascades 2", "--shadows"},
                        Case{"bench builtin:cubes --size 32x32 --shadows --orbit", "--orbit"},
                        Case{"bench builtin:cubes --size 32x32 --shadows --shadow-cascades 0", "--shadow-cascades"},
                        Case{"bench builtin:cubes --size 32x32 --shadows --outputs depth,face", "triangle"},
                        Case{base + "--light-dir 0,-1,0", "--shadows"},
                        Case{base + "--shadows --light-dir 0,-1,0 --light-pos 0,9,0", "excludes"},
                        Case{"render builtin:cubes --size 32x32 --shadows --outputs depth,face", "triangle"},
                        Case{"render bad.json --size 32x32 --shadows", "bad.json:3: light: direction must not be zero"}}) {
    Result r = hsr(c.args);
    EXPECT_EQ(r.status, 2) << c.args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << c.args << "\n" << r;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << "\n" << r;
    EXPECT_FALSE(fs::exists(dir_ / "x.png")) << c.args;
  }
}

}  // namespace

// Tests of the `hsr` command line as scripts use it: runs the built binary (HSR_CLI_PATH) in a
// scratch directory and checks exit status, the one-line error on stderr, the files written and
// the JSON printed (CONVENTIONS.md "Command line").
#include <gtest/gtest.h>

#include "cli_runner.hpp"
#include <nlohmann/json.hpp>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using hsr::test::readText;
using Result = hsr::test::CliResult;

class CommandLine : public hsr::test::CliTest {
 protected:
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

// The header text and data of an NPY file.
std::pair<std::string, std::string> splitNpy(const std::string& npy) {
  EXPECT_GE(npy.size(), 10u);
  EXPECT_EQ(npy.compare(0, 6, "\x93NUMPY"), 0);
  size_t len = uint8_t(npy[8]) | (size_t(uint8_t(npy[9])) << 8);
  return {npy.substr(10, len), npy.substr(10 + len)};
}

}  // namespace

TEST_F(CommandLine, ScenesListsBuiltins) {
  Result r = hsr("scenes");
  EXPECT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("builtin:cubes"), std::string::npos) << r;
  EXPECT_TRUE(r.err.empty()) << r;
}

TEST_F(CommandLine, VersionAndHelp) {
  Result r = hsr("--version");
  EXPECT_EQ(r.status, 0) << r;
  EXPECT_EQ(r.out.rfind("hsr ", 0), 0u) << r;
  r = hsr("help");
  EXPECT_EQ(r.status, 0) << r;
  for (const char* command : {"render", "bench", "algorithms", "scenes", "info", "help"}) EXPECT_NE(r.out.find(command), std::string::npos);
}

TEST_F(CommandLine, HelpRenderMentionsEveryFlag) {
  Result r = hsr("help render");
  ASSERT_EQ(r.status, 0) << r;
  for (const char* flag :
       {"--camera", "--size", "--algorithm", "--depth-format", "--out", "-o", "--ids", "--depth ", "--depth-image",
        "--stats", "--verify", "--threads", "--param", "--overdraw-image", "--cull", "--shading", "--background", "--eye", "--target",
        "--up", "--fov", "--near", "--far", "--ortho", "--json", "--quiet", "zbuffer"})
    EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
  EXPECT_EQ(hsr("render --help").out, r.out);
}

TEST_F(CommandLine, RenderWritesPngOfRequestedSize) {
  Result r = hsr("render builtin:cubes -o c.png --size 64x48 --threads 1");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_TRUE(r.err.empty()) << r;
  EXPECT_NE(r.out.find("64x48"), std::string::npos) << r;
  int w = 0, h = 0, channels = 0;
  uint8_t* pixels = stbi_load(file("c.png").c_str(), &w, &h, &channels, 0);
  ASSERT_NE(pixels, nullptr);
  stbi_image_free(pixels);
  EXPECT_EQ(w, 64);
  EXPECT_EQ(h, 48);
  EXPECT_EQ(listing(), std::vector<std::string>{"c.png"});  // no temporary left behind
}

TEST_F(CommandLine, IdsAndDepthNpyAgree) {
  Result r = hsr("render builtin:cubes --size 64x48 --threads 1 --ids ids.npy --depth d.npy --quiet");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_TRUE(r.out.empty()) << r;
  auto [idsHeader, ids] = splitNpy(readText(file("ids.npy")));
  auto [depthHeader, depth] = splitNpy(readText(file("d.npy")));
  EXPECT_NE(idsHeader.find("'<i4'"), std::string::npos) << idsHeader;
  EXPECT_NE(idsHeader.find("(48, 64)"), std::string::npos) << idsHeader;
  EXPECT_NE(depthHeader.find("'<f4'"), std::string::npos) << depthHeader;
  ASSERT_EQ(ids.size(), 64u * 48 * 4);
  ASSERT_EQ(depth.size(), 64u * 48 * 4);
  // Every pixel is background (-1, +inf) or a face (id >= 0, finite positive depth); both occur.
  size_t covered = 0, empty = 0;
  for (size_t i = 0; i < 64 * 48; ++i) {
    int32_t id;
    float d;
    std::memcpy(&id, ids.data() + 4 * i, 4);
    std::memcpy(&d, depth.data() + 4 * i, 4);
    if (id == -1) {
      EXPECT_TRUE(std::isinf(d)) << i;
      ++empty;
    } else {
      EXPECT_TRUE(id >= 0 && std::isfinite(d) && d > 0) << i << ": " << id << " " << d;
      ++covered;
    }
  }
  EXPECT_GT(covered, 0u);
  EXPECT_GT(empty, 0u);
}

// --outputs: only the buffers asked for are resolved; the files written from them are the same
// bytes as a full render's.
TEST_F(CommandLine, OutputsListKeepsOnlyWhatIsAsked) {
  ASSERT_EQ(hsr("render builtin:cubes --size 64x48 --ids full.npy --depth full_d.npy -o full.png -q").status, 0);
  Result r = hsr("render builtin:cubes --size 64x48 --outputs depth,face,color --ids part.npy --depth part_d.npy "
                 "-o part.png --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(readText(file("part.npy")), readText(file("full.npy")));
  EXPECT_EQ(readText(file("part_d.npy")), readText(file("full_d.npy")));
  EXPECT_EQ(readText(file("part.png")), readText(file("full.png")));
  Result full = hsr("bench builtin:cubes --size 64x48 --frames 1 --warmup-time 0 --json");
  Result part = hsr("bench builtin:cubes --size 64x48 --frames 1 --warmup-time 0 --json --outputs face,depth");
  ASSERT_EQ(full.status, 0) << full;
  ASSERT_EQ(part.status, 0) << part;
  const nlohmann::json f = nlohmann::json::parse(full.out), p = nlohmann::json::parse(part.out);
  EXPECT_EQ(f["outputs"], "depth,face,triangle,color");
  EXPECT_EQ(p["outputs"], "depth,face");
  EXPECT_EQ(p["color_writes"], 0);
  EXPECT_GT(f["color_writes"].get<int>(), 0);
  EXPECT_EQ(p["covered_pixels"], f["covered_pixels"]);
  EXPECT_EQ(f["memory_bytes"].get<uint64_t>() - p["memory_bytes"].get<uint64_t>(), 64u * 48 * 8);  // two buffers
}

TEST_F(CommandLine, StatsJsonHasConventionKeys) {
  Result r = hsr("render builtin:cubes --size 64x48 --threads 1 --stats s.json --verify");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("verify"), std::string::npos) << r;
  nlohmann::json stats = nlohmann::json::parse(readText(file("s.json")));
  for (const char* key : {"algorithm", "width", "height", "faces", "triangles", "triangles_clipped", "culled_backface",
                          "culled_frustum", "culled_occlusion", "depth_tests", "depth_writes", "color_writes",
                          "covered_pixels", "overdraw", "memory_bytes", "time_ms", "wrong_pixels", "ambiguous_pixels"})
    EXPECT_TRUE(stats.contains(key)) << key;
  EXPECT_EQ(stats["algorithm"], "zbuffer");
  EXPECT_EQ(stats["width"], 64);
  EXPECT_EQ(stats["height"], 48);
  EXPECT_TRUE(stats["time_ms"].is_object());

  r = hsr("render builtin:cubes --size 64x48 --threads 1 --json");  // the same object on stdout
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out)["covered_pixels"], stats["covered_pixels"]);
}

TEST_F(CommandLine, BenchJsonHasTimesAndStatistics) {
  Result r = hsr("bench builtin:cubes --frames 3 --warmup 4 --warmup-time 0 --json --size 64x48");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json bench = nlohmann::json::parse(r.out);
  EXPECT_EQ(bench["frames"], 3);
  EXPECT_EQ(bench["warmup"], 4);  // frames only, with --warmup-time 0
  EXPECT_GT(bench["median_ms"].get<double>(), 0.0);
  EXPECT_LE(bench["min_ms"].get<double>(), bench["median_ms"].get<double>());
  EXPECT_EQ(bench["frame_ms"].size(), 3u);
  EXPECT_GE(bench["threads"].get<int>(), 1);
  EXPECT_EQ(bench["scene"], "builtin:cubes");
  EXPECT_EQ(bench["width"], 64);
  EXPECT_TRUE(bench.contains("covered_pixels"));
  EXPECT_FALSE(bench["kernel_isa"].get<std::string>().empty());
  EXPECT_NE(bench["build"]["flags"].get<std::string>().find("-ffp-contract=off"), std::string::npos);
  EXPECT_TRUE(bench["build"].contains("build_type"));
  EXPECT_FALSE(bench["cpu"].get<std::string>().empty());
}

TEST_F(CommandLine, BenchWarmsUpForAtLeastItsTime) {
  // Untimed frames until both --warmup frames and --warmup-time seconds are done.
  Result r = hsr("bench builtin:cubes --frames 1 --warmup 0 --warmup-time 0.3 --json --size 64x48");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json bench = nlohmann::json::parse(r.out);
  EXPECT_GE(bench["warmup_ms"].get<double>(), 300.0);
  EXPECT_GE(bench["warmup"].get<int>(), 1);
  EXPECT_EQ(bench["frames"], 1);
  r = hsr("bench builtin:cubes --frames 1 --warmup 0 --warmup-time 0 --json --size 64x48");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out)["warmup"], 0);
  EXPECT_NE(hsr("bench builtin:cubes --warmup-time -1").status, 0);
}

// --occlusion times the occlusion buffer: its statistics, and the depth-only frame's coverage.
TEST_F(CommandLine, BenchOcclusionTimesTheOcclusionBuffer) {
  Result r = hsr("bench builtin:city --frames 2 --warmup-time 0 --json --size 160x90 --occlusion");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json bench = nlohmann::json::parse(r.out);
  EXPECT_EQ(bench["algorithm"], "occlusion");
  Result d = hsr("bench builtin:city --frames 1 --warmup-time 0 --json --size 160x90 --depth-only");
  ASSERT_EQ(d.status, 0) << d;
  nlohmann::json depth = nlohmann::json::parse(d.out);
  EXPECT_EQ(bench["covered_pixels"], depth["covered_pixels"]);
  EXPECT_GT(bench["covered_pixels"].get<int>(), 1000);
  Result bad = hsr("bench builtin:city --frames 1 --occlusion --param raster=halfspace");
  EXPECT_EQ(bad.status, 2) << bad;
  EXPECT_NE(bad.err.find("--occlusion"), std::string::npos) << bad;
}

TEST_F(CommandLine, InfoDescribesScene) {
  Result r = hsr("info builtin:cubes --json");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json info = nlohmann::json::parse(r.out);
  EXPECT_GT(info["faces"].get<int>(), 0);
  EXPECT_GE(info["triangles"].get<int>(), info["faces"].get<int>());
  EXPECT_FALSE(info["meshes"].empty());
  EXPECT_TRUE(info["bounds"].contains("min"));
  EXPECT_EQ(hsr("info builtin:cubes").status, 0);
}

TEST_F(CommandLine, BadUsageIsExitTwoWithOneLine) {
  for (const char* args :
       {"render builtin:cubes --bogus", "render builtin:cubes --size 0x5", "render builtin:cubes --size abc",
        "render builtin:cubes --size 64x", "render builtin:cubes --size 16385x8", "render builtin:cubes --threads -1",
        "render builtin:cubes --algorithm nonsense", "render builtin:cubes --cull sideways",
        "render builtin:cubes --eye 1,2", "render builtin:cubes --fov nan", "render builtin:cubes --background 1,2,300",
        "render builtin:cubes --depth d.tiff", "render builtin:cubes --depth-only -o c.png",
        "render builtin:cubes --depth-only --ids i.png", "render builtin:cubes --depth-only --verify", "render",
        "render builtin:cubes --outputs depth,colour", "render builtin:cubes --outputs face --depth-only",
        "render builtin:cubes --outputs depth,face -o c.png", "render builtin:cubes --outputs color --ids i.png",
        "render builtin:cubes --outputs face,color --verify", "bench builtin:cubes --outputs face,",
        "render builtin:cubes --outputs \"\"", 
        "bench builtin:cubes --frames 0", "help nonsense", ""}) {
    Result r = hsr(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << args << "\n" << r;
  }
  EXPECT_TRUE(listing().empty());
}

TEST_F(CommandLine, MissingSceneFileIsNamed) {
  Result r = hsr("render no_such_scene.obj -o c.png");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("no_such_scene.obj"), std::string::npos) << r;
  EXPECT_TRUE(listing().empty());
}

TEST_F(CommandLine, BadCameraFileIsNamedAndNothingWritten) {
  writeFile("cam.json", "{\"eye\": [0, 0, 5], \"target\": [0, 0");
  Result r = hsr("render builtin:cubes --camera cam.json -o c.png");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("cam.json"), std::string::npos) << r;

  r = hsr("render builtin:cubes --camera missing.json -o c.png");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r;
  EXPECT_EQ(listing(), std::vector<std::string>{"cam.json"});
}

TEST_F(CommandLine, CameraFileAndFlags) {
  writeFile("cam.json", R"({"eye": [0, 0, 12], "target": [0, 0, 0], "up": [0, 1, 0], "fovy_deg": 50})");
  Result r = hsr("render builtin:cubes --camera cam.json --size 32x24 --threads 1 --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_GT(nlohmann::json::parse(r.out)["covered_pixels"].get<int>(), 0);
  // Flags override the file: looking away from the scene sees nothing.
  r = hsr("render builtin:cubes --camera cam.json --target 0,0,100 --size 32x24 --threads 1 --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out)["covered_pixels"], 0);
  // A degenerate camera from the flags is bad input.
  r = hsr("render builtin:cubes --eye 1,1,1 --target 1,1,1");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
}

TEST_F(CommandLine, UnwritableOutputIsExitOne) {
  Result r = hsr("render builtin:cubes --size 16x16 -o no/such/dir/c.png");
  EXPECT_EQ(r.status, 1) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("no/such/dir/c.png"), std::string::npos) << r;
  EXPECT_TRUE(listing().empty());
}

TEST_F(CommandLine, AlgorithmsListsEveryAlgorithmWithGuaranteeAndParameters) {
  Result r = hsr("algorithms");
  ASSERT_EQ(r.status, 0) << r;
  for (const char* text : {"zbuffer", "raycast", "guarantee: exact", "--param raster=tiled|halfspace|scanline",
                           "(default tiled)", "source:"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r;
  EXPECT_EQ(hsr("help algorithms").out, r.out);
  Result j = hsr("algorithms --json");
  ASSERT_EQ(j.status, 0) << j;
  const nlohmann::json list = nlohmann::json::parse(j.out);
  ASSERT_GE(list.size(), 2u);
  EXPECT_EQ(list[0]["name"], "zbuffer");
  EXPECT_EQ(list[0]["params"][0]["name"], "raster");
  EXPECT_EQ(list[0]["params"][0]["values"].size(), 4u);
  EXPECT_EQ(list[1]["guarantee"], "exact");
}

// --markdown: every algorithm's parameter table under its name, or one algorithm's alone.
TEST_F(CommandLine, AlgorithmsMarkdownPrintsParameterTables) {
  Result all = hsr("algorithms --markdown");
  ASSERT_EQ(all.status, 0) << all;
  for (const char* text : {"## zbuffer\n\n| `--param` | type | default | values | what |\n|---|---|---|---|---|\n",
                           "| `raster` | choice | `tiled` | `tiled`, `halfspace`, `scanline`, `binned` | ",
                           "## zbuffer-sliced\n", "| `slices` | int | `4` | 1 to 64 | ",
                           "| `region` | size | `64x64` | `WxH` (each 1 to 16384), `full` | ",
                           "## hzb\n", "| `occlusion-cull` | bool | `off` | `on`, `off` | ", "\n## raycast\n\nNone.\n", "\\|front - back\\|"})
    EXPECT_NE(all.out.find(text), std::string::npos) << text << "\n" << all;
  Result one = hsr("algorithms --markdown raycast");
  ASSERT_EQ(one.status, 0) << one;
  EXPECT_EQ(one.out, "None.\n");
  for (const char* bad : {"algorithms --markdown nosuch", "algorithms zbuffer", "algorithms --markdown --json"}) {
    Result r = hsr(bad);
    EXPECT_EQ(r.status, 2) << bad << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
  }
}

// Each registered algorithm's page, docs/algorithms/NAME.md, shows between its params markers
// exactly what `hsr algorithms --markdown NAME` prints: scripts/docs-params.sh rewrites them.
TEST_F(CommandLine, DocsShowEachAlgorithmsGeneratedParameterTable) {
  const nlohmann::json list = nlohmann::json::parse(hsr("algorithms --json").out);
  ASSERT_FALSE(list.empty());
  for (const nlohmann::json& algorithm : list) {
    const std::string name = algorithm["name"];
    const fs::path page = fs::path(HSR_SOURCE_DIR) / "docs" / "algorithms" / (name + ".md");
    const std::string text = readText(page);
    const std::string begin = "<!-- params: generated by hsr algorithms --markdown " + name + "; do not edit -->\n";
    const size_t from = text.find(begin);
    ASSERT_NE(from, std::string::npos) << page << " has no generated parameter table";
    const size_t to = text.find("<!-- end params -->", from);
    ASSERT_NE(to, std::string::npos) << page << ": no end marker";
    Result r = hsr("algorithms --markdown " + name);
    ASSERT_EQ(r.status, 0) << r;
    EXPECT_EQ(text.substr(from + begin.size(), to - from - begin.size()), "\n" + r.out + "\n")
        << page << " differs from 'hsr algorithms --markdown " << name << "': run scripts/docs-params.sh";
  }
}

TEST_F(CommandLine, ParamTyposAndBadValuesAreExit2NamingThem) {
  for (const auto& [args, named] : std::vector<std::pair<std::string, std::string>>{
           {"--param rastr=halfspace", "rastr"},
           {"--param raster=fast", "fast"},
           {"--param raster", "KEY=VALUE"},
           {"--param raster=halfspace --param raster=tiled", "twice"},
           {"--algorithm raycast --param raster=tiled", "raycast has no parameter"}}) {
    Result r = hsr("render builtin:cubes --size 32x24 -o x.png " + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find(named), std::string::npos) << args << "\n" << r;
    EXPECT_FALSE(fs::exists(file("x.png"))) << args;
  }
}

TEST_F(CommandLine, StatisticsRecordParamsAndTheOverdrawImageIsWritten) {
  Result r = hsr("render builtin:painter-cycle --size 64x48 --param raster=scanline --stats s.json "
                 "--overdraw-image o.png --threads 1 -q");
  ASSERT_EQ(r.status, 0) << r;
  const nlohmann::json stats = nlohmann::json::parse(readText(file("s.json")));
  EXPECT_EQ(stats["algorithm"], "zbuffer");
  EXPECT_EQ(stats["params"]["raster"], "scanline");
  EXPECT_EQ(stats["zbuffer"]["rasterizer"], "scanline");
  EXPECT_EQ(stats["zbuffer"]["write_rule"], "depth-test");
  int w = 0, h = 0, n = 0;
  unsigned char* pixels = stbi_load(file("o.png").c_str(), &w, &h, &n, 3);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(w, 64);
  EXPECT_EQ(h, 48);
  // Somewhere the cycle's polygons overlap: a pixel written twice (green on the fixed scale).
  bool twice = false;
  for (int i = 0; i < w * h; ++i) twice |= pixels[3 * i] == 40 && pixels[3 * i + 1] == 170 && pixels[3 * i + 2] == 80;
  stbi_image_free(pixels);
  EXPECT_TRUE(twice);
  // The tiled z-buffer cannot count per-pixel writes: a clear refusal, nothing written.
  Result tiled = hsr("render builtin:painter-cycle --size 64x48 --overdraw-image t.png");
  EXPECT_EQ(tiled.status, 2) << tiled;
  EXPECT_NE(tiled.err.find("raster=halfspace"), std::string::npos) << tiled;
  EXPECT_FALSE(fs::exists(file("t.png")));
}

// --orbit: each timed frame from another pose; per-frame stages apart from the first frame's
// build (a BSP tree is built once, in the first frame of the process).
TEST_F(CommandLine, BenchOrbitTimesTheBuildOnceAndTheFramesApart) {
  Result r = hsr("bench builtin:cubes --algorithm bsp --orbit --frames 4 --warmup 0 --warmup-time 0 --json --size 64x48");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json bench = nlohmann::json::parse(r.out);
  EXPECT_EQ(bench["poses"], 4);
  EXPECT_EQ(bench["frame_ms"].size(), 4u);
  EXPECT_TRUE(bench["first_frame_stages_ms"].contains("build")) << bench.dump();
  EXPECT_FALSE(bench["stage_median_ms"].contains("build")) << bench.dump();  // only the first frame built
  EXPECT_TRUE(bench["stage_median_ms"].contains("traverse")) << bench.dump();
  EXPECT_TRUE(bench["stage_median_ms"].contains("raster")) << bench.dump();
  Result text = hsr("bench builtin:cubes --algorithm bsp --orbit --frames 3 --warmup-time 0 --size 64x48");
  ASSERT_EQ(text.status, 0) << text;
  EXPECT_NE(text.out.find("an orbit of 3 poses"), std::string::npos) << text;
  EXPECT_NE(text.out.find("per frame, median ms:"), std::string::npos) << text;
}

TEST_F(CommandLine, PrecisionPrintsEveryFormatAndTheThesisClaims) {
  Result r = hsr("precision --near 1 --far 100 --json");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json p = nlohmann::json::parse(r.out);
  EXPECT_EQ(p["formats"].size(), 16u);
  EXPECT_EQ(p["claims"].size(), 2u);
  for (const auto& f : p["formats"]) EXPECT_GT(f["values"].get<uint64_t>(), 1000u) << f.dump();
  Result text = hsr("precision --near 0.1 --far 100 --formats u16:z,f32:reversed");
  ASSERT_EQ(text.status, 0) << text;
  EXPECT_NE(text.out.find("u16:z"), std::string::npos);
  EXPECT_EQ(text.out.find("u24:z "), std::string::npos);
  for (const char* args : {"precision --near 0 --far 1", "precision --near 2 --far 1", "precision --far nan",
                           "precision --formats u17:z"}) {
    Result bad = hsr(args);
    EXPECT_EQ(bad.status, 2) << args << "\n" << bad;
    EXPECT_TRUE(bad.oneErrorLine()) << args << "\n" << bad;
  }
}

TEST_F(CommandLine, CompareOnGivenScenesWritesResultsAndReport) {
  Result r = hsr("compare builtin:painter-cycle --sizes 48x36 --algorithms raycast,painter,bsp,zbuffer:raster=halfspace "
                 "--frames 1 --quiet --out study");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json results = nlohmann::json::parse(readText(file("study/results.json")));
  ASSERT_EQ(results["cases"].size(), 1u);
  const auto& runs = results["cases"][0]["runs"];
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[1]["variant"], "painter");
  EXPECT_GT(runs[1]["wrong_pixels"].get<uint64_t>(), 0u);  // the painter's cycle, on its own camera
  EXPECT_EQ(runs[1]["check"], "fails, as declared");
  EXPECT_EQ(runs[2]["wrong_pixels"], 0);
  EXPECT_EQ(runs[3]["variant"], "zbuffer raster=halfspace");
  EXPECT_TRUE(results["complete"].get<bool>());
  EXPECT_TRUE(fs::is_regular_file(file("study/index.html")));
  EXPECT_TRUE(fs::is_regular_file(file("study/chart.min.js")));
  EXPECT_TRUE(fs::is_regular_file(file("study/" + runs[1]["images"]["error"].get<std::string>())));
  EXPECT_NE(r.out.find("Report:"), std::string::npos);
}

TEST_F(CommandLine, CompareRefusesBadArgumentsBeforeRunning) {
  writeFile("plain.txt", "x");
  for (const char* args : {"compare --out s --algorithms nonsense", "compare --out s --algorithms painter:sort-key=up",
                           "compare --out s --algorithms zbuffer:raster", "compare builtin:cubes --sizes 0x3 --out s",
                           "compare builtin:nosuch --out s", "compare --out plain.txt --algorithms painter",
                           "compare --out s --exclude nonsense", "compare --algorithms painter"}) {
    Result bad = hsr(args);
    EXPECT_EQ(bad.status, 2) << args << "\n" << bad;
    EXPECT_TRUE(bad.oneErrorLine()) << args << "\n" << bad;
  }
  EXPECT_FALSE(fs::exists(file("s")));
}

// --- Outputs as a set, cameras, messages (issue 53) -------------------------------------------

// An output path that exists and is not a regular file (a FIFO, a device, a directory) is
// refused before any work, and left as it was; "-" is standard output for --stats only.
TEST_F(CommandLine, OutputsNeverReplaceSpecialFiles) {
  ASSERT_EQ(::mkfifo(file("fifo.json").c_str(), 0600), 0);
  fs::create_directory(file("dir.png"));
  for (const char* args : {"--stats fifo.json", "--stats /dev/null", "-o dir.png", "--ids /dev/null", "-o -"}) {
    Result r = hsr(std::string("render builtin:cubes --size 16x16 ") + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << args << "\n" << r;
  }
  EXPECT_TRUE(fs::is_fifo(file("fifo.json")));
  EXPECT_TRUE(fs::is_directory(file("dir.png")));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  Result r = hsr("render builtin:cubes --size 16x16 --stats -");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out)["width"], 16);
  EXPECT_EQ(listing(), (std::vector<std::string>{"dir.png", "fifo.json"}));
}

// All outputs of a render are written, or none: a failing one removes the others' files.
TEST_F(CommandLine, AFailedOutputLeavesNoOtherOutput) {
  Result r = hsr("render builtin:cubes --size 16x16 -o good.png --depth good.npy --stats s.json --ids no/dir/ids.png");
  EXPECT_EQ(r.status, 1) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("no/dir/ids.png"), std::string::npos) << r;
  EXPECT_TRUE(listing().empty());
  r = hsr("render builtin:cubes --size 16x16 -o good.png --depth good.npy --stats s.json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(listing(), (std::vector<std::string>{"good.npy", "good.png", "s.json"}));
}

// Two outputs naming one file, however spelt, and an empty output path are refused.
TEST_F(CommandLine, DuplicateAndEmptyOutputPathsAreRefused) {
  fs::create_directory(file("sub"));
  for (const char* args : {"-o same.png --depth-image same.png", "-o a.png --overdraw-image ./sub/../a.png",
                           "--ids i.npy --instance-ids i.npy", "-o \"\"", "--stats \"\"", "--depth ''"}) {
    Result r = hsr(std::string("render builtin:cubes --size 16x16 ") + args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << args << "\n" << r;
  }
  EXPECT_EQ(listing(), std::vector<std::string>{"sub"});
}

// A camera JSON may carry its image size (an OpenCV K fits only its own); --size overrides it;
// a principal point outside the image is warned about.
TEST_F(CommandLine, CameraJsonCarriesTheImageSize) {
  const std::string pose = R"("world_to_camera": [[1,0,0,0],[0,1,0,0],[0,0,1,12],[0,0,0,1]])";
  writeFile("cam.json", R"({"K": [[60,0,50],[0,60,40],[0,0,1]], "width": 64, "height": 48, )" + pose + "}");
  Result r = hsr("render builtin:cubes --camera cam.json --json");
  ASSERT_EQ(r.status, 0) << r;
  nlohmann::json stats = nlohmann::json::parse(r.out);
  EXPECT_EQ(stats["width"], 64);
  EXPECT_EQ(stats["height"], 48);
  EXPECT_TRUE(r.err.empty()) << r;
  r = hsr("render builtin:cubes --camera cam.json --size 32x24 --json");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(nlohmann::json::parse(r.out)["width"], 32);
  EXPECT_NE(r.err.find("warning: cam.json"), std::string::npos) << r;
  EXPECT_NE(r.err.find("principal point (50, 40) lies outside the 32x24 image"), std::string::npos) << r;
  writeFile("half.json", R"({"K": [[60,0,32],[0,60,24],[0,0,1]], "width": 64, )" + pose + "}");
  writeFile("bad.json", R"({"K": [[60,0,32],[0,60,24],[0,0,1]], "width": 64.5, "height": 48, )" + pose + "}");
  for (const char* camera : {"half.json", "bad.json"}) {
    r = hsr(std::string("render builtin:cubes --camera ") + camera);
    EXPECT_EQ(r.status, 2) << camera << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find(camera), std::string::npos) << r;
  }
}

// Messages say what is wrong: an eye too far away is not an 'up' problem; `hsr info` prints
// bounds with 6 significant digits whatever the format; the render summary and `hsr info` say
// what their degenerate counts count.
TEST_F(CommandLine, MessagesSayWhatIsWrong) {
  Result r = hsr("render builtin:cubes --eye 1e300,0,0");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("beyond 1e30"), std::string::npos) << r;
  EXPECT_EQ(r.err.find("'up'"), std::string::npos) << r;

  writeFile("t.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 1\nproperty list uchar int vertex_indices\nend_header\n0.1 0 0\n1 0.3 0\n0 1 0.7\n"
                     "3 0 1 2\n");
  r = hsr("info t.ply");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("bounds [0, 0, 0] .. [1, 1, 0.7]"), std::string::npos) << r;
  EXPECT_NE(r.out.find("degenerate (not drawn)"), std::string::npos) << r;
  r = hsr("render t.ply --size 16x16");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("zero area on the pixel grid 0"), std::string::npos) << r;
}

// --max-memory: a request beyond it is refused up front, in one line, with exit 2 and no output.
TEST_F(CommandLine, MaxMemoryRefusesAHugeImageUpFront) {
  Result r = hsr("render builtin:cubes --size 16384x16384 --max-memory 256M -o big.png");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("a 16384x16384 image with"), std::string::npos) << r;
  EXPECT_NE(r.err.find("memory limit of 256 MiB (--max-memory)"), std::string::npos) << r;
  EXPECT_FALSE(fs::exists(file("big.png")));
}

// The library's errors name the setting, not a flag; the command line words them with its flags.
TEST_F(CommandLine, LibraryErrorsAreWordedWithTheFlags) {
  // The one error line of a command that must fail with exit status 2.
  auto refusal = [&](const std::string& args) {
    Result r = hsr(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    return r.err;
  };
  auto startsWith = [](const std::string& text, const std::string& start) { return text.rfind(start, 0) == 0; };
  const std::string render = "render builtin:cubes --size 32x24 -o x.png ";
  std::string err = refusal(render + "--depth-format u17");
  EXPECT_EQ(err, "hsr: --depth-format: unknown storage 'u17' (u16, u24, u32, f32)\n");
  err = refusal(render + "--shadows --shadow-map-size 8");
  EXPECT_TRUE(startsWith(err, "hsr: --shadow-map-size 8: must be 16 to ")) << err;
  err = refusal(render + "--param raster=fast");
  EXPECT_TRUE(startsWith(err, "hsr: --param raster=fast: not a value of zbuffer's raster (one of ")) << err;
  // Also when a scene file names the built-in scene: the error keeps its key.
  writeFile("big.json", R"({"meshes": [{"builtin": "random?n=50000000"}]})");
  err = refusal("info big.json --max-memory 1G");
  EXPECT_TRUE(startsWith(err, "hsr: big.json: meshes[0].builtin: builtin:random?n=50000000 needs about ")) << err;
  EXPECT_NE(err.find(" MiB, more than the memory limit of 1024 MiB (--max-memory)"), std::string::npos) << err;
}

TEST_F(CommandLine, MaxMemoryRefusesAnAbsurdBuiltinScene) {
  Result r = hsr("info 'builtin:random?n=50000000' --max-memory 1G");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_TRUE(r.oneErrorLine()) << r;
  EXPECT_NE(r.err.find("builtin:random?n=50000000 needs about"), std::string::npos) << r;
}

TEST_F(CommandLine, MaxMemoryTakesUnitsAndRefusesNonsense) {
  EXPECT_EQ(hsr("info builtin:cubes --max-memory 2GiB").status, 0);
  EXPECT_EQ(hsr("info builtin:cubes --max-memory 1.5g").status, 0);
  for (const char* bad : {"banana", "12Q", "-5G", "100K", "''"}) {
    Result r = hsr(std::string("info builtin:cubes --max-memory ") + bad);
    EXPECT_EQ(r.status, 2) << bad << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
  }
}

// Tests of `hsr batch` (apps/batch_cmd.cpp) run as a script runs it, and of its checksum
// (apps/sha256.cpp): shards add up to the whole run byte for byte, a view equals `hsr render` of
// it, a run resumes after lost or damaged files, a torn index and a kill, and bad manifests and
// --shard values are refused with one line naming the file and line.
#include <gtest/gtest.h>

#include "cli_runner.hpp"
#include "sha256.hpp"
#include <nlohmann/json.hpp>

#include <fmt/core.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

using hsr::test::readText;
using Result = hsr::test::CliResult;

// The FIPS 180-2 examples, whole and fed in uneven pieces.
TEST(Sha256, NistExamples) {
  using hsr::cli::sha256Hex;
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // 56 bytes: the padding needs a block of its own.
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  const std::string million(1000000, 'a');
  EXPECT_EQ(sha256Hex(million), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  hsr::cli::Sha256 pieces;
  for (size_t done = 0, step = 1; done < million.size(); done += step, step = step * 7 % 997 + 1)
    pieces.update(million.data() + done, std::min(step, million.size() - done));
  EXPECT_EQ(pieces.hexDigest(), sha256Hex(million));
}

// A tetrahedron, one mesh file the manifest names by a relative path.
const char* kTetrahedron = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// Views over three scenes and four algorithms, each output and format, both camera styles, a
// camera's own size and a framed view.
const char* kManifest = R"({"id": "a0", "scene": "builtin:cubes", "camera": {"eye": [4, 3, 5], "target": [0, 0, 0]}, "size": "64x48", "outputs": ["depth", "face_id", "color"]}
{"id": "t0", "scene": "meshes/tet.obj", "camera": {"eye": [2, 1.5, 2.5], "target": [0.25, 0.25, 0.25]}, "size": "40x30", "outputs": ["depth.exr", "face_id.png", "instance_id", "barycentric", "depth_image"]}
{"id": "a1", "scene": "builtin:cubes", "camera": {"K": [[60, 0, 31.5], [0, 60, 23.5], [0, 0, 1]], "world_to_camera": [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 8], [0, 0, 0, 1]], "near": 1, "far": 20}, "size": "64x48", "outputs": ["depth.pfm", "face_id"], "algorithm": "bsp"}

{"id": "c0", "scene": "builtin:city", "size": "48x32", "outputs": ["depth.f32", "color", "instance_id.png"], "depth_format": "u16:z"}
{"id": "a2", "scene": "builtin:cubes", "camera": {"eye": [-4, 2, 5], "target": [0, 0, 0], "fovy_deg": 50}, "size": "64x48", "outputs": ["depth", "color"], "algorithm": "painter", "params": {"sort-key": "max"}}
{"id": "t1", "scene": "meshes/tet.obj", "camera": {"eye": [-1, 2, 2], "target": [0, 0, 0], "width": 32, "height": 24}, "outputs": ["depth", "face_id"], "params": {"raster": "halfspace"}}
{"id": "a3", "scene": "builtin:cubes", "camera": {"eye": [0, 6, 0.1], "target": [0, 0, 0], "ortho_height": 6}, "size": "64x48", "outputs": ["depth", "face_id", "color"]}
)";
const std::vector<std::string> kIds = {"a0", "t0", "a1", "c0", "a2", "t1", "a3"};

class Batch : public hsr::test::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    fs::create_directories(dir_ / "meshes");
    writeFile("meshes/tet.obj", kTetrahedron);
    writeFile("views.jsonl", kManifest);
  }
  // The view files of a folder (not the index), name -> bytes.
  std::map<std::string, std::string> viewFiles(const std::string& folder) const {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::directory_iterator(dir_ / folder))
      if (e.path().filename().string().rfind("index-", 0) != 0) files[e.path().filename().string()] = readText(e.path());
    return files;
  }
  // The whole index lines of a folder's index files, by view id.
  std::map<std::string, std::vector<nlohmann::json>> indexLines(const std::string& folder) const {
    std::map<std::string, std::vector<nlohmann::json>> lines;
    for (const auto& e : fs::directory_iterator(dir_ / folder)) {
      if (e.path().filename().string().rfind("index-", 0) != 0) continue;
      std::ifstream in(e.path());
      for (std::string line; std::getline(in, line);) {
        const auto j = nlohmann::json::parse(line, nullptr, false);
        if (j.is_object()) lines[j["id"].get<std::string>()].push_back(j);
      }
    }
    return lines;
  }
  // Runs shell text in the scratch directory: its exit status, and its standard output in `out`.
  int shell(const std::string& command, std::string* out = nullptr) const {
    FILE* pipe = ::popen(("cd '" + dir_.string() + "' && " + command).c_str(), "r");
    if (!pipe) return -1;
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;)
      if (out) out->append(buffer, n);
    const int raw = ::pclose(pipe);
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  }
  // Shell text that runs `command` with the built hsr first on PATH, as the nodes of a cluster have it.
  static std::string withHsrOnPath(const std::string& command) {
    return "PATH='" + fs::path(HSR_CLI_PATH).parent_path().string() + "':\"$PATH\" " + command;
  }
  void runWhole(const std::string& folder, const std::string& flags = "--threads 1") const {
    const Result r = hsr("batch views.jsonl --out " + folder + " " + flags);
    ASSERT_EQ(r.status, 0) << r;
  }
};

// The union of N shards is the unsharded run, byte for byte, whatever the thread count; each
// view is rendered by one shard and indexed once.
TEST_F(Batch, ShardsAddUpToTheWholeRun) {
  runWhole("whole");
  const auto whole = viewFiles("whole");
  EXPECT_EQ(whole.size(), 20u);
  for (const int n : {1, 2, 3}) {
    const std::string folder = "shards" + std::to_string(n);
    for (int i = 0; i < n; ++i) {
      const Result r = hsr(fmt::format("batch views.jsonl --out {} --shard {}/{} --threads {}", folder, i, n, 1 + i % 2));
      ASSERT_EQ(r.status, 0) << r;
      EXPECT_TRUE(fs::exists(file(folder + fmt::format("/index-{}-of-{}.jsonl", i, n))));
    }
    EXPECT_EQ(viewFiles(folder), whole) << n << " shards";
    const auto lines = indexLines(folder);
    EXPECT_EQ(lines.size(), kIds.size());
    for (const auto& [id, entries] : lines) EXPECT_EQ(entries.size(), 1u) << id;
  }
}

// Contiguous blocks: 7 views in 3 shards are views 0-1, 2-3 and 4-6; more shards than views
// leaves some empty.
TEST_F(Batch, ShardsAreContiguousBlocks) {
  ASSERT_EQ(hsr("batch views.jsonl --out s --shard 1/3 --threads 1").status, 0);
  const auto lines = indexLines("s");
  EXPECT_EQ(lines.size(), 2u);
  EXPECT_TRUE(lines.count("a1") && lines.count("c0"));
  const Result r = hsr("batch views.jsonl --out e --shard 0/9 --threads 1");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("0 views"), std::string::npos) << r;
  EXPECT_TRUE(viewFiles("e").empty());
}

// The index names each file with its size and SHA-256, the same as sha256sum's.
TEST_F(Batch, IndexRecordsChecksums) {
  runWhole("out");
  const auto lines = indexLines("out");
  const nlohmann::json& t0 = lines.at("t0").at(0);
  ASSERT_EQ(t0["files"].size(), 5u);
  for (const auto& f : t0["files"]) {
    const std::string name = f["file"];
    EXPECT_EQ(f["bytes"].get<uint64_t>(), fs::file_size(file("out/" + name)));
    EXPECT_EQ(f["sha256"].get<std::string>(), hsr::cli::sha256Hex(readText(file("out/" + name))));
  }
  std::string sha256sum;
  EXPECT_EQ(shell("sha256sum out/t0.barycentric.npy", &sha256sum), 0);
  EXPECT_EQ(sha256sum.substr(0, 64), t0["files"][3]["sha256"].get<std::string>());
  EXPECT_EQ(t0["files"][3]["file"], "t0.barycentric.npy");
}

// A view of the batch is the same bytes as `hsr render` of it.
TEST_F(Batch, ViewEqualsRender) {
  runWhole("out");
  writeFile("cam.json", R"({"eye": [4, 3, 5], "target": [0, 0, 0]})");
  Result r = hsr("render builtin:cubes --camera cam.json --size 64x48 --threads 1 -q --depth d.npy --ids i.npy -o c.png");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(readText(file("out/a0.depth.npy")), readText(file("d.npy")));
  EXPECT_EQ(readText(file("out/a0.face_id.npy")), readText(file("i.npy")));
  EXPECT_EQ(readText(file("out/a0.color.png")), readText(file("c.png")));
  writeFile("tcam.json", R"({"eye": [2, 1.5, 2.5], "target": [0.25, 0.25, 0.25]})");
  r = hsr("render meshes/tet.obj --camera tcam.json --size 40x30 -q --depth d.exr --ids i.png --instance-ids n.npy "
          "--barycentric b.npy --depth-image di.png");
  ASSERT_EQ(r.status, 0) << r;
  for (const auto& [mine, theirs] : std::map<std::string, std::string>{{"depth.exr", "d.exr"}, {"face_id.png", "i.png"},
                                                                      {"instance_id.npy", "n.npy"}, {"barycentric.npy", "b.npy"},
                                                                      {"depth_image.png", "di.png"}})
    EXPECT_EQ(readText(file("out/t0." + mine)), readText(file(theirs))) << mine;
  r = hsr("render builtin:city --size 48x32 --depth-format u16:z -q --depth d.f32 -o city.png");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_EQ(readText(file("out/c0.depth.f32")), readText(file("d.f32")));
  EXPECT_EQ(readText(file("out/c0.color.png")), readText(file("city.png")));
}

// A second run renders nothing and writes nothing; a missing or damaged file, or a changed view,
// is rendered again, to the same bytes, and indexed again.
TEST_F(Batch, ResumeSkipsCompleteViewsAndRepairsOthers) {
  runWhole("out");
  const auto first = viewFiles("out");
  const std::string indexBefore = readText(file("out/index-0-of-1.jsonl"));
  Result r = hsr("batch views.jsonl --out out --threads 1");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("7 views, 0 rendered, 7 complete already"), std::string::npos) << r;
  EXPECT_EQ(readText(file("out/index-0-of-1.jsonl")), indexBefore);

  fs::remove(file("out/a1.depth.pfm"));
  std::string damaged = first.at("c0.color.png");
  damaged[damaged.size() / 2] ^= 1;  // same size, other bytes
  writeFile("out/c0.color.png", damaged);
  writeFile("out/t1.depth.npy.tmp-999999-0", "left by a killed run");
  r = hsr("batch views.jsonl --out out --threads 1 --verbose");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("7 views, 2 rendered (2 again"), std::string::npos) << r;
  EXPECT_NE(r.out.find("a1: rendered"), std::string::npos) << r;
  EXPECT_NE(r.out.find("c0: rendered"), std::string::npos) << r;
  EXPECT_EQ(viewFiles("out"), first);  // repaired, and the temporary removed

  // A view whose line changed is rendered again.
  std::string manifest = kManifest;
  manifest.replace(manifest.find("\"fovy_deg\": 50"), 14, "\"fovy_deg\": 40");
  writeFile("views.jsonl", manifest);
  r = hsr("batch views.jsonl --out out --threads 1 --verbose");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("1 rendered (1 again"), std::string::npos) << r;
  EXPECT_NE(r.out.find("a2: rendered"), std::string::npos) << r;
}

// An index cut in the middle of its last line (a kill during the append): that line is not
// taken as complete, its view is rendered again, and the torn line stays a line of its own.
TEST_F(Batch, ResumeAfterTornIndexLine) {
  runWhole("out");
  const auto first = viewFiles("out");
  const std::string index = readText(file("out/index-0-of-1.jsonl"));
  const size_t lastLine = index.rfind('\n', index.size() - 2) + 1;
  writeFile("out/index-0-of-1.jsonl", index.substr(0, lastLine + (index.size() - lastLine) / 2));
  Result r = hsr("batch views.jsonl --out out --threads 1 --verbose");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find("1 rendered, 6 complete already"), std::string::npos) << r;
  EXPECT_NE(r.out.find("1 index lines ignored"), std::string::npos) << r;
  EXPECT_EQ(viewFiles("out"), first);
  r = hsr("batch views.jsonl --out out --threads 1");
  EXPECT_NE(r.out.find("0 rendered, 7 complete already"), std::string::npos) << r;
  const auto lines = indexLines("out");
  EXPECT_EQ(lines.size(), kIds.size());
  for (const auto& [id, entries] : lines) EXPECT_EQ(entries.size(), 1u) << id;
}

// A run killed with SIGKILL in the middle (after 3 views, then after 3 more) resumes to the
// same files as a run never killed, each view indexed once. Ray-cast views: slow enough (tens of
// ms each) that the kill lands well before the end.
TEST_F(Batch, ResumeAfterKill) {
  std::string manifest;
  for (int k = 0; k < 12; ++k)
    manifest += fmt::format(R"({{"id": "k{}", "scene": "builtin:city", "camera": {{"eye": [{}, 40, 70], "target": [0, 0, 0]}}, )"
                            R"("size": "320x240", "outputs": ["depth", "face_id", "color"], "algorithm": "raycast"}})" "\n",
                            k, 60 + 5 * k);
  writeFile("views.jsonl", manifest);
  runWhole("whole");
  size_t indexed = 0;
  for (const int views : {3, 6}) {
    const int status = shell(fmt::format(
        "(: >log.txt; '{}' batch views.jsonl --out out --threads 1 --verbose >log.txt & pid=$!; "
        "until [ \"$(grep -c rendered log.txt)\" -ge {} ] || ! kill -0 $pid; do sleep 0.01; done; "
        "kill -9 $pid; wait $pid)",
        HSR_CLI_PATH, views));
    EXPECT_EQ(status, 128 + 9);  // killed, not finished
    const size_t lines = indexLines("out").size();
    EXPECT_GE(lines, size_t(views));
    EXPECT_LT(lines, 12u);
    indexed = lines;
  }
  const Result r = hsr("batch views.jsonl --out out --threads 2");
  ASSERT_EQ(r.status, 0) << r;
  EXPECT_NE(r.out.find(fmt::format("12 views, {} rendered, {} complete already", 12 - indexed, indexed)),
            std::string::npos) << r;
  EXPECT_EQ(viewFiles("out"), viewFiles("whole"));  // and no temporary left
  const auto lines = indexLines("out");
  EXPECT_EQ(lines.size(), 12u);
  for (const auto& [id, entries] : lines) EXPECT_EQ(entries.size(), 1u) << id;
}

// A fenced block of docs/distributed.md: the first ```LANG block that holds `marker`, with the
// shared folder /data/ made the scratch directory.
std::string docBlock(const std::string& lang, const std::string& marker, const fs::path& data) {
  const std::string doc = readText(fs::path(HSR_SOURCE_DIR) / "docs/distributed.md");
  const std::string fence = "```" + lang + "\n";
  for (size_t start = doc.find(fence); start != std::string::npos; start = doc.find(fence, start + 1)) {
    const size_t body = start + fence.size();
    std::string block = doc.substr(body, doc.find("```", body) - body);
    if (block.find(marker) == std::string::npos) continue;
    for (size_t at; (at = block.find("/data/")) != std::string::npos;) block.replace(at, 6, data.string() + "/");
    return block;
  }
  return "";
}

// The Slurm script of the docs, run as each of its array tasks would run it.
TEST_F(Batch, DocsSlurmScript) {
  runWhole("whole");
  const std::string script = docBlock("bash", "#SBATCH", dir_);
  ASSERT_NE(script.find("#SBATCH --array=0-7 "), std::string::npos) << script;
  writeFile("render-views.sh", script);
  for (int task = 0; task < 8; ++task)
    EXPECT_EQ(shell(withHsrOnPath(fmt::format("SLURM_ARRAY_TASK_ID={} bash render-views.sh >/dev/null", task))), 0);
  EXPECT_EQ(viewFiles("out"), viewFiles("whole"));
  EXPECT_TRUE(fs::exists(file("out/index-7-of-8.jsonl")));
}

// The Kubernetes Job's container command, run as each completion index's pod would run it.
TEST_F(Batch, DocsKubernetesCommand) {
  runWhole("whole");
  const std::string job = docBlock("yaml", "completionMode: Indexed", dir_);
  ASSERT_NE(job.find("completions: 8 "), std::string::npos) << job;
  const size_t exec = job.find("exec hsr batch");
  ASSERT_NE(exec, std::string::npos) << job;
  writeFile("command.sh", job.substr(exec, job.find('\n', exec) - exec) + "\n");
  for (int index = 0; index < 8; ++index)
    EXPECT_EQ(shell(withHsrOnPath(fmt::format("JOB_COMPLETION_INDEX={} sh command.sh >/dev/null", index))), 0);
  EXPECT_EQ(viewFiles("out"), viewFiles("whole"));
}

// A bad line: exit 2, one line "MANIFEST:LINE: problem", nothing written (not even the folder).
TEST_F(Batch, BadManifestLinesAreRefused) {
  const std::string good = R"({"id": "ok", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"]})";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"])", "not valid JSON"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "colour": 1})", "unknown key 'colour'"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "0x16", "outputs": ["depth"]})", "size '0x16'"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": [16, 16], "outputs": ["depth"]})", "size '[16,16]'"},
      {R"({"id": "x", "scene": "builtin:cubes", "outputs": ["depth"]})", "'size' is missing"},
      {R"({"id": "x", "scene": "missing.obj", "size": "16x16", "outputs": ["depth"]})", "scene 'missing.obj': no such file"},
      {R"({"id": "x", "size": "16x16", "outputs": ["depth"]})", "'scene' is missing"},
      {R"({"id": "x", "scene": "builtin:nothing", "size": "16x16", "outputs": ["depth"]})", "no such built-in scene"},
      {R"({"id": "../x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"]})", "id '../x'"},
      {R"({"id": "ok", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"]})", "also the id of line 1"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["normals"]})", "unknown output 'normals'"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth.png"]})", "depth is written as npy, pfm, exr, f32"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth", "depth.exr"]})", "asked for twice"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": []})", "non-empty array"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "algorithm": "magic"})", "algorithm 'magic': unknown"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "params": {"raster": "x"}})", "params raster=x"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "depth_format": "u17"})", "depth_format"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "camera": {"eye": [1, 0, 0], "target": [0, 0, 0], "fov": 3}})", "camera: unknown key 'fov'"},
      {R"({"id": "x", "scene": "builtin:cubes", "size": "16x16", "outputs": ["depth"], "camera": {"eye": [1, 0, 0], "target": [1, 0, 0]}})", "camera: eye and target are the same point"},
      {R"(["x"])", "one JSON object per line"},
  };
  for (const auto& [line, problem] : cases) {
    writeFile("bad.jsonl", good + "\n\n" + line + "\n");
    const Result r = hsr("batch bad.jsonl --out out");
    EXPECT_EQ(r.status, 2) << line << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_EQ(r.err.rfind("hsr: bad.jsonl:3: ", 0), 0u) << r;
    EXPECT_NE(r.err.find(problem), std::string::npos) << problem << "\n" << r;
    EXPECT_FALSE(fs::exists(file("out"))) << line;
  }
  writeFile("empty.jsonl", "\n");
  const Result r = hsr("batch empty.jsonl --out out");
  EXPECT_EQ(r.status, 2) << r;
  EXPECT_NE(r.err.find("empty.jsonl: no views"), std::string::npos) << r;
  EXPECT_EQ(hsr("batch nowhere.jsonl --out out").status, 2);
}

TEST_F(Batch, BadShardIsRefused) {
  for (const char* shard : {"2/2", "a/2", "1", "-1/2", "0/0", "1/2x", "/2", "1/"}) {
    const Result r = hsr(std::string("batch views.jsonl --out out --shard='") + shard + "'");
    EXPECT_EQ(r.status, 2) << shard << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find("--shard '" + std::string(shard) + "': expected I/N"), std::string::npos) << r;
    EXPECT_FALSE(fs::exists(file("out"))) << shard;
  }
}

TEST_F(Batch, HelpNamesTheFlags) {
  const Result r = hsr("help batch");
  ASSERT_EQ(r.status, 0) << r;
  for (const char* flag : {"MANIFEST", "--out", "--shard", "--threads", "--verbose", "--quiet"})
    EXPECT_NE(r.out.find(flag), std::string::npos) << flag;
  EXPECT_NE(hsr("help").out.find("batch"), std::string::npos);
}

}  // namespace

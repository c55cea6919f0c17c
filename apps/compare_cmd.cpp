// `hsr compare`: the source documents' comparisons as one experiment (apps/compare/), with a
// table on stdout, DIR/results.json and the report DIR/index.html (docs/compare.md).
#include <hsr/hsr.hpp>
#include <hsr/threads.hpp>

#include <fmt/core.h>

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <sstream>

#include "commands.hpp"
#include "compare/study.hpp"

#ifndef HSR_GIT_COMMIT
#define HSR_GIT_COMMIT "unknown"
#endif

namespace hsr::cli {
namespace {

constexpr int kSchemaVersion = 1;
std::atomic<bool> gInterrupted{false};

struct CompareFlags {
  std::vector<std::string> scenes;
  std::string sizes = "640x480", algorithms, exclude, out;
  int frames = 3, threads = 0;
  bool quick = false, quiet = false;
};

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

std::vector<std::pair<int, int>> parseSizes(const std::string& text) {
  std::vector<std::pair<int, int>> sizes;
  for (const std::string& s : splitList(text)) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 1 || h < 1 || w > 16384 || h > 16384)
      throw InputError("--sizes: '" + s + "': expected WxH, 1 to 16384 each");
    sizes.push_back({w, h});
  }
  if (sizes.empty()) throw InputError("--sizes: no size given");
  return sizes;
}

std::vector<Variant> variantsOf(const CompareFlags& f) {
  std::vector<Variant> variants;
  if (f.algorithms.empty())
    variants = defaultVariants();
  else
    for (const std::string& v : splitList(f.algorithms)) variants.push_back(parseVariant(v));
  for (const std::string& name : splitList(f.exclude)) {
    if (!findAlgorithm(name)) throw InputError("--exclude: unknown algorithm '" + name + "'");
    std::erase_if(variants, [&](const Variant& v) { return v.algorithm == name; });
  }
  if (variants.empty()) throw InputError("--algorithms/--exclude: no algorithm left to run");
  return variants;
}

// The output directory: created if absent; an existing path must be a directory.
void prepareOut(const std::string& dir) {
  if (dir.empty()) throw InputError("--out: empty path");
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw InputError("--out " + dir + ": exists and is not a directory");
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("--out " + dir + ": cannot create the directory (" + ec.message() + ")");
}

Json machine(int threads) {
  return {{"cpu", cpuModel()},
          {"kernel_isa", kernelInstructionSet()},
          {"threads", resolveThreads(threads)},
          {"build_type", HSR_BUILD_TYPE},
          {"compiler",
#ifdef __clang__
           "clang " __clang_version__
#else
           "gcc " __VERSION__
#endif
          },
          {"version", HSR_VERSION},
          {"commit", HSR_GIT_COMMIT}};
}

// results.json and index.html, each replaced whole (atomic writes): a reader never sees half.
void writeOutputs(const std::string& dir, Json results) {
  results["claims"] = evaluateClaims(results);
  writeTextFile(results.dump(1) + "\n", dir + "/results.json");
  writeReport(dir, results);
}

class Progress {
 public:
  explicit Progress(bool shown) : shown_(shown) {}
  void operator()(size_t run, size_t runs, const StudyCase& c, const std::string& what) {
    if (!shown_) return;
    constexpr int kWidth = 30;
    const int filled = runs ? int(kWidth * run / runs) : kWidth;
    fmt::print(stderr, "\r\033[K[{}{}] {}/{} {} {}x{} {}", std::string(size_t(filled), '#'),
               std::string(size_t(kWidth - filled), ' '), run, runs, c.scene, c.width, c.height, what);
    if (run == runs) fmt::print(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool shown_;
};

void printTable(const Json& results) {
  fmt::print("{:<36} {:>9} {:<26} {:>10} {:>12} {:>12} {:>8} {:>11} {:>8} {:>9}\n", "scene", "size", "algorithm",
             "median ms", "z tests", "colour wr.", "overdr.", "memory B", "wrong", "ambig.");
  for (const Json& c : results["cases"])
    for (const Json& r : c["runs"]) {
      const std::string size = fmt::format("{}x{}", c["width"].get<int>(), c["height"].get<int>());
      if (r.contains("error")) {
        fmt::print("{:<36} {:>9} {:<26} error: {}\n", c["scene"].get<std::string>(), size, r["variant"].get<std::string>(),
                   r["error"].get<std::string>());
        continue;
      }
      fmt::print("{:<36} {:>9} {:<26} {:>10.3f} {:>12} {:>12} {:>8.3f} {:>11} {:>8} {:>9}\n", c["scene"].get<std::string>(),
                 size, r["variant"].get<std::string>(), r["median_ms"].get<double>(), r["depth_tests"].get<uint64_t>(),
                 r["color_writes"].get<uint64_t>(), r["overdraw"].get<double>(), r["memory_bytes"].get<uint64_t>(),
                 r["wrong_pixels"].get<uint64_t>(), r["ambiguous_pixels"].get<uint64_t>());
    }
  fmt::print("\nClaims:\n");
  for (const Json& c : results["claims"])
    fmt::print("  [{}] {} ({}): {}\n", c["verdict"].get<std::string>(), c["claim"].get<std::string>(),
               c["source"].get<std::string>(), c["measured"].get<std::string>());
}

int runCompare(const CompareFlags& f) {
  const std::vector<Variant> variants = variantsOf(f);
  const std::vector<StudyCase> cases = f.scenes.empty() ? defaultStudy(f.quick) : casesOf(f.scenes, parseSizes(f.sizes));
  for (const StudyCase& c : cases) (void)loadScene(c.scene);  // every scene readable before the study starts
  prepareOut(f.out);

  StudySettings settings;
  settings.frames = f.quick ? 1 : f.frames;
  settings.threads = f.threads;
  settings.outDir = f.out;
  settings.interrupted = &gInterrupted;
  settings.progress = Progress(!f.quiet && isatty(STDERR_FILENO));
  auto previous = std::signal(SIGINT, [](int) { gInterrupted = true; });

  Json head = {{"schema", "hsr-compare-results"}, {"schema_version", kSchemaVersion}, {"machine", machine(f.threads)},
               {"frames", settings.frames}, {"quick", f.quick}, {"complete", false}};
  head["memory"] = memoryTable();
  head["precision"] = precisionCurves(1.0, 1000.0);
  auto withHead = [&](const Json& partial) {
    Json all = head;
    all["cases"] = partial["cases"];
    return all;
  };
  Json results = withHead(runStudy(cases, variants, settings, [&](const Json& partial) { writeOutputs(f.out, withHead(partial)); }));
  if (f.scenes.empty() && !gInterrupted) results["zfight"] = zfightExperiment(settings, f.quick);
  if (f.scenes.empty() && !gInterrupted) results["coherence"] = coherenceExperiment(settings, f.quick);
  if (f.scenes.empty() && !gInterrupted) results["depth_compression"] = depthCompressionExperiment(settings, f.quick);
  if (f.scenes.empty() && !gInterrupted) results["shadows"] = shadowExperiment(settings, f.quick);
  results["complete"] = !gInterrupted.load();
  writeOutputs(f.out, results);
  std::signal(SIGINT, previous);

  results["claims"] = evaluateClaims(results);
  printTable(results);
  fmt::print("\n{} {}/index.html (results: {}/results.json)\n", gInterrupted ? "Interrupted; partial report:" : "Report:",
             f.out, f.out);
  return gInterrupted ? 130 : 0;
}

}  // namespace

Runner setupCompare(CLI::App& cmd) {
  auto f = std::make_shared<CompareFlags>();
  cmd.add_option("scenes", f->scenes, "Scenes to compare on (default: the documents' study on built-in scenes)")
      ->type_name("SCENE...");
  cmd.add_option("--sizes", f->sizes, "Image sizes for the scenes given")->type_name("WxH,...")->capture_default_str();
  cmd.add_option("--algorithms", f->algorithms,
                 "Algorithm variants, comma-separated, each NAME[:KEY=VALUE...] (default: every registered algorithm, "
                 "zbuffer:raster=binned and zbuffer:raster=halfspace (the textbook z-buffer), and NAME:raster=tiled for "
                 "the painter's family)")
      ->type_name("LIST");
  cmd.add_option("--exclude", f->exclude, "Algorithms to leave out")->type_name("LIST");
  cmd.add_option("--frames", f->frames, "Timed frames per run (median; one when a frame takes over 2 s)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd.add_option("--threads", f->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 4096))->capture_default_str();
  cmd.add_flag("--quick", f->quick, "The study at a sixth of its sizes, one frame per run (for the test suite)");
  cmd.add_flag("--quiet", f->quiet, "No progress bar");
  cmd.add_option("--out", f->out, "Directory for results.json, index.html and the pictures")->type_name("DIR")->required();
  cmd.footer(
      "Every run is checked against the exact reference (raycast). Ctrl-C stops after the current run and leaves a\n"
      "consistent partial report (exit 130). docs/compare.md explains the study and the report.\n\n"
      "Examples:\n"
      "  hsr compare --out study\n"
      "  hsr compare builtin:city model.obj --sizes 640x480,1920x1080 --algorithms zbuffer,bsp,painter:sort-key=max --out mine");
  return [f] { return runCompare(*f); };
}

}  // namespace hsr::cli

// `hsr bench`: times repeated renders of one scene (or the occlusion buffer's pass, or the shadow
// pass of one view), after a warm-up, and prints the median and minimum with each stage's median, as text or one JSON
// record that names the scene, size, threads and build. Set up by apps/main.cpp's table.
#include <hsr/hsr.hpp>
#include <hsr/threads.hpp>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "flags.hpp"

namespace hsr::cli {
namespace {

using Json = nlohmann::ordered_json;

struct BenchFlags {
  ViewFlags view;
  int frames = 10, warmup = 2;
  double warmupSeconds = 1;  // and at least this long (see setupBench)
  bool json = false, occlusion = false, orbit = false;
  ShadowFlags shadow;  // --shadows: time the shadow pass (hsr::shadowMap) of the view instead
};

// --shadows: what the shadow pass of the one view frame is given.
struct ShadowPass {
  hsr::Light light;
  hsr::ShadowOptions options;
};

// What a benchmark measured: whole frames, each frame's stages (Stats::time_ms), and the first
// frame of the process apart (it builds what later frames reuse, such as a BSP tree).
struct BenchRecord {
  std::vector<double> frameMs;
  std::vector<std::pair<std::string, std::vector<double>>> stageMs;  // in pipeline order
  double firstMs = 0;
  std::vector<std::pair<std::string, double>> firstStages;
  int warmupFrames = 0;
  double warmupMs = 0;
  int poses = 1;
  std::string subject;  // what was timed: the algorithm, or the shadow pass and its maps

  void addStages(const hsr::Stats& stats) {
    for (const auto& [stage, ms] : stats.time_ms) {
      auto it = std::find_if(stageMs.begin(), stageMs.end(), [&](const auto& s) { return s.first == stage; });
      if (it == stageMs.end()) it = stageMs.insert(stageMs.end(), {stage, {}});
      it->second.push_back(ms);
    }
  }
};

BenchRecord timeFrames(const BenchFlags& f, const Job& job, hsr::Frame& frame, const std::optional<ShadowPass>& shadows) {
  hsr::OcclusionBuffer occlusion;
  BenchRecord rec;
  // --orbit: every frame from another side of the scene, poses evenly around it.
  const std::vector<hsr::Camera> cameras =
      f.orbit ? hsr::orbitCameras(job.camera, job.scene.bounds().center(), f.frames) : std::vector{job.camera};
  rec.poses = int(cameras.size());
  std::optional<hsr::Renderer> renderer;  // one algorithm object for every frame: what it builds, built once
  if (!f.occlusion) renderer.emplace(job.scene, job.options);
  if (shadows) renderer->render(job.camera, frame);  // the view, once, untimed: the shadow pass is timed
  hsr::Stats stages;  // the last timed frame's stages
  int rendered = 0;
  // One frame, timed; the first of the process is recorded apart.
  auto renderOnce = [&](size_t pose) {
    const auto start = std::chrono::steady_clock::now();
    const hsr::Camera& camera = cameras[pose % cameras.size()];
    if (f.occlusion)  // depth kept in tiles, no image: what an occlusion culler pays per frame
      occlusion.render(job.scene, camera,
                       {job.options.depthFormat, job.options.cull, job.options.threads, job.options.tiled});
    else if (shadows) {  // the map(s) and the lookup of every visible pixel
      stages = {};
      hsr::addShadowTimes(stages, hsr::shadowMap(job.scene, camera, frame, shadows->light, shadows->options),
                          shadows->options);
    }
    else
      renderer->render(camera, frame);  // reuses the frame's buffers
    const double ms = millisecondsSince(start);
    if (!shadows) stages.time_ms = frame.stats.time_ms;
    if (rendered++ == 0) {
      rec.firstMs = ms;
      if (!f.occlusion) rec.firstStages = stages.time_ms;
    }
    return ms;
  };
  // Warm-up: f.warmup frames, and more until f.warmupSeconds have passed.
  const auto warmupStart = std::chrono::steady_clock::now();
  while (rec.warmupFrames < f.warmup || (f.warmupSeconds > 0 && millisecondsSince(warmupStart) < 1e3 * f.warmupSeconds))
    renderOnce(size_t(rec.warmupFrames++));
  rec.warmupMs = millisecondsSince(warmupStart);
  for (int i = 0; i < f.frames; ++i) {
    rec.frameMs.push_back(renderOnce(size_t(i)));
    if (!f.occlusion) rec.addStages(stages);
  }
  if (f.occlusion) occlusion.depthImage(frame);  // its statistics, with covered_pixels (not timed)
  return rec;
}

// The stages every timed frame ran (a stage of only some frames, such as a build, is the first frame's).
bool everyFrame(const BenchRecord& rec, const std::vector<double>& stageMs) { return stageMs.size() == rec.frameMs.size(); }

std::string stageText(const BenchRecord& rec) {
  std::string text;
  for (const auto& [stage, ms] : rec.stageMs)
    if (everyFrame(rec, ms)) text += fmt::format("{}{} {:.3f}", text.empty() ? "" : ", ", stage, median(ms));
  return text;
}

void printBenchText(const BenchRecord& rec, const Job& job, const hsr::Frame& frame, int threads) {
  const double min = *std::min_element(rec.frameMs.begin(), rec.frameMs.end());
  fmt::print("{} on {}: {}x{}, {} threads{}: median {:.3f} ms, min {:.3f} ms over {} frames ({} warm-up in {:.2f} s)\n",
             rec.subject, job.sceneName, frame.width, frame.height, threads,
             rec.poses > 1 ? fmt::format(", an orbit of {} poses", rec.poses) : "", median(rec.frameMs), min,
             rec.frameMs.size(), rec.warmupFrames, rec.warmupMs / 1e3);
  if (rec.stageMs.empty()) return;
  fmt::print("  per frame, median ms: {}\n", stageText(rec));
  std::string first;
  for (const auto& [stage, ms] : rec.firstStages)
    if (stage == "build") first = fmt::format(" (build {:.3f} ms, once: later frames reuse it)", ms);
  fmt::print("  first frame: {:.3f} ms{}\n", rec.firstMs, first);
}

Json benchJson(const BenchRecord& rec, const Job& job, const hsr::Frame& frame, int threads) {
  // Every figure travels with what produced it: scene, size, threads, build.
  Json out;
  out["scene"] = job.sceneName;
  out["size"] = fmt::format("{}x{}", frame.width, frame.height);
  out["threads"] = threads;
  out["outputs"] = hsr::frameOutputsName(job.options.outputs);
  out["kernel_isa"] = hsr::kernelInstructionSet();
  out["cpu"] = cpuModel();
  out["frames"] = rec.frameMs.size();
  out["poses"] = rec.poses;
  out["warmup"] = rec.warmupFrames;
  out["warmup_ms"] = rec.warmupMs;
  out["median_ms"] = median(rec.frameMs);
  out["min_ms"] = *std::min_element(rec.frameMs.begin(), rec.frameMs.end());
  out["frame_ms"] = rec.frameMs;
  out["first_frame_ms"] = rec.firstMs;
  out["timed"] = rec.subject;
  Json firstStages = Json::object(), stages = Json::object();
  for (const auto& [stage, ms] : rec.firstStages) firstStages[stage] = ms;
  for (const auto& [stage, ms] : rec.stageMs)
    if (everyFrame(rec, ms)) stages[stage] = median(ms);
  out["first_frame_stages_ms"] = firstStages;
  out["stage_median_ms"] = stages;
  out["build"] = {{"version", HSR_VERSION},
                  {"build_type", HSR_BUILD_TYPE},
                  {"flags", HSR_BUILD_FLAGS},
#ifdef __clang__
                  {"compiler", "clang " __clang_version__},
#else
                  {"compiler", "gcc " __VERSION__},
#endif
#ifdef NDEBUG
                  {"assertions", false}
#else
                  {"assertions", true}
#endif
  };
  const Json stats = Json::parse(frame.stats.toJson());
  for (const auto& [key, value] : stats.items())
    if (!out.contains(key)) out[key] = value;
  return out;
}

int runBench(const BenchFlags& f) {
  if (f.shadow.shadows) {  // before the scene loads
    if (f.occlusion || f.orbit)
      throw hsr::InputError("--shadows times the shadow pass of one view: drop --occlusion and --orbit");
    if (!has(f.view.frameOutputs(), hsr::FrameOutputs::TriangleIds))
      throw hsr::InputError("--shadows finds each pixel's point on its triangle: --outputs " + f.view.outputs +
                            " has no triangle ids (add triangle)");
    f.shadow.flagLight();
    f.shadow.checkedShadowOptions(hsr::RenderOptions{});
  }
  Job job = f.view.prepare();
  if (f.occlusion && (job.options.algorithm != "zbuffer" || !job.options.params.empty()))
    throw hsr::InputError("--occlusion: times the occlusion buffer (the tiled z-buffer, depth only); drop "
                          "--algorithm and --param");
  std::optional<ShadowPass> shadows;
  if (f.shadow.shadows) shadows = ShadowPass{f.shadow.shadowLight(job), f.shadow.checkedShadowOptions(job.options)};
  hsr::Frame frame;
  BenchRecord rec = timeFrames(f, job, frame, shadows);
  rec.subject = frame.stats.algorithm;
  if (shadows)
    rec.subject = fmt::format("shadow pass ({}, {} map(s) of {}x{}, {})", hsr::shadowMethodName(shadows->options.method),
                              shadows->options.method == hsr::ShadowMethod::Single ? 1 : shadows->options.cascades,
                              shadows->options.mapSize, shadows->options.mapSize, hsr::describeLight(shadows->light));
  const int threads = hsr::resolveThreads(job.options.threads);
  if (f.json)
    fmt::print("{}\n", benchJson(rec, job, frame, threads).dump(2));
  else
    printBenchText(rec, job, frame, threads);
  return 0;
}

}  // namespace

Runner setupBench(CLI::App& cmd) {
  auto f = std::make_shared<BenchFlags>();
  f->view.declare(cmd);
  cmd.add_option("--frames", f->frames, "Timed frames")->type_name("N")->check(CLI::Range(1, 1000000))->capture_default_str();
  cmd.add_option("--warmup", f->warmup, "Untimed frames first")->type_name("K")->check(CLI::Range(0, 1000000))->capture_default_str();
  cmd.add_option("--warmup-time", f->warmupSeconds,
                 "Untimed frames for at least this many seconds too (0: --warmup frames only). On the 2-core VMs "
                 "this project is measured on, a new process runs 1.5-3x slower for its first ~0.5 s (docs/benchmarks.md)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd.add_flag("--occlusion", f->occlusion,
               "Time the occlusion buffer (hsr::OcclusionBuffer::render): the tiled z-buffer's depth only, kept in "
               "tiles, no image written (what an occlusion culler pays per frame)");
  cmd.add_flag("--orbit", f->orbit,
               "Render each timed frame from another pose: --frames poses evenly around the scene (the camera "
               "turned about its up axis through the scene's centre), so what an algorithm builds once per scene "
               "(a BSP tree) is timed apart from what it does per view");
  f->shadow.declareShadows(cmd,
                           "Time the shadow pass instead (docs/shadows.md): the view rendered once, then per timed "
                           "frame the shadow map(s) rendered from the light and every visible pixel tested");
  cmd.add_flag("--json", f->json,
               "Print one JSON object: timed, median_ms, min_ms, frames, frame_ms, stage_median_ms, first_frame_ms, "
               "first_frame_stages_ms, poses, threads, scene, size, build and the last frame's statistics");
  cmd.footer(
      "Times are wall-clock milliseconds of whole render() calls (with --occlusion, of OcclusionBuffer::render "
      "calls; with --shadows, of shadowMap() calls).\n\n"
      "Examples:\n"
      "  hsr bench builtin:cubes --frames 20\n"
      "  hsr bench builtin:sphere --size 1920x1080 --outputs depth,face,color\n"
      "  hsr bench builtin:city --size 1920x1080 --algorithm bsp --orbit --frames 20\n"
      "  hsr bench builtin:city --size 1920x1080 --shadows --light-dir 0.6,-1,0.4 --frames 5\n"
      "  hsr bench model.obj --camera cam.json --size 1920x1080 --algorithm zbuffer --threads 1 --json");
  return [f] { return runBench(*f); };
}

}  // namespace hsr::cli

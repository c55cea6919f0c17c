// hsr_ab_switch: whole frames of one scene with one of the tiled z-buffer's switches off (A) and
// on (B) (hsr::TiledSwitches: defer-back-faces, defer-clusters, mesh-culling, background-pump),
// interleaved frame by frame in one process, so that both see the same machine: on a shared VM
// whose speed drifts by 20-30% within minutes, runs of separate processes one after the other
// compare the drift as much as the code.
//   hsr_ab_switch SCENE [--size WxH] [--threads N] [--frames N] [--depth-only] [--cull-back] [--occlusion]
//                 [--switch NAME] [--pause-ms MS]
// Prints the median and minimum frame time of each and the median of the per-pair ratios B/A
// (each pair: one frame of each, in alternating order).
#include <hsr/hsr.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

int main(int argc, char** argv) {
  CLI::App app{"Interleaved A/B of one of the tiled z-buffer's switches, off and on, frame by frame"};
  std::string spec, size = "1920x1080", switchName = "defer-back-faces";
  int threads = 2, frames = 20;
  double pauseMs = 0;
  bool depthOnly = false, cullBack = false, occlusion = false;
  app.add_option("scene", spec, "Scene (file or builtin:NAME)")->required();
  app.add_option("--size", size, "Image size WxH");
  app.add_option("--threads", threads, "Worker threads");
  app.add_option("--frames", frames, "Timed pairs of frames (after 2 warm-up pairs)")->check(CLI::Range(1, 100000));
  std::string outputs;
  app.add_flag("--depth-only", depthOnly, "Depth only (FrameOutputs::DepthOnly)");
  app.add_option("--outputs", outputs, "Buffers resolved, as hsr bench --outputs (default all)");
  app.add_flag("--cull-back", cullBack, "Cull back faces (Cull::Back)");
  app.add_flag("--occlusion", occlusion,
               "Time hsr::OcclusionBuffer::render (depth kept in tiles, no image), as hsr bench --occlusion");
  app.add_option("--switch", switchName, "The switch: A = off, B = on")
      ->check(CLI::IsMember(std::vector<std::string>(std::begin(hsr::kTiledSwitchNames), std::end(hsr::kTiledSwitchNames))));
  app.add_option("--pause-ms", pauseMs,
                 "Sleep this long before each frame (the pool's threads fall asleep, as between the peer's frames)")
      ->check(CLI::Range(0.0, 1000.0));
  CLI11_PARSE(app, argc, argv);
  int w = 0, h = 0;
  if (std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2 || w <= 0 || h <= 0) {
    std::fprintf(stderr, "hsr_ab_switch: --size needs WxH\n");
    return 2;
  }
  const std::string value[2] = {"off", "on"};
  try {
    const hsr::Scene scene = hsr::loadScene(spec);
    const hsr::Camera cam = hsr::resolveCamera(scene.camera ? *scene.camera : hsr::frameBounds(scene.bounds()), w, h,
                                               scene.bounds());
    hsr::RenderOptions o;
    o.threads = threads;
    o.shading = hsr::Shading::Flat;
    if (!outputs.empty()) o.outputs = hsr::parseFrameOutputs(outputs);
    if (depthOnly) o.outputs = hsr::FrameOutputs::DepthOnly;
    if (cullBack) o.cull = hsr::Cull::Back;
    hsr::RenderOptions off = o;
    hsr::switchOff(off.tiled, switchName);
    const hsr::RenderOptions options[2] = {off, o};
    hsr::Frame frame[2];
    hsr::Renderer renderer[2] = {hsr::Renderer(scene, options[0]), hsr::Renderer(scene, options[1])};
    hsr::OcclusionBuffer buffer[2];
    const hsr::OcclusionOptions occlusionOptions[2] = {{off.depthFormat, off.cull, off.threads, off.tiled},
                                                       {o.depthFormat, o.cull, o.threads, o.tiled}};
    std::vector<double> ms[2], ratio;
    for (int i = 0; i < frames + 2; ++i) {
      double t[2];
      for (int k = 0; k < 2; ++k) {
        const int which = i % 2 ? 1 - k : k;  // alternate which value goes first
        if (pauseMs > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pauseMs));
        const auto t0 = std::chrono::steady_clock::now();
        if (occlusion) buffer[which].render(scene, cam, occlusionOptions[which]);
        else renderer[which].render(cam, frame[which]);
        t[which] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      }
      if (i < 2) continue;
      ms[0].push_back(t[0]), ms[1].push_back(t[1]), ratio.push_back(t[1] / t[0]);
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    for (int k = 0; k < 2; ++k)
      std::printf("%s=%s: median %.2f ms, min %.2f ms\n", switchName.c_str(), value[k].c_str(), median(ms[k]),
                  *std::min_element(ms[k].begin(), ms[k].end()));
    std::printf("%s %s threads %d, %d pairs: B/A median of pair ratios %.3f, of medians %.3f\n", spec.c_str(),
                size.c_str(), threads, frames, median(ratio), median(ms[1]) / median(ms[0]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hsr_ab_switch: %s\n", e.what());
    return 2;
  }
}

// hsr_ab_env: whole frames of one scene under two values of an environment variable that hsr
// reads per frame (HSR_DEFER_BACK_FACES, HSR_DEFER_CLUSTERS), interleaved frame by frame in one process, so that
// both see the same machine: on a shared VM whose speed drifts by 20-30% within minutes, runs
// of separate processes one after the other compare the drift as much as the code.
//   hsr_ab_env SCENE [--size WxH] [--threads N] [--frames N] [--depth-only] [--cull-back] [--occlusion]
//              [--var NAME] [--values A,B] [--pause-ms MS]
// Prints the median and minimum frame time of each value and the median of the per-pair ratios
// B/A (each pair: one frame of each, in alternating order).
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
  CLI::App app{"Interleaved A/B of an hsr environment variable, frame by frame"};
  std::string spec, size = "1920x1080", var = "HSR_DEFER_BACK_FACES", values = "off,on";
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
  app.add_option("--var", var, "Environment variable");
  app.add_option("--values", values, "Its two values, A,B");
  app.add_option("--pause-ms", pauseMs,
                 "Sleep this long before each frame (the pool's threads fall asleep, as between the peer's frames)")
      ->check(CLI::Range(0.0, 1000.0));
  CLI11_PARSE(app, argc, argv);
  const size_t comma = values.find(',');
  int w = 0, h = 0;
  if (comma == std::string::npos || std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2 || w <= 0 || h <= 0) {
    std::fprintf(stderr, "hsr_ab_env: --values needs A,B and --size WxH\n");
    return 2;
  }
  const std::string value[2] = {values.substr(0, comma), values.substr(comma + 1)};
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
    hsr::Frame frame[2];
    hsr::Renderer renderer[2] = {hsr::Renderer(scene, o), hsr::Renderer(scene, o)};
    hsr::OcclusionBuffer buffer[2];
    const hsr::OcclusionOptions occlusionOptions{o.depthFormat, o.cull, o.threads};
    std::vector<double> ms[2], ratio;
    for (int i = 0; i < frames + 2; ++i) {
      double t[2];
      for (int k = 0; k < 2; ++k) {
        const int which = i % 2 ? 1 - k : k;  // alternate which value goes first
        setenv(var.c_str(), value[which].c_str(), 1);
        if (pauseMs > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pauseMs));
        const auto t0 = std::chrono::steady_clock::now();
        if (occlusion) buffer[which].render(scene, cam, occlusionOptions);
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
      std::printf("%s=%s: median %.2f ms, min %.2f ms\n", var.c_str(), value[k].c_str(), median(ms[k]),
                  *std::min_element(ms[k].begin(), ms[k].end()));
    std::printf("%s %s threads %d, %d pairs: B/A median of pair ratios %.3f, of medians %.3f\n", spec.c_str(),
                size.c_str(), threads, frames, median(ratio), median(ms[1]) / median(ms[0]));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hsr_ab_env: %s\n", e.what());
    return 2;
  }
}

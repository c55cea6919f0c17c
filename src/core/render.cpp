// render(): the algorithm registry and the common frame set-up (buffers, scene counts, total
// time, --verify against the ray-cast reference). Called by the CLI, the benchmarks and tests.
#include <hsr/render.hpp>

#include "algorithms/algorithms.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "frontend/frontend.hpp"
#include "raster/tiled.hpp"

namespace hsr {

const std::vector<AlgorithmInfo>& algorithms() {
  static const std::vector<AlgorithmInfo> list = {
      {"zbuffer", "z-buffer: per-pixel depth test in submission order (000, 001, 003, 004)", algo::zbuffer},
      {"raycast", "ray casting: one ray per pixel centre, nearest hit in double (001); the exact reference",
       algo::raycast},
  };
  return list;
}

const AlgorithmInfo* findAlgorithm(const std::string& name) {
  for (const AlgorithmInfo& a : algorithms())
    if (a.name == name) return &a;
  return nullptr;
}

Stats algo::frameStats(const Scene& scene, const Camera& camera) {
  Stats st;
  st.width = camera.width;
  st.height = camera.height;
  st.faces = scene.faceCount();
  st.triangles = scene.triangles.size();
  return st;
}

void algo::checkImage(const Camera& camera, DepthFormat format) {
  if (camera.width <= 0 || camera.height <= 0 || camera.width > kMaxImageSize || camera.height > kMaxImageSize)
    throw InputError("--size: width and height must be in 1.." + std::to_string(kMaxImageSize));
  if (format.mapping == DepthMapping::Inv && !(camera.near > 0))
    throw InputError("--depth-format: the inv mapping needs near > 0");
}

const char* kernelInstructionSet() { return tiled::kernelTarget(); }

Frame render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  Frame frame;
  render(scene, camera, options, frame);
  return frame;
}

void render(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame) {
  const AlgorithmInfo* algorithm = findAlgorithm(options.algorithm);
  if (!algorithm) {
    std::string names;
    for (const AlgorithmInfo& a : algorithms()) names += (names.empty() ? "" : ", ") + a.name;
    throw InputError("--algorithm: unknown algorithm '" + options.algorithm + "' (" + names + ")");
  }
  algo::checkImage(camera, options.depthFormat);

  if (options.verify && !has(options.outputs, FrameOutputs::IdsAndDepth))
    throw InputError("--verify: compares face and triangle ids, which the outputs asked for (" +
                     frameOutputsName(options.outputs) + ") do not keep");

  Timer total;
  frame.stats = algo::frameStats(scene, camera);
  // Sized, not cleared: every algorithm writes every pixel (a pass over 33 MB less at 1080p).
  frame.allocate(camera.width, camera.height, options.outputs);
  algorithm->run(scene, camera, options, frame);
  frame.stats.addTime("total", total.ms());

  if (options.verify) {
    RenderOptions refOptions = options;
    refOptions.algorithm = "raycast";
    refOptions.verify = false;
    Frame reference = render(scene, camera, refOptions);
    Timer verifyTimer;
    VerifyResult v = verifyAgainstReference(scene, camera, options, frame, reference);
    frame.stats.wrong_pixels = v.wrong_pixels;
    frame.stats.ambiguous_pixels = v.ambiguous_pixels;
    frame.stats.addTime("verify_reference", reference.stats.time_ms.back().second);
    frame.stats.addTime("verify_compare", verifyTimer.ms());
  }
}

}  // namespace hsr

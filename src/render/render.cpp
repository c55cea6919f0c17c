// Renderer and render(): one algorithm object made for a scene (its parameters checked), and the
// frame set-up around each of its views (buffers sized, scene counts, total time, --verify
// against the ray-cast reference). Called by the CLI, the Python module, the benchmarks and
// tests; the algorithms themselves are in the registry (algorithms/registry.cpp).
#include <hsr/limits.hpp>
#include <hsr/render.hpp>

#include "algorithms/algorithms.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "raster/tiled.hpp"

namespace hsr {

namespace {

// What a render needs besides the scene: per pixel the frame's buffers and the algorithm's own
// depth buffer, per triangle the front end's set-up and bins (rounded up from the peak resident
// size of the z-buffer on a million random triangles, about 260 bytes each); twice with
// --verify (the reference is a second frame).
constexpr double kWorkBytesPerTriangle = 320;

void checkRenderMemory(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  double perPixel = 4.0 + 4.0;  // depth, and the algorithm's own depth buffer
  if (has(options.outputs, FrameOutputs::FaceIds)) perPixel += 4;
  if (has(options.outputs, FrameOutputs::TriangleIds)) perPixel += 4;
  if (has(options.outputs, FrameOutputs::Color)) perPixel += 4;
  if (options.countWrites) perPixel += sizeof(WriteCount);
  double bytes = double(camera.width) * double(camera.height) * perPixel +
                 double(scene.triangles.size()) * kWorkBytesPerTriangle;
  if (options.verify) bytes *= 2;
  checkMemory(bytes, "a " + std::to_string(camera.width) + "x" + std::to_string(camera.height) + " image with " +
                         std::to_string(scene.triangles.size()) + " triangles");
}

}  // namespace

const char* kernelInstructionSet() { return tiled::kernelTarget(); }

namespace {

const AlgorithmInfo& algorithmNamed(const std::string& name) {
  const AlgorithmInfo* algorithm = findAlgorithm(name);
  if (!algorithm) {
    std::string names;
    for (const AlgorithmInfo& a : algorithms()) names += (names.empty() ? "" : ", ") + a.name;
    throw InputError(Setting::Algorithm, "", "unknown algorithm '" + name + "' (" + names + ")");
  }
  return *algorithm;
}

// Checks, per frame, what the options ask of the image and the machine.
void checkFrameOptions(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  algo::checkImage(camera, options.depthFormat);
  checkRenderMemory(scene, camera, options);
  if (options.verify && !has(options.outputs, FrameOutputs::IdsAndDepth))
    throw InputError(Setting::Verify, "",
                     "compares face and triangle ids, which the outputs asked for (" +
                         frameOutputsName(options.outputs) + ") do not keep");
}

}  // namespace

Renderer::Renderer(const Scene& scene, const RenderOptions& options)
    : scene_(&scene), options_(options), info_(&algorithmNamed(options.algorithm)),
      params_(resolveParams(*info_, options.params)), algorithm_(info_->create(scene, params_)) {}

Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

void Renderer::render(const Camera& camera, Frame& frame) { render(camera, options_, frame); }

Frame Renderer::render(const Camera& camera) {
  Frame frame;
  render(camera, options_, frame);
  return frame;
}

void Renderer::render(const Camera& camera, const RenderOptions& options, Frame& frame) {
  if (options.algorithm != options_.algorithm || options.params != options_.params)
    throw std::invalid_argument("Renderer::render: made for " + options_.algorithm +
                                " with its parameters; make another Renderer for " + options.algorithm);
  checkFrameOptions(*scene_, camera, options);

  Timer total;
  algo::beginStats(frame.stats, *scene_, camera);
  // Sized, not cleared: every algorithm writes every pixel (a pass over 33 MB less at 1080p).
  frame.allocate(camera.width, camera.height, options.outputs);
  if (options.countWrites) frame.writes.assign(size_t(camera.width) * size_t(camera.height), 0);
  else frame.writes.clear();
  algorithm_->render(camera, options, frame);
  // (After the run: a path that takes over another's statistics, as the tiled z-buffer's depth
  // image does from its occlusion buffer, is still named as what ran.)
  frame.stats.algorithm = info_->name;
  frame.stats.params = params_.entries();
  frame.stats.addTime("total", total.ms());
  if (options.verify) verifyFrame(*scene_, camera, options, frame);
}

Frame render(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  Frame frame;
  render(scene, camera, options, frame);
  return frame;
}

void render(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame) {
  Renderer(scene, options).render(camera, frame);
}

// --verify: the frame against the ray-cast reference, and with transparency its colours against
// the A-buffer's.
void verifyFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame) {
  RenderOptions refOptions = options;
  refOptions.algorithm = "raycast";
  refOptions.params.clear();
  refOptions.verify = false;
  refOptions.countWrites = false;
  Frame reference = render(scene, camera, refOptions);
  Timer verifyTimer;
  VerifyResult v = verifyAgainstReference(scene, camera, options, frame, reference);
  frame.stats.wrong_pixels = v.wrong_pixels;
  frame.stats.ambiguous_pixels = v.ambiguous_pixels;
  frame.stats.addTime("verify_reference", reference.stats.time_ms.back().second);
  frame.stats.addTime("verify_compare", verifyTimer.ms());
  // With transparency, the colours against the A-buffer (the colour reference).
  if (algo::hasTransparency(scene) && has(options.outputs, FrameOutputs::Color)) {
    Timer colorTimer;
    Frame colors;
    colors.allocate(camera.width, camera.height);
    algo::beginStats(colors.stats, scene, camera);
    std::vector<uint8_t> nearEdge;
    algo::abufferFrame(scene, camera, refOptions, colors, &nearEdge);
    const algo::ColorError e = algo::colorError(frame, colors, &nearEdge);
    Stats& st = frame.stats;
    st.setDetail("verify_color_pixels", e.pixels);
    st.setDetail("verify_color_near_edge", e.nearEdge);
    st.setDetail("verify_color_max_r", uint64_t(e.max[0]));
    st.setDetail("verify_color_max_g", uint64_t(e.max[1]));
    st.setDetail("verify_color_max_b", uint64_t(e.max[2]));
    st.setDetail("verify_color_mean_r", e.mean[0]);
    st.setDetail("verify_color_mean_g", e.mean[1]);
    st.setDetail("verify_color_mean_b", e.mean[2]);
    st.setDetail("verify_color_beyond_step", e.beyondStep);
    st.addTime("verify_colors", colorTimer.ms());
  }
}

}  // namespace hsr

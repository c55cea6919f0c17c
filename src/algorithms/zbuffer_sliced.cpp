// The z-buffer drawn in depth slices: the KTH thesis's mitigation of z-fighting. The depth range
// [near, far] is cut into parts of equal far/near ratio, drawn from the farthest to the nearest,
// each with the camera's planes set to the part's, so the depth format spends its whole precision
// on each; the textbook loop (a depth test per fragment, submission order) draws each part on the
// drawing service's rasterizers.
#include <algorithm>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"

namespace hsr::algo {
namespace {

// A nearer slice's pixels replace the farther slices' under them.
void mergeNearer(const Frame& part, Frame& frame) {
  for (size_t i = 0; i < part.depth.size(); ++i) {
    if (!std::isfinite(part.depth[i])) continue;
    frame.depth[i] = part.depth[i];
    if (!part.faceId.empty()) frame.faceId[i] = part.faceId[i];
    if (!part.triangleId.empty()) frame.triangleId[i] = part.triangleId[i];
    if (!part.color.empty()) frame.color[i] = part.color[i];
  }
  for (size_t i = 0; i < part.writes.size(); ++i) frame.writes[i] += part.writes[i];
}

// The depth range [near, far] cut into `slices` parts of equal far/near ratio, drawn from the
// farthest to the nearest, each with the camera's planes set to the part's (so the depth format
// spends its whole precision on it); the front end clips every triangle to each part. Each part
// but the farthest reaches a tenth of its depth into the next: a surface where two parts meet lies
// inside the nearer one, away from its clipping plane, so the rounding of clipped edges leaves no
// crack there; and where the nearer part shows anything, its nearest surface is the pixel's.
void drawInSlices(const Scene& scene, const Camera& camera, const RenderOptions& options, DrawRaster raster,
                     int slices, DrawBuffers& buffers, Frame& frame) {
  const double ratio = std::pow(camera.far / camera.near, 1.0 / slices);
  const Stats begun = frame.stats;  // what render() recorded: each part starts from it
  Stats total;
  Frame part;
  for (int s = slices - 1; s >= 0; --s) {
    Camera slice = camera;
    slice.near = s == 0 ? camera.near : camera.near * std::pow(ratio, s);
    const double boundary = camera.near * std::pow(ratio, s + 1);
    slice.far = s == slices - 1 ? camera.far : std::min(camera.far, boundary + 0.1 * (boundary - slice.near));
    const bool farthest = s == slices - 1;
    if (s == slices - 2) part = frame;  // the buffers' sizes; drawScene clears them
    Frame& target = farthest ? frame : part;
    target.stats = begun;
    drawScene(scene, slice, options, WriteRule::DepthTest, raster, /*order: submission*/ {}, buffers, target);
    if (farthest) {
      total = frame.stats;
      continue;
    }
    total.addCounts(part.stats);  // (its buffers are the farthest part's, reused)
    mergeNearer(part, frame);
  }
  total.covered_pixels = 0;
  for (float d : frame.depth) total.covered_pixels += std::isfinite(d);
  Stats partFrame;
  addFrameMemory(partFrame, part);
  total.addMemory("slice_frame", partFrame.memory_bytes);
  frame.stats = std::move(total);
  frame.stats.setDetail("depth_slices", uint64_t(slices));
}

// The object keeps the drawing service's buffers, reused by every part.
class ZbufferSliced final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    drawInSlices(scene_, camera, options, drawRasterOf(params_), int(params_.integer("slices")), buffers_, frame);
  }
};

}  // namespace

AlgorithmInfo zbufferSlicedAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer-sliced";
  a.summary = "the textbook z-buffer in depth slices, farthest first, each with the depth format's whole precision";
  a.source = "KTH thesis";
  a.params = {{"slices", ParamType::Int, "4", {}, 1, 64,
               "the parts the depth range is drawn in, of equal far/near ratio (1: the textbook z-buffer)"},
              drawRasterParam("binned")};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision over each slice: z-fighting is counted as ambiguous";
  a.create = factoryOf<ZbufferSliced>();
  return a;
}

}  // namespace hsr::algo

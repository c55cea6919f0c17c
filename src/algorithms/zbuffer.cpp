// The z-buffer [KTH report, KTH thesis, lecture notes, Java chapter], as a textbook states it:
//
//   depth[every pixel] = far;  colour[every pixel] = background
//   for each triangle, in the order it was submitted:
//     for each pixel centre (x, y) it covers:
//       z = its depth at (x, y), in the depth format
//       if z is strictly nearer than depth[x, y]:   (a tie keeps what was drawn first)
//         depth[x, y] = z;  colour[x, y] = its colour
//
// That loop is the drawing service's depth-test rule (draw.cpp, FragmentWriter::apply), drawn in
// submission order: so `raster=halfspace`, `scanline` and `binned` are this file's few lines. Its
// counters are the textbook's: one z comparison per fragment, one write per fragment that won.
// `raster=tiled` (the default) is the production z-buffer of zbuffer_tiled.cpp: the same image,
// bit for bit, computed with far fewer tests on every core. `depth-slices=N` is the KTH thesis's
// mitigation of z-fighting: the depth range drawn in parts, each with the buffer's full precision.
// `occlusion-cull=on` drops whole meshes hidden behind what is drawn before setting them up,
// testing them against a z-pyramid kept over the textbook z-buffer (hzb.cpp: zbufferOcclusionCulled).
// `region=WxH` and `clear=half-range` are the paper's memory and clearing savers
// (zbuffer_memory.cpp).
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

#include <algorithm>
#include <cmath>

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
void zbufferInSlices(const Scene& scene, const Camera& camera, const RenderOptions& options, DrawRaster raster,
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

// Opaque faces first in submission order, then the transparent ones back to front by `key`
// (sort-key), depth-tested without depth writes (the tiled rasterizer's kernel has no such pass:
// its transparent frames are drawn by the service's binned rasterizer).
void zbufferWithTransparency(const Scene& scene, const Camera& camera, const RenderOptions& options,
                             const std::string& raster, SortKey key, DrawBuffers& buffers, Frame& frame) {
  std::vector<uint32_t> submission(scene.faceCount());
  for (uint32_t f = 0; f < submission.size(); ++f) submission[f] = f;
  const DrawRaster r = raster == "scanline"                      ? DrawRaster::Scanline
                       : raster == "tiled" || raster == "binned" ? DrawRaster::Binned
                                                                 : DrawRaster::HalfSpace;
  drawScene(scene, camera, options, WriteRule::DepthTestBlend, r,
            byFaceRank(transparentLast(scene, camera, submission, key)), buffers, frame);
}

// The z-buffer's object: the buffers its ways of drawing keep from one frame to the next.
class Zbuffer final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override;

 private:
  void drawSaving(const Camera& camera, const RenderOptions& options, Frame& frame);
  TiledZBuffer tiled_;          // raster=tiled
  HalfRangeZBuffer halfRange_;  // clear=half-range
};

// region=WxH or clear=half-range: the textbook loop on the half-space rasterizer, alone.
void Zbuffer::drawSaving(const Camera& camera, const RenderOptions& options, Frame& frame) {
  const auto [rw, rh] = params_.size("region");
  const bool halfRange = params_.text("clear") == "half-range";
  const char* what = halfRange ? "--param clear=half-range" : "--param region";
  if (halfRange && rw > 0) throw InputError("--param clear=half-range: keeps one whole-image buffer; drop --param region");
  if (params_.integer("depth-slices") > 1 || params_.flag("occlusion-cull"))
    throw InputError(std::string(what) + ": not with depth-slices or occlusion-cull (drop those)");
  if (params_.text("raster") == "scanline")
    throw InputError(std::string(what) + ": draws on the half-space rasterizer (drop --param raster=scanline)");
  if (halfRange) return halfRange_.draw(scene_, camera, options, frame);
  zbufferInRegions(scene_, camera, options, int(rw), int(rh), buffers_, frame);
}

void Zbuffer::render(const Camera& camera, const RenderOptions& options, Frame& frame) {
  const Scene& scene = scene_;
  const std::string& raster = params_.text("raster");
  if (hasTransparency(scene))
    return zbufferWithTransparency(scene, camera, options, raster, sortKeyOf(params_.text("sort-key")), buffers_,
                                   frame);
  if (params_.text("region") != "full" || params_.text("clear") == "half-range")
    return drawSaving(camera, options, frame);
  if (params_.flag("occlusion-cull")) {
    if (params_.integer("depth-slices") > 1)
      throw InputError("--param occlusion-cull=on: culls against one depth buffer over the whole range; drop "
                       "--param depth-slices");
    if (raster == "scanline")
      throw InputError("--param occlusion-cull=on: zbuffer culls objects on the half-space rasterizer only (drop "
                       "--param raster=scanline)");
    return zbufferOcclusionCulled(scene, camera, options, frame);
  }
  if (raster == "tiled") {
    if (params_.integer("depth-slices") > 1)
      throw InputError("--param depth-slices: the tiled z-buffer draws the whole range at once; add --param "
                       "raster=binned (or halfspace, scanline) to draw it in parts");
    if (options.countWrites)
      throw InputError("--overdraw-image: zbuffer's tiled rasterizer does not count writes per pixel (it replaces "
                       "whole blocks at once); add --param raster=halfspace for the textbook z-buffer");
    return tiled_.draw(scene, camera, options, frame);
  }
  const DrawRaster textbook = raster == "scanline" ? DrawRaster::Scanline
                              : raster == "binned"  ? DrawRaster::Binned
                                                    : DrawRaster::HalfSpace;
  if (const int slices = int(params_.integer("depth-slices")); slices > 1)
    return zbufferInSlices(scene, camera, options, textbook, slices, buffers_, frame);
  drawScene(scene, camera, options, WriteRule::DepthTest, textbook, /*order: submission*/ {}, buffers_, frame);
}

}  // namespace

AlgorithmInfo zbufferAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer";
  a.summary = "z-buffer: a depth test per pixel, triangles in submission order";
  a.source = "KTH report, KTH thesis, lecture notes, Java chapter";
  a.params = {{"raster", ParamType::Choice, "tiled", {"tiled", "halfspace", "scanline", "binned"}, -1e300, 1e300,
               "tiled: the production z-buffer (binned, SIMD, every core; counts only the tests it makes); "
               "halfspace: the textbook z-buffer on the scalar reference rasterizer, every fragment tested in "
               "submission order; scanline: the same on the lecture notes' scanline rasterizer, depth stepped "
               "along each span; binned: the textbook z-buffer on the drawing service's binned rasterizer (64x64 "
               "tiles on every core, scalar), the one the painter's family draws with by default, so times compare"},
              {"depth-slices", ParamType::Int, "1", {}, 1, 64,
               "draw the depth range in this many parts of equal far/near ratio, farthest first, each with the "
               "depth format's whole precision (the KTH thesis's mitigation of z-fighting; not with raster=tiled)"},
              {"occlusion-cull", ParamType::Bool, "off", {}, -1e300, 1e300,
               "occlusion culling: meshes in batches nearest first, each mesh's screen box and nearest depth tested "
               "against a z-pyramid over the depth buffer before any of its triangles is set up; the triangles left "
               "drawn by the textbook loop (a depth test per fragment, half-space rasterizer, whatever raster says)"},
              {"region", ParamType::Size, "full", {}, 1, 16384,
               "draw the image region by region, WxH pixels at a time, with one z-buffer the size of a region (the "
               "textbook loop on the half-space rasterizer, whatever raster says; the same image)"},
              sortKeyParam("centroid",
                           "scenes with transparency: after the opaque faces, the transparent ones are drawn back to "
                           "front by this depth of each face (its area centroid, farthest or nearest vertex, or the "
                           "mean of its vertices), depth-tested without depth writes; no order by one depth per face "
                           "is right for interpenetrating or cyclically overlapping faces (docs/transparency.md)"),
              {"clear", ParamType::Choice, "every-frame", {"every-frame", "half-range"}, -1e300, 1e300,
               "half-range: the z-buffer is kept by the algorithm object (a Renderer's, across its views) and not "
               "cleared between frames; even frames use the "
               "lower half of its values, odd frames the upper half with the test reversed (one bit of precision "
               "less; the textbook loop on the half-space rasterizer, whatever raster says)"}};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision: z-fighting is counted as ambiguous";
  a.create = factoryOf<Zbuffer>();
  return a;
}

}  // namespace hsr::algo

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
// submission order: so `raster=halfspace` and `raster=scanline` are this file's few lines. Its
// counters are the textbook's: one z comparison per fragment, one write per fragment that won.
// `raster=tiled` (the default) is the production z-buffer of zbuffer_tiled.cpp: the same image,
// bit for bit, computed with far fewer tests on every core.
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

void zbuffer(const Scene& scene, const Camera& camera, const RenderOptions& options, const AlgorithmParams& params,
             Frame& frame) {
  const std::string& raster = params.text("raster");
  if (hasTransparency(scene)) {
    // Opaque faces first in submission order, then the transparent ones back to front by their
    // centroids, depth-tested without depth writes (the tiled rasterizer's kernel has no such
    // pass: its transparent frames are drawn by the service's binned rasterizer).
    std::vector<uint32_t> submission(scene.faceCount());
    for (uint32_t f = 0; f < submission.size(); ++f) submission[f] = f;
    const DrawRaster r = raster == "scanline" ? DrawRaster::Scanline
                         : raster == "tiled"  ? DrawRaster::Binned
                                              : DrawRaster::HalfSpace;
    drawScene(scene, camera, options, WriteRule::DepthTestBlend, r,
              byFaceRank(transparentLast(scene, camera, submission, SortKey::Centroid)), frame);
    return;
  }
  if (raster == "tiled") {
    if (options.countWrites)
      throw InputError("--overdraw-image: zbuffer's tiled rasterizer does not count writes per pixel (it replaces "
                       "whole blocks at once); add --param raster=halfspace for the textbook z-buffer");
    return zbufferTiled(scene, camera, options, frame);
  }
  const DrawRaster textbook = raster == "scanline" ? DrawRaster::Scanline : DrawRaster::HalfSpace;
  drawScene(scene, camera, options, WriteRule::DepthTest, textbook, /*order: submission*/ {}, frame);
}

}  // namespace

AlgorithmInfo zbufferAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer";
  a.summary = "z-buffer: a depth test per pixel, triangles in submission order";
  a.source = "KTH report, KTH thesis, lecture notes, Java chapter";
  a.params = {{"raster", ParamType::Choice, "tiled", {"tiled", "halfspace", "scanline"}, -1e300, 1e300,
               "tiled: the production z-buffer (binned, SIMD, every core; counts only the tests it makes); "
               "halfspace: the textbook z-buffer on the scalar reference rasterizer, every fragment tested in "
               "submission order; scanline: the same on the lecture notes' scanline rasterizer, depth stepped "
               "along each span"}};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision: z-fighting is counted as ambiguous";
  a.run = zbuffer;
  return a;
}

}  // namespace hsr::algo

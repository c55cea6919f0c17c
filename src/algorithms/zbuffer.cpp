// The z-buffer [KTH report, KTH thesis, lecture notes, Java chapter], as a textbook states it:
//
//   depth[every pixel] = far;  colour[every pixel] = background
//   for each triangle, in the order it was submitted:
//     for each pixel centre (x, y) it covers:
//       z = its depth at (x, y), in the depth format
//       if z is strictly nearer than depth[x, y]:   (a tie keeps what was drawn first)
//         depth[x, y] = z;  colour[x, y] = its colour
//
// That loop is the drawing service's depth-test rule (draw.cpp, DepthTestRule), drawn in
// submission order: so `raster=halfspace`, `scanline` and `binned` are this file's few lines. Its
// counters are the textbook's: one z comparison per fragment, one write per fragment that won.
// `raster=tiled` (the default) is the production z-buffer of zbuffer_tiled.cpp: the same image,
// bit for bit, computed with far fewer tests on every core. The documents' variants of the loop
// are algorithms of their own: zbuffer-sliced (the KTH thesis's depth slices), zbuffer-regions
// and zbuffer-half-range (the Ukrainian paper's memory and clearing savers) and zbuffer-culled
// (occlusion culling of meshes).
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

#include <algorithm>
#include <cmath>

namespace hsr::algo {
namespace {

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

// The z-buffer's object: the tiled z-buffer's bins and buffers, and the drawing service's, kept
// from one frame to the next.
class Zbuffer final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const std::string& raster = params_.text("raster");
    if (hasTransparency(scene_))
      return zbufferWithTransparency(scene_, camera, options, raster, sortKeyOf(params_.text("sort-key")), buffers_,
                                     frame);
    if (raster != "tiled") return drawScene(scene_, camera, options, WriteRule::DepthTest, drawRasterOf(params_),
                                            /*order: submission*/ {}, buffers_, frame);
    if (options.countWrites)
      throw InputError(Setting::OverdrawImage, "",
                       "zbuffer's tiled rasterizer does not count writes per pixel (it replaces whole blocks at "
                       "once); the textbook z-buffer (parameter raster=halfspace) does");
    tiled_.draw(scene_, camera, options, frame);
  }

 private:
  TiledZBuffer tiled_;  // raster=tiled
};

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
              sortKeyParam("centroid",
                           "scenes with transparency: after the opaque faces, the transparent ones are drawn back to "
                           "front by this depth of each face (its area centroid, farthest or nearest vertex, or the "
                           "mean of its vertices), depth-tested without depth writes; no order by one depth per face "
                           "is right for interpenetrating or cyclically overlapping faces (docs/transparency.md)")};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision: z-fighting is counted as ambiguous";
  a.create = factoryOf<Zbuffer>();
  return a;
}

}  // namespace hsr::algo

// The z-buffer region by region: "a smaller z-buffer reused region by region", one of the
// Ukrainian paper's memory savers, on the textbook loop (a depth test per fragment, triangles in
// submission order, the scalar half-space rasterizer). The image is cut into regions of W x H
// pixels; each region is drawn on its own, from the triangles whose screen box meets it, with one
// z-buffer the size of a region, and resolved into the frame before the next. Each pixel sees the
// same fragments in the same order as with a whole-image buffer: the same image, bit for bit,
// with a region's buffer instead of an image's.
#include <algorithm>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "core/timer.hpp"
#include "raster/halfspace.hpp"

namespace hsr::algo {
namespace {

// The triangles drawn region by region into the cleared frame, with one region-sized z-buffer
// of `buffers`; times its stages "clear" (the region's buffers), "raster" and "resolve".
template <DepthStorage S, DepthMapping M>
void drawRegions(std::span<const SetupTriangle> tris, const Camera& camera, const RenderOptions& options,
                 const TriangleShader& shade, int rw, int rh, DrawBuffers& buffers, Frame& frame, DrawCounters& n) {
  using T = DepthT<S>;
  const int columns = (camera.width + rw - 1) / rw, rows = (camera.height + rh - 1) / rh;
  const std::vector<std::vector<uint32_t>> bins = binByCell(tris, rw, rh, columns, rows);
  const T clear = quantizeDepth<S>(options.depthFormat.clearValue());
  const std::vector<Rgba8> colors =
      has(options.outputs, FrameOutputs::Color) ? triangleColors(tris, shade, nullptr, 1) : std::vector<Rgba8>{};
  Timer timer;
  double clearMs = 0, rasterMs = 0, resolveMs = 0;
  std::vector<T>& depth = buffers.depth<T>();        // the one z-buffer, a region's size
  std::vector<uint32_t>& winner = buffers.winner();  // 1 + the winning triangle, 0 = none
  depth.resize(size_t(rw) * size_t(rh));
  winner.resize(depth.size());
  for (int ry = 0; ry < rows; ++ry)
    for (int rx = 0; rx < columns; ++rx) {
      const PixelRect region{rx * rw, ry * rh, std::min((rx + 1) * rw, camera.width) - 1,
                             std::min((ry + 1) * rh, camera.height) - 1, size_t(rw)};
      std::fill(depth.begin(), depth.end(), clear);
      std::fill(winner.begin(), winner.end(), 0);
      clearMs += timer.lap();
      for (const uint32_t i : bins[size_t(ry) * size_t(columns) + size_t(rx)]) {
        const MappedPlanes m = mapPlanes<M>(tris[i].depthNum, tris[i].depthDen, camera.near, camera.far,
                                            camera.orthographic);
        rasterizeHalfSpace(clippedTo(tris[i], region.x0, region.y0, region.x1, region.y1), [&](int x, int y, double) {
          const size_t at = region.at(x, y);
          const T z = T(fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5)));
          if (!depthTest<M>(z, depth[at], n)) return;
          winner[at] = i + 1;
          countWritten(frame.index(x, y), frame, n);
        });
      }
      rasterMs += timer.lap();
      resolvePixels(
          region, winner, tris, options.outputs, nullptr,
          [&](uint32_t w, size_t idx) {
            if (!colors.empty()) frame.color[idx] = colors[w];
          },
          frame, n);
      resolveMs += timer.lap();
    }
  Stats& st = frame.stats;
  st.addTime("clear", clearMs);
  st.addTime("raster", rasterMs);
  st.addTime("resolve", resolveMs);
  st.addMemory("triangle_colors", colors.size() * sizeof(Rgba8));
  st.addMemory("depth_buffer", depth.size() * sizeof(T));
  st.addMemory("winner_ids", winner.size() * sizeof(uint32_t));
  st.addMemory("region_bins", binBytes(bins));
  st.setDetail("regions", uint64_t(columns) * uint64_t(rows));
}

// The object keeps the region's buffers from one view to the next.
class ZbufferRegions final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const auto [w, h] = params_.size("region");
    const int rw = w > 0 ? std::min(int(w), camera.width) : camera.width;
    const int rh = h > 0 ? std::min(int(h), camera.height) : camera.height;
    drawFrame(scene_, camera, options, {}, [&](FrameWork& work, const TriangleShader& shade) {
      visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
        drawRegions<S, M>(work.triangles, camera, options, shade, rw, rh, buffers_, frame, work.counters);
      });
    }, frame);
    frame.stats.setDetail("rasterizer", "halfspace");
  }
};

}  // namespace

AlgorithmInfo zbufferRegionsAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer-regions";
  a.summary = "the textbook z-buffer region by region, with one z-buffer the size of a region: the same image";
  a.source = "Ukrainian paper";
  a.params = {{"region", ParamType::Size, "64x64", {}, 1, 16384,
               "the region's size in pixels, WxH (full: the whole image, one region); the z-buffer is one "
               "region's size"}};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision: z-fighting is counted as ambiguous";
  a.create = factoryOf<ZbufferRegions>();
  return a;
}

}  // namespace hsr::algo

// The occlusion buffer (include/hsr/occlusion.hpp): the tiled z-buffer's front end, binning and
// kernel (depth only), with one tile buffer per screen tile kept after the pass instead of a
// worker's scratch resolved into an image. Queries read the tiles' states and bounds; the depth
// image is the z-buffer's depth-only resolve, run on demand.
#include <hsr/occlusion.hpp>

#include <atomic>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "algorithms/tiled_pass.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"

namespace hsr {

struct OcclusionBuffer::Impl {
  algo::TiledState state;
  // One tile buffer per screen tile, kept between calls. Allocated without initialising (each
  // pass sets every tile's state; pixel buffers are written before they are read), so the pages
  // of buffers a frame never touches (the triangle ids, unused here) are not even mapped in.
  std::unique_ptr<tiled::TileScratch[]> tiles;
  size_t tileCapacity = 0;
  DepthSetup depth;
  Stats stats;
  int threads = 1;
  int width = 0, height = 0;  // of the last completed render (0: nothing rendered)

  int tileOf(int x, int y) const { return (y / tiled::kTileSize) * state.bins.tilesX + x / tiled::kTileSize; }
};

OcclusionBuffer::OcclusionBuffer() : impl_(std::make_unique<Impl>()) {}
OcclusionBuffer::~OcclusionBuffer() = default;
OcclusionBuffer::OcclusionBuffer(OcclusionBuffer&&) noexcept = default;
OcclusionBuffer& OcclusionBuffer::operator=(OcclusionBuffer&&) noexcept = default;

int OcclusionBuffer::width() const { return impl_->width; }
int OcclusionBuffer::height() const { return impl_->height; }

const Stats& OcclusionBuffer::render(const Scene& scene, const Camera& camera, const OcclusionOptions& options) {
  Impl& im = *impl_;
  im.width = im.height = 0;  // nothing to query, until the pass below has completed
  algo::checkImage(camera, options.depthFormat);
  Timer total, timer;
  RenderOptions opt;
  opt.depthFormat = options.depthFormat;
  opt.cull = options.cull;
  opt.threads = options.threads;
  opt.outputs = FrameOutputs::DepthOnly;
  im.threads = resolveThreads(options.threads);
  im.depth = DepthSetup{opt.depthFormat, camera.near, camera.far, camera.orthographic};
  algo::setUpAndBin(scene, camera, opt, im.depth, im.state);
  Stats& st = im.stats;
  st = Stats{};
  st.addTime("frontend", timer.lap());

  const tiled::Bins& bins = im.state.bins;
  const size_t tiles = size_t(bins.tileCount());
  if (im.tileCapacity < tiles) {
    im.tiles.reset(new tiled::TileScratch[tiles]);  // default-initialised: see Impl::tiles
    im.tileCapacity = tiles;
  }
  const int workers = algo::prepareTilePass(im.state, im.threads);
  std::atomic<size_t> next{0};
  parallelFor(0, size_t(workers), workers, [&](size_t worker) {
    for (size_t tile; (tile = next.fetch_add(1, std::memory_order_relaxed)) < tiles;)
      tiled::rasterizeTile(bins, int(tile), im.depth, false, im.tiles[tile], im.state.orders[worker],
                           im.state.counters[tile]);
  });
  tiled::RasterCounters counters;
  for (size_t tile = 0; tile < tiles; ++tile) counters.add(im.state.counters[tile]);
  st.addTime("raster", timer.lap());

  st.algorithm = "occlusion";
  st.width = camera.width;
  st.height = camera.height;
  st.faces = scene.faceCount();
  st.triangles = scene.triangles.size();
  st.depth_format = opt.depthFormat.name();
  algo::tiledStats(st, im.state.fe, &bins, counters);
  st.memory_bytes = im.state.memoryBytes() + im.tileCapacity * sizeof(tiled::TileScratch) + im.state.fe.memoryBytes();
  st.addTime("total", total.ms());
  im.width = camera.width;
  im.height = camera.height;
  return st;
}

namespace {
void requireRendered(int width, const char* what) {
  if (width == 0) throw InputError(std::string(what) + ": the occlusion buffer holds nothing yet (call render first)");
}
}  // namespace

bool OcclusionBuffer::rectVisible(int x0, int y0, int x1, int y1, double eyeDepth) const {
  const Impl& im = *impl_;
  requireRendered(width(), "rectVisible");
  if (std::isnan(eyeDepth)) throw InputError("rectVisible: the depth is NaN");
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width() - 1);
  y1 = std::min(y1, height() - 1);
  if (x1 < x0 || y1 < y0) return false;
  double q = 0;
  visitDepthFormat(im.depth.format, [&]<DepthStorage S, DepthMapping M>() {
    q = double(quantizeDepth<S>(mapDepth<M>(eyeDepth, im.depth.near, im.depth.far, im.depth.orthographic)));
  });
  constexpr int T = tiled::kTileSize;
  for (int ty = y0 / T; ty <= y1 / T; ++ty)
    for (int tx = x0 / T; tx <= x1 / T; ++tx) {
      const int tile = ty * im.state.bins.tilesX + tx;
      if (tiled::anyFarther(im.state.bins, tile, im.depth, im.tiles[size_t(tile)], std::max(x0 - tx * T, 0),
                            std::max(y0 - ty * T, 0), std::min(x1 - tx * T, T - 1), std::min(y1 - ty * T, T - 1), q))
        return true;
    }
  return false;
}

double OcclusionBuffer::storedAt(int x, int y) const {
  const Impl& im = *impl_;
  requireRendered(width(), "storedAt");
  if (x < 0 || y < 0 || x >= width() || y >= height())
    throw InputError("storedAt: pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") is outside the " +
                     std::to_string(width()) + "x" + std::to_string(height()) + " image");
  const int tile = im.tileOf(x, y);
  return tiled::storedAt(im.state.bins, tile, im.depth, im.tiles[size_t(tile)], x % tiled::kTileSize,
                         y % tiled::kTileSize);
}

void OcclusionBuffer::depthImage(Frame& frame) const {
  const Impl& im = *impl_;
  requireRendered(width(), "depthImage");
  const tiled::Bins& bins = im.state.bins;
  frame.allocate(bins.width, bins.height, false, false);
  frame.stats = im.stats;
  // One tile row per task, written band by band across it (long row pieces: tiled::resolveTile).
  std::vector<uint64_t> covered(size_t(bins.tilesY), 0);
  parallelFor(0, size_t(bins.tilesY), im.threads, [&](size_t ty) {
    for (int row = 0; row < tiled::kTileSize; row += 8)
      for (int tx = 0; tx < bins.tilesX; ++tx) {
        const int tile = int(ty) * bins.tilesX + tx;
        covered[ty] += tiled::resolveTile(bins, tile, im.depth, FrameOutputs::DepthOnly, nullptr, Rgba8{},
                                          im.tiles[size_t(tile)], frame, row, row + 8);
      }
  });
  for (uint64_t c : covered) frame.stats.covered_pixels += c;
}

}  // namespace hsr

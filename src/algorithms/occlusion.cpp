// The occlusion buffer (include/hsr/occlusion.hpp): the tiled z-buffer's front end, binning and
// kernel (depth only), with one kept tile per screen tile (tiled::KeptTile: each tile rasterized
// in the worker's scratch, then stored) instead of a worker's scratch resolved into an image.
// Queries read the tiles' states and bounds; the depth image is the z-buffer's depth-only
// resolve of each kept tile unpacked, run on demand.
#include <hsr/occlusion.hpp>

#include <atomic>
#include <cmath>
#include <limits>

#include "algorithms/algorithms.hpp"
#include "algorithms/tiled_pass.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"

namespace hsr {

struct OcclusionBuffer::Impl {
  algo::TiledState state;
  // One kept tile per screen tile, between calls (each rasterized in a worker's scratch, then
  // stored: tiled::storeTile). Allocated without initialising (each pass sets every tile's
  // summary; pixel values are written before they are read).
  std::unique_ptr<tiled::KeptTile[]> tiles;
  size_t tileCapacity = 0;
  DepthSetup depth;
  Camera camera;
  Stats stats;
  int threads = 1;
  int width = 0, height = 0;  // of the last completed render (0: nothing rendered)

  int tileOf(int x, int y) const { return (y / tiled::kTileSize) * state.bins.tilesX + x / tiled::kTileSize; }

  // Whether some pixel of the rectangle (clipped to the image) stores a value farther than q.
  bool anyFarther(int x0, int y0, int x1, int y1, double q) const {
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, width - 1);
    y1 = std::min(y1, height - 1);
    constexpr int T = tiled::kTileSize;
    for (int ty = y0 / T; y1 >= y0 && ty <= y1 / T; ++ty)
      for (int tx = x0 / T; x1 >= x0 && tx <= x1 / T; ++tx) {
        const int tile = ty * state.bins.tilesX + tx;
        if (tiled::anyFarther(state.bins, tile, depth, tiles[size_t(tile)], std::max(x0 - tx * T, 0),
                              std::max(y0 - ty * T, 0), std::min(x1 - tx * T, T - 1), std::min(y1 - ty * T, T - 1), q))
          return true;
      }
    return false;
  }

  // The value a fragment at eye depth d stores by the mapping, `steps` storage steps nearer.
  double storedOf(double d, int steps) const {
    double q = 0;
    visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
      constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
      const DepthT<S> v = quantizeDepth<S>(mapDepth<M>(d, depth.near, depth.far, depth.orthographic));
      q = double(v);
      for (int i = 0; i < steps; ++i) {
        if constexpr (S == DepthStorage::F32)
          q = double(std::nextafter(float(q), greater ? std::numeric_limits<float>::infinity()
                                                      : -std::numeric_limits<float>::infinity()));
        else
          q += greater ? 1.0 : -1.0;
      }
    });
    return q;
  }
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
  im.camera = camera;
  im.depth = DepthSetup{opt.depthFormat, camera.near, camera.far, camera.orthographic};
  algo::setUpAndBin(scene, camera, opt, im.depth, im.state);
  Stats& st = im.stats;
  st = algo::frameStats(scene, camera);
  st.addTime("frontend", timer.lap());

  const tiled::Bins& bins = im.state.bins;
  const size_t tiles = size_t(bins.tileCount());
  if (im.tileCapacity < tiles) {
    im.tiles.reset(new tiled::KeptTile[tiles]);  // default-initialised: see Impl::tiles
    im.tileCapacity = tiles;
  }
  const int workers = algo::prepareTilePass(im.state, im.threads);
  if (im.state.scratch.size() < size_t(workers)) im.state.scratch.resize(size_t(workers));
  algo::assignUnits(im.state, workers, tiles, [](size_t tile) { return std::pair(int(tile), 1); });
  parallelFor(0, size_t(workers), workers, [&](size_t worker) {
    const size_t part = currentPart();  // (tiles whose records this thread set up come first)
    tiled::TileScratch& scratch = im.state.scratch[worker];
    for (size_t tile = im.state.tileWork.next(part); tile < tiles;) {
      tiled::rasterizeTile(bins, int(tile), im.depth, false, scratch, im.state.orders[worker], im.state.counters[tile]);
      // The next tile is claimed before this one's streamed stores: claiming is a locked
      // instruction, which waits until the streamed stores before it have drained.
      const size_t following = im.state.tileWork.next(part);
      tiled::storeTile(scratch, im.depth, im.tiles[tile]);
      tile = following;
    }
    tiled::finishResolves();
  });
  tiled::RasterCounters counters;
  for (size_t tile = 0; tile < tiles; ++tile) counters.add(im.state.counters[tile]);
  st.addTime("raster", timer.lap());

  st.algorithm = "occlusion";
  st.depth_format = opt.depthFormat.name();
  algo::tiledStats(st, im.state.fe, &bins, counters);
  st.memory_bytes = im.state.memoryBytes() + im.tileCapacity * sizeof(tiled::KeptTile) + im.state.fe.memoryBytes();
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
  return im.anyFarther(x0, y0, x1, y1, im.storedOf(eyeDepth, 0));
}

bool OcclusionBuffer::boxVisible(const Bounds3& box) const {
  const Impl& im = *impl_;
  requireRendered(width(), "boxVisible");
  if (glm::any(glm::isnan(box.lo)) || glm::any(glm::isnan(box.hi))) throw InputError("boxVisible: the box has NaN corners");
  if (box.empty()) return false;
  constexpr double inf = std::numeric_limits<double>::infinity();
  double minX = inf, minY = inf, maxX = -inf, maxY = -inf, nearest = inf;
  for (int c = 0; c < 8; ++c) {
    const dvec3 corner(c & 1 ? box.hi.x : box.lo.x, c & 2 ? box.hi.y : box.lo.y, c & 4 ? box.hi.z : box.lo.z);
    const dvec4 h = im.camera.toPixelH(corner);
    if (!(h.z > im.camera.near) || !(h.w > 0)) return true;  // reaches the near plane: no bound here
    const double px = h.x / h.w, py = h.y / h.w;
    minX = std::min(minX, px);
    maxX = std::max(maxX, px);
    minY = std::min(minY, py);
    maxY = std::max(maxY, py);
    nearest = std::min(nearest, h.z);
  }
  if (nearest > im.camera.far) return false;  // wholly beyond the far plane: clipped away
  // Pixels whose centres the box's faces may cover (vertices snap by at most 1/512 pixel),
  // clamped before conversion so that huge coordinates cannot overflow.
  auto pixel = [&](double v, int size) { return int(std::clamp(std::floor(v), -1.0, double(size))); };
  const int x0 = pixel(minX - 0.5 - 0.01, im.width), x1 = pixel(maxX - 0.5 + 0.01, im.width) + 1;
  const int y0 = pixel(minY - 0.5 - 0.01, im.height), y1 = pixel(maxY - 0.5 + 0.01, im.height) + 1;
  return im.anyFarther(x0, y0, x1, y1, im.storedOf(nearest, 1));
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
  frame.allocate(bins.width, bins.height, FrameOutputs::DepthOnly);
  frame.stats = im.stats;
  // One tile row per task: each kept tile unpacked into the task's scratch, then resolved.
  std::vector<uint64_t> covered(size_t(bins.tilesY), 0);
  parallelFor(0, size_t(bins.tilesY), im.threads, [&](size_t ty) {
    const auto scratch = std::make_unique<tiled::TileScratch>();
    for (int tx = 0; tx < bins.tilesX; ++tx) {
      const int tile = int(ty) * bins.tilesX + tx;
      tiled::loadTile(im.tiles[size_t(tile)], im.depth, *scratch);
      covered[ty] += tiled::resolveTile(bins, tile, im.depth, FrameOutputs::DepthOnly, nullptr, Rgba8{}, *scratch, frame);
    }
    tiled::finishResolves();
  });
  for (uint64_t c : covered) frame.stats.covered_pixels += c;
}

}  // namespace hsr

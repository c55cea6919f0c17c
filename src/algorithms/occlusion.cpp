// The occlusion buffer (include/hsr/occlusion.hpp): the tiled z-buffer's front end, binning and
// kernel (depth only), with one kept tile per screen tile (tiled::KeptTile: each tile rasterized
// in the worker's scratch, then stored) instead of a worker's scratch resolved into an image.
// Queries read the tiles' states and bounds; the depth image is the z-buffer's depth-only
// resolve of each kept tile unpacked, run on demand.
#include <hsr/occlusion.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

#include "algorithms/algorithms.hpp"
#include "algorithms/tiled_pass.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "frontend/mesh_bounds.hpp"
#include "frontend/vertices.hpp"

namespace hsr {

namespace {

// Mesh culling (README, Performance; Greene's object-space culling, the Ukrainian paper): a scene of at
// least kMinMeshes meshes, seen in perspective, is drawn in up to kMaxPasses passes, nearest
// meshes first; before each pass after the first, every mesh not drawn yet whose box and nearest
// bound (meshBound) lie behind what the kept tiles already hold is dropped whole, before set-up.
// Every fragment it would draw fails the depth test there, whatever else is drawn later (stored
// values only come nearer): the same depth, bit for bit. The first pass draws the meshes that
// cannot be bounded and the nearest kPassShare-th of the others (by their boxes' least depth),
// at least kPassMeshes; the last pass, every mesh left. (Two passes, the first of a 20th, were
// faster than other shares or more passes, each tile pass having its cost: see
// docs/benchmarks.md.)
constexpr size_t kMinMeshes = 64, kMaxPasses = 2, kPassShare = 20, kPassMeshes = 16;
// For a frame (algo::cullMeshes), the first pass is drawn again by the frame, so it
// draws fewer: the nearest 40th (as many culled as with a 20th, in less time).
constexpr size_t kFramePassShare = 40;
// ... and only when the meshes left to test hold at least this many triangles per tile of the
// image (algo::meshCullingPaysForFrame checks the scene's count first): the first pass is a tile
// pass over the whole image, and a mesh found hidden saves less than its triangles' whole cost
// (the frame would have rejected many of them early anyway): below this, the first pass cost
// more than it saved (see docs/benchmarks.md).
constexpr uint64_t kFrameWaitingPerTile = 40;

}  // namespace

// The switch mesh-culling (TiledSwitches) turns it off, for tests and measurements (same depth bits).
bool algo::meshCullingApplies(const Scene& scene, const Camera& camera, const TiledSwitches& switches) {
  return !camera.orthographic && scene.meshes.size() >= kMinMeshes && switches.meshCulling;
}

bool algo::meshCullingPaysForFrame(const Scene& scene, const Camera& camera, const TiledSwitches& switches) {
  const uint64_t tiles = uint64_t((camera.width + tiled::kTileSize - 1) / tiled::kTileSize) *
                         uint64_t((camera.height + tiled::kTileSize - 1) / tiled::kTileSize);
  return scene.triangles.size() >= kFrameWaitingPerTile * tiles && meshCullingApplies(scene, camera, switches);
}

struct OcclusionBuffer::Impl {
  algo::TiledState state;  // the vertex pass, the first pass's set-up and bins, the workers' scratch
  // Passes after the first (mesh culling): their set-up records and bins stay alive until the
  // next render (the kept tiles refer to their triangles).
  std::vector<algo::TiledState> later;
  size_t passes = 0;
  // Mesh culling's scratch: each mesh's test and bound (meshBound); the meshes not drawn yet
  // (least depth, index); the meshes of a pass and their triangles; the tests of a pass; the
  // tiles a later pass touches.
  std::vector<MeshTest> tests;
  std::vector<MeshBound> bounds;
  std::vector<std::pair<double, uint32_t>> waiting;
  std::vector<uint32_t> drawn, touched, firstDrawn;
  std::vector<uint8_t> hidden;
  std::vector<TriangleRange> ranges, vertexRuns;  // (vertexRuns: of vertices, not triangles)
  algo::MeshCulling culling;  // for a frame with ids (algo::cullMeshes)
  // One kept tile per screen tile, between calls (each rasterized in a worker's scratch, then
  // stored: tiled::storeTile). Allocated without initialising (each pass sets every tile's
  // summary; pixel values are written before they are read).
  std::unique_ptr<tiled::KeptTile[]> tiles;
  size_t tileCapacity = 0;
  DepthSetup depth;
  Camera camera;
  Stats stats;
  Stats passStats;  // one pass's statistics before they are added (its details' storage reused)
  int threads = 1;
  int width = 0, height = 0;  // of the last completed render (0: nothing rendered)

  // depthImage's scratch, kept from call to call (used by one query at a time: resolveMutex).
  mutable std::mutex resolveMutex;
  mutable std::vector<tiled::TileScratch> resolveScratch;
  mutable std::vector<uint64_t> resolveCovered;
  mutable WorkQueue resolveWork;

  void tilePass(algo::TiledState& pass, bool first, Stats& st);
  void transformVerticesOf(const Scene& scene, const std::vector<uint32_t>& meshes, FrontEndOutput& vertices);
  // With forFrame: the first pass only, then `culling` (algo::cullMeshes).
  void drawByMeshes(const Scene& scene, const RenderOptions& opt, Stats& st, bool forFrame = false);
  RenderOptions start(const Scene& scene, const Camera& cam, const OcclusionOptions& options);
  uint64_t memoryBytes() const {
    uint64_t bytes = state.memoryBytes() + tileCapacity * sizeof(tiled::KeptTile) + state.fe.memoryBytes();
    for (size_t p = 1; p < passes; ++p) bytes += later[p - 1].memoryBytes() + later[p - 1].fe.memoryBytes();
    return bytes;
  }

  int tileOf(int x, int y) const { return (y / tiled::kTileSize) * state.bins.tilesX + x / tiled::kTileSize; }

  // Whether some pixel of the rectangle (clipped to the image) stores a value farther than q.
  bool anyFarther(int x0, int y0, int x1, int y1, double q) const {
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, state.bins.width - 1);
    y1 = std::min(y1, state.bins.height - 1);
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
      q = double(quantizeDepth<S>(mapDepth<M>(d, depth.near, depth.far, depth.orthographic)));
    });
    return stepsNearer(q, steps);
  }
  // Stored value q (of the format), `steps` storage steps nearer.
  double stepsNearer(double q, int steps) const {
    visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
      constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
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

namespace {

// The statistics of one pass's front end and tile pass, added to `st` through `part`.
void addPassStats(Stats& st, Stats& part, const algo::TiledState& pass, const tiled::RasterCounters& counters) {
  part.details.clear();
  algo::tiledStats(part, pass.fe, &pass.bins, counters);
  st.addCounts(part);
  for (const StaticName key : {StaticName("triangles_deferred"), StaticName("clusters_deferred"),
                               StaticName("triangles_set_up_late")})
    if (const auto count = part.detailCount(key)) st.addDetail(key, *count);
}

}  // namespace

// One pass over the tiles: the first rasterizes every tile from clear; a later one only the tiles
// its meshes were binned to, onto what the passes before kept there.
void OcclusionBuffer::Impl::tilePass(algo::TiledState& pass, bool first, Stats& st) {
  const tiled::Bins& bins = pass.bins;
  const int workers = algo::prepareTilePass(pass, threads, first ? nullptr : &touched);
  if (state.scratch.size() < size_t(workers)) state.scratch.resize(size_t(workers));
  const size_t units = first ? size_t(bins.tileCount()) : touched.size();
  if (first) algo::assignUnits(pass, workers, units, [](size_t tile) { return std::pair(int(tile), 1); });
  else algo::assignUnits(pass, workers, units, [&](size_t u) { return std::pair(int(touched[u]), 1); });
  parallelFor(0, size_t(workers), workers, [&](size_t worker) {
    const size_t part = currentPart();  // (tiles whose records this thread set up come first)
    tiled::TileScratch& scratch = state.scratch[worker];
    for (size_t u = pass.tileWork.next(part); u < units;) {
      const size_t tile = first ? u : touched[u];
      if (!first) tiled::loadTile(tiles[tile], depth, scratch);
      tiled::rasterizeTile(bins, int(tile), depth, false, scratch, pass.orders[worker], pass.counters[tile], !first);
      // The next tile is claimed before this one's streamed stores: claiming is a locked
      // instruction, which waits until the streamed stores before it have drained.
      const size_t following = pass.tileWork.next(part);
      tiled::storeTile(scratch, depth, tiles[tile]);
      u = following;
    }
    tiled::finishResolves();
  });
  tiled::RasterCounters counters;
  for (size_t tile = 0; tile < size_t(bins.tileCount()); ++tile) counters.add(pass.counters[tile]);
  addPassStats(st, passStats, pass, counters);
}

// The vertex pass for the vertices of `meshes` (ascending; Scene::meshVerticesApart), in runs of
// about kChunkTriangles vertices: on the calling thread up to kSerialVertices (a few
// microseconds, less than handing them to the pool), on the pool beyond.
void OcclusionBuffer::Impl::transformVerticesOf(const Scene& scene, const std::vector<uint32_t>& meshes,
                                                FrontEndOutput& vertices) {
  constexpr size_t kSerialVertices = 8192;
  vertexRuns.clear();
  size_t total = 0;
  for (uint32_t m : meshes) {
    const MeshRange& mesh = scene.meshes[m];
    if (mesh.vertexCount == 0) continue;
    total += mesh.vertexCount;
    if (!vertexRuns.empty() && vertexRuns.back().end == mesh.firstVertex &&
        vertexRuns.back().end - vertexRuns.back().first < kChunkTriangles)
      vertexRuns.back().end += mesh.vertexCount;
    else
      vertexRuns.push_back({mesh.firstVertex, mesh.firstVertex + mesh.vertexCount});
  }
  auto run = [&](size_t i) {
    const TriangleRange& r = vertexRuns[i];
    transformVertices(scene.positions.data() + r.first, r.end - r.first, vertices.pixelFromWorld, camera,
                      vertices.outcodes.data() + r.first, vertices.projected.data() + r.first);
  };
  if (total > kSerialVertices)
    parallelFor(0, vertexRuns.size(), threads, run);
  else
    for (size_t i = 0; i < vertexRuns.size(); ++i) run(i);
}

namespace {
// The triangles of `meshes` (ascending) as ranges, neighbours joined.
void trianglesOf(const Scene& scene, const std::vector<uint32_t>& meshes, std::vector<TriangleRange>& ranges) {
  ranges.clear();
  for (uint32_t m : meshes) {
    const MeshRange& mesh = scene.meshes[m];
    if (mesh.triangleCount == 0) continue;
    if (!ranges.empty() && ranges.back().end == mesh.firstTriangle) ranges.back().end += mesh.triangleCount;
    else ranges.push_back({mesh.firstTriangle, mesh.firstTriangle + mesh.triangleCount});
  }
}
}  // namespace

// Draws the scene mesh by mesh, nearest first, dropping the meshes found hidden (see kMinMeshes).
void OcclusionBuffer::Impl::drawByMeshes(const Scene& scene, const RenderOptions& opt, Stats& st, bool forFrame) {
  Timer timer;
  algo::TiledState& first = state;
  // Every mesh in view bounded, within the vertex pass (each run of meshes once its view test is
  // done, on that worker: each writes its own entries).
  const size_t meshCount = scene.meshes.size();
  const MeshView view = meshView(camera, depth);
  tests.resize(meshCount);
  bounds.resize(meshCount);
  // When each mesh's vertices are its own (Scene::meshVerticesApart), only the vertices of the
  // meshes a pass draws are transformed, before its set-up (most of the city's are never).
  const bool byMesh = scene.meshVerticesApart;
  runVertexPass(
      scene, camera, opt, first.fe,
      [&](size_t firstMesh, size_t lastMesh) {
        meshBounds(scene, firstMesh, lastMesh, view, tests.data() + firstMesh, bounds.data() + firstMesh);
        for (size_t m = firstMesh; m < lastMesh; ++m)
          if (first.fe.meshCulled[m]) tests[m] = MeshTest::Outside;
      },
      !byMesh);
  FrontEndOutput& vertices = first.fe;
  // The meshes that draw nothing are left out (their triangles counted as set-up would: outside
  // the view); those without a bound are drawn first (they may hide others; nothing can show
  // them hidden); the others wait, nearest first.
  waiting.clear();
  drawn.clear();
  uint64_t outside = 0;
  for (size_t m = 0; m < meshCount; ++m) {
    const MeshRange& mesh = scene.meshes[m];
    if (tests[m] == MeshTest::Outside) outside += mesh.triangleCount;
    else if (tests[m] == MeshTest::None) drawn.push_back(uint32_t(m));
    else waiting.emplace_back(bounds[m].zMin, uint32_t(m));
  }
  st.culled_frustum += outside;
  culling.trianglesOutside = outside;
  const size_t perPass = std::max(kPassMeshes, waiting.size() / (forFrame ? kFramePassShare : kPassShare));
  uint64_t culledMeshes = 0, culledTriangles = 0;
  size_t p = 0;
  bool noPass = false;
  for (;; ++p) {
    // This pass's meshes: the nearest perPass waiting (all of them in the last pass).
    if (p + 1 == kMaxPasses || waiting.size() <= perPass) {
      for (const auto& w : waiting) drawn.push_back(w.second);
      waiting.clear();
    } else {
      std::nth_element(waiting.begin(), waiting.begin() + perPass, waiting.end());
      for (size_t i = 0; i < perPass; ++i) drawn.push_back(waiting[i].second);
      waiting.erase(waiting.begin(), waiting.begin() + perPass);
    }
    std::sort(drawn.begin(), drawn.end());
    if (forFrame && !waiting.empty()) {
      // For a frame, the first pass pays only when the meshes it may find hidden hold more
      // triangles than it draws (the frame draws its meshes again) — not when most meshes have
      // no bound — and enough of them for a tile pass over the whole image (kFrameWaitingPerTile).
      uint64_t drawnTriangles = 0, waitingTriangles = 0;
      for (uint32_t m : drawn) drawnTriangles += scene.meshes[m].triangleCount;
      for (const auto& w : waiting) waitingTriangles += scene.meshes[w.second].triangleCount;
      const uint64_t enough = kFrameWaitingPerTile * uint64_t(state.bins.tileCount());
      if (waitingTriangles <= drawnTriangles || waitingTriangles < enough) {
        for (const auto& w : waiting) drawn.push_back(w.second);
        waiting.clear();
        std::sort(drawn.begin(), drawn.end());
      }
    }
    if (forFrame && waiting.empty()) {  // nothing to test: no first pass
      firstDrawn.swap(drawn);
      drawn.clear();
      noPass = true;
      break;
    }
    if (byMesh) transformVerticesOf(scene, drawn, vertices);
    trianglesOf(scene, drawn, ranges);
    if (forFrame) firstDrawn.swap(drawn);
    drawn.clear();
    if (p > 0 && later.size() < p) later.resize(p);
    algo::TiledState& pass = p == 0 ? first : later[p - 1];
    algo::setUpAndBin(scene, camera, opt, depth, pass, &vertices, &ranges);
    st.addTime("frontend", timer.lap());
    tilePass(pass, p == 0, st);
    st.addTime("raster", timer.lap());
    if (waiting.empty()) break;
    // The meshes left, tested against what the kept tiles hold now (in parallel: each test reads
    // the tiles and writes its own entry only). Hidden now, hidden at the end. For a frame with
    // ids, hidden only behind values strictly nearer than its bound (a tie may be the mesh's).
    hidden.assign(waiting.size(), 0);
    constexpr size_t kTestsPerItem = 64;
    const int strict = forFrame ? 1 : 0;
    parallelFor(0, (waiting.size() + kTestsPerItem - 1) / kTestsPerItem, threads, [&](size_t item) {
      for (size_t i = item * kTestsPerItem, end = std::min(waiting.size(), i + kTestsPerItem); i < end; ++i) {
        const MeshBound& b = bounds[waiting[i].second];
        hidden[i] = !anyFarther(b.minX, b.minY, b.maxX, b.maxY, stepsNearer(b.nearest, strict));
      }
    });
    size_t kept = 0;
    for (size_t i = 0; i < waiting.size(); ++i) {
      if (hidden[i]) {
        ++culledMeshes;
        culledTriangles += scene.meshes[waiting[i].second].triangleCount;
      } else {
        waiting[kept++] = waiting[i];
      }
    }
    waiting.resize(kept);
    st.addTime("frontend", timer.lap());
    if (waiting.empty() || forFrame) break;
  }
  passes = noPass ? 0 : p + 1;
  if (forFrame) {
    // What the frame draws: the first pass's meshes and those left. The vertices of those left
    // are transformed here (without a first pass, none left: every mesh's).
    drawn.clear();
    for (const auto& w : waiting) drawn.push_back(w.second);
    if (passes == 0) drawn.swap(firstDrawn);
    std::sort(drawn.begin(), drawn.end());
    if (byMesh) transformVerticesOf(scene, drawn, vertices);
    drawn.insert(drawn.end(), firstDrawn.begin(), firstDrawn.end());
    std::sort(drawn.begin(), drawn.end());
    trianglesOf(scene, drawn, culling.ranges);
    drawn.clear();
    culling.vertices = &vertices;
    culling.meshesCulled = culledMeshes;
    culling.passes = passes + 1;  // (and the frame's)
    culling.trianglesCulled = culledTriangles;
  }
  st.setDetail("occlusion_passes", passes);
  st.setDetail("meshes_culled_occlusion", culledMeshes);
  st.setDetail("triangles_culled_occlusion", culledTriangles);
}

// A render's start: the camera, depth setup and thread count; the statistics begun; the kept
// tiles sized for the image (the bins' geometry, which every pass shares). Returns the passes'
// options (depth only).
RenderOptions OcclusionBuffer::Impl::start(const Scene& scene, const Camera& cam, const OcclusionOptions& options) {
  RenderOptions opt;
  opt.depthFormat = options.depthFormat;
  opt.cull = options.cull;
  opt.threads = options.threads;
  opt.tiled = options.tiled;
  opt.outputs = FrameOutputs::DepthOnly;
  algo::beginStats(stats, scene, cam);
  threads = resolveThreads(opt.threads);
  camera = cam;
  depth = DepthSetup{opt.depthFormat, cam.near, cam.far, cam.orthographic};
  tiled::prepareBins(state.bins, cam.width, cam.height, 0);
  const size_t count = size_t(state.bins.tileCount());
  if (tileCapacity < count) {
    tiles.reset(new tiled::KeptTile[count]);  // default-initialised: see Impl::tiles
    tileCapacity = count;
  }
  return opt;
}

const algo::MeshCulling& algo::cullMeshes(OcclusionBuffer& buffer, const Scene& scene, const Camera& camera,
                                          const RenderOptions& options) {
  OcclusionBuffer::Impl& im = *buffer.impl_;
  im.width = im.height = 0;  // holds the first pass only: not to be queried
  const RenderOptions opt = im.start(scene, camera, {options.depthFormat, options.cull, options.threads, options.tiled});
  Stats& st = im.stats;
  im.drawByMeshes(scene, opt, st, true);
  im.culling.depthTests = st.depth_tests;
  im.culling.depthWrites = st.depth_writes;
  im.culling.memoryBytes = im.memoryBytes();
  return im.culling;
}

const Stats& OcclusionBuffer::render(const Scene& scene, const Camera& camera, const OcclusionOptions& options) {
  Impl& im = *impl_;
  im.width = im.height = 0;  // nothing to query, until the pass below has completed
  algo::checkImage(camera, options.depthFormat);
  Timer total, timer;
  const RenderOptions opt = im.start(scene, camera, options);
  Stats& st = im.stats;
  if (algo::meshCullingApplies(scene, camera, opt.tiled)) {
    im.drawByMeshes(scene, opt, st);
  } else {
    algo::setUpAndBin(scene, camera, opt, im.depth, im.state);
    st.addTime("frontend", timer.lap());
    im.tilePass(im.state, true, st);
    st.addTime("raster", timer.lap());
    im.passes = 1;
  }

  st.algorithm = "occlusion";
  st.depth_format = opt.depthFormat.name();
  st.addMemory("occlusion_buffer", im.memoryBytes());
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
  // Segments of up to kSegmentTiles tiles of a tile row, as render() resolves them: each kept
  // tile unpacked into the task's scratch, then the segment written band by band across its
  // tiles (long row pieces, not 64-pixel ones). The scratch is the buffer's own, kept from call
  // to call, unless another thread is querying the buffer meanwhile: then this call's own.
  constexpr int kSegmentTiles = 8, kBand = 8;
  const int segmentsX = (bins.tilesX + kSegmentTiles - 1) / kSegmentTiles;
  const size_t segments = size_t(segmentsX) * size_t(bins.tilesY);
  const int workers = int(std::min<size_t>(segments, size_t(im.threads)));
  std::unique_lock lock(im.resolveMutex, std::try_to_lock);
  std::vector<tiled::TileScratch> ownScratch;
  std::vector<uint64_t> ownCovered;
  WorkQueue ownWork;
  const bool kept = lock.owns_lock();
  std::vector<tiled::TileScratch>& scratch = kept ? im.resolveScratch : ownScratch;
  std::vector<uint64_t>& covered = kept ? im.resolveCovered : ownCovered;
  WorkQueue& work = kept ? im.resolveWork : ownWork;
  if (scratch.size() < size_t(workers) * kSegmentTiles) scratch.resize(size_t(workers) * kSegmentTiles);
  covered.assign(size_t(workers), 0);
  work.reset(segments, size_t(workers));
  parallelFor(0, size_t(workers), workers, [&](size_t worker) {
    tiled::TileScratch* mine = scratch.data() + worker * kSegmentTiles;
    const size_t part = currentPart();
    for (size_t seg = work.next(part); seg < segments; seg = work.next(part)) {
      const int ty = int(seg) / segmentsX, tx0 = (int(seg) % segmentsX) * kSegmentTiles;
      const int count = std::min(kSegmentTiles, bins.tilesX - tx0), first = ty * bins.tilesX + tx0;
      for (int i = 0; i < count; ++i) tiled::loadTile(im.tiles[size_t(first + i)], im.depth, mine[i]);
      for (int row = 0; row < tiled::kTileSize; row += kBand)
        for (int i = 0; i < count; ++i)
          covered[worker] += tiled::resolveStoredDepth(bins, first + i, im.depth, mine[i], frame, row, row + kBand);
    }
    tiled::finishResolves();
  });
  for (uint64_t c : covered) frame.stats.covered_pixels += c;
}

}  // namespace hsr

// The production z-buffer (--param raster=tiled, the default): the textbook z-buffer's fragments
// (zbuffer.cpp), compared and stored with the same arithmetic, but binned into tiles that threads
// own whole, each tile's triangles visited nearest first (a tie goes to the triangle submitted
// first, so the image is the submission order's), rasterized with SIMD (raster/tiled.hpp), with
// early rejection of triangles behind a tile's or block's farthest stored depth, whole tiles and
// blocks replaced at once by a triangle in front of all they hold, and colour, ids and depth
// resolved per tile into a frame that is never cleared separately. Bit-identical images with
// less work: its depth_tests and depth_writes count what it did (fewer than the textbook's).
#include <algorithm>
#include <bit>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <hsr/occlusion.hpp>

#include "algorithms/algorithms.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "scene/shading.hpp"
#include "core/timer.hpp"
#include "frontend/frontend.hpp"
#include "raster/tiled.hpp"
#include "algorithms/tiled_pass.hpp"

namespace hsr::algo {
namespace {

struct Counters {
  uint64_t covered = 0;
};

// Whether a frame is drawn after mesh culling: many meshes and enough triangles. Scenes of fewer
// triangles skip it: the kept tiles' extra pass costs more than culling saves there
// (docs/benchmarks.md).
bool cullsByMeshes(const Scene& scene, const Camera& cam, const RenderOptions& opt) {
  constexpr size_t kByMeshesTriangles = 8192;
  return scene.triangles.size() >= kByMeshesTriangles && meshCullingPaysForFrame(scene, cam, opt.tiled);
}

// ---------------------------------------------------------------------------------------------
// The tiled path (its state, front end and binning shared with the occlusion buffer: tiled_pass.hpp).

// A worker's unit: up to 8 tiles side by side (512 pixels), resolved 8 rows at a time across
// them, so that the frame is written in long row pieces (docs/benchmarks.md).
constexpr int kSegmentTiles = 8;
constexpr int kResolveBand = 8;

// The background of a frame's idle segments (nothing binned in any of their tiles), shared by
// the workers' pumps (tiled::BackgroundPump): each claims a whole segment and streams it, row by
// row and buffer by buffer, a few lines at a time while it rasterizes other segments.
struct IdleSegments {
  const Frame* frame = nullptr;
  uint32_t* buffers[4] = {};  // the frame's buffers of the outputs asked for ...
  uint32_t values[4] = {};    // ... and their background values
  int bufferCount = 0, segmentsX = 0;
  const std::vector<uint32_t>* list = nullptr;
  std::atomic<size_t> next{0};  // the next segment of `list` to claim
};

// The next piece of a pump's background: row cursor[1] of segment cursor[0] (-1: claim one), in
// buffer cursor[2].
bool nextIdlePiece(tiled::BackgroundPump& p) {
  IdleSegments& idle = *static_cast<IdleSegments*>(p.context);
  const Frame& frame = *idle.frame;
  int& segment = p.cursor[0];
  int& row = p.cursor[1];
  int& buffer = p.cursor[2];
  for (;;) {
    if (segment < 0) {
      const size_t i = idle.next.fetch_add(1, std::memory_order_relaxed);
      if (i >= idle.list->size()) return false;
      segment = int((*idle.list)[i]);
      row = 0;
      buffer = 0;
    }
    const int ty = segment / idle.segmentsX, tx0 = (segment % idle.segmentsX) * kSegmentTiles;
    const int x0 = tx0 * tiled::kTileSize, x1 = std::min(x0 + kSegmentTiles * tiled::kTileSize, frame.width);
    const int y = ty * tiled::kTileSize + row;
    if (row >= tiled::kTileSize || y >= frame.height) {
      segment = -1;
      continue;
    }
    const bool lines = p.setPiece(idle.buffers[buffer] + frame.index(x0, y), size_t(x1 - x0), idle.values[buffer]);
    if (++buffer == idle.bufferCount) buffer = 0, ++row;
    if (lines) return true;
  }
}

// Rasterizes and resolves the binned frame in segments of up to kSegmentTiles tiles of one
// tile row: a worker rasterizes each tile of its segment into its own scratch, then resolves the
// segment band by band across its tiles, so that the frame is written in long row pieces (see
// tiled::resolveTile). Each tile has one owner, so no locks; counters are kept per tile and
// summed in tile order. Segments with nothing binned are not units: the workers' pumps stream
// their background while the others are rasterized (IdleSegments; off with the switch
// background-pump, the same bits; its effect: docs/benchmarks.md).
void drawTiled(const RenderOptions& opt, const DepthSetup& depth, const TriangleShader& shade, Frame& frame,
               TiledState& state, Counters& n, tiled::RasterCounters& total) {
  const tiled::Bins& bins = state.bins;
  const int segmentsX = (bins.tilesX + kSegmentTiles - 1) / kSegmentTiles;
  const size_t allSegments = size_t(segmentsX) * size_t(bins.tilesY);
  const int workers = std::min(prepareTilePass(state, resolveThreads(opt.threads)), int(allSegments));
  if (state.scratch.size() < size_t(workers) * kSegmentTiles) state.scratch.resize(size_t(workers) * kSegmentTiles);
  std::vector<uint32_t>& busy = state.busySegments;
  std::vector<uint32_t>& idleList = state.idleSegments;
  busy.clear();
  idleList.clear();
  const bool pump = opt.tiled.backgroundPump;
  for (size_t seg = 0; seg < allSegments; ++seg) {
    const int ty = int(seg) / segmentsX, tx0 = (int(seg) % segmentsX) * kSegmentTiles;
    bool idle = pump;
    for (int t = ty * bins.tilesX + tx0, end = t + std::min(kSegmentTiles, bins.tilesX - tx0); idle && t < end; ++t)
      idle = bins.entries(t) == 0 && bins.entries(t, true) == 0;
    (idle ? idleList : busy).push_back(uint32_t(seg));
  }
  IdleSegments idle;
  idle.frame = &frame;
  idle.segmentsX = segmentsX;
  idle.list = &idleList;
  auto addBuffer = [&](void* buffer, uint32_t value) {
    idle.buffers[idle.bufferCount] = static_cast<uint32_t*>(buffer);
    idle.values[idle.bufferCount++] = value;
  };
  addBuffer(frame.depth.data(), std::bit_cast<uint32_t>(std::numeric_limits<float>::infinity()));
  if (has(opt.outputs, FrameOutputs::FaceIds)) addBuffer(frame.faceId.data(), std::bit_cast<uint32_t>(int32_t(-1)));
  if (has(opt.outputs, FrameOutputs::TriangleIds))
    addBuffer(frame.triangleId.data(), std::bit_cast<uint32_t>(int32_t(-1)));
  if (has(opt.outputs, FrameOutputs::Color)) addBuffer(frame.color.data(), std::bit_cast<uint32_t>(opt.background));
  const size_t units = busy.size();
  assignUnits(state, workers, units, [&](size_t unit) {
    const int ty = int(busy[unit]) / segmentsX, tx0 = (int(busy[unit]) % segmentsX) * kSegmentTiles;
    return std::pair(ty * bins.tilesX + tx0, std::min(kSegmentTiles, bins.tilesX - tx0));
  });
  parallelFor(0, size_t(workers), workers, [&](size_t worker) {
    tiled::TileScratch* scratch = state.scratch.data() + worker * kSegmentTiles;
    const size_t part = currentPart();  // (segments whose records this thread set up come first)
    tiled::BackgroundPump background;
    background.done = idleList.empty();
    background.refill = nextIdlePiece;
    background.context = &idle;
    for (size_t unit = state.tileWork.next(part), following = 0; unit < units; unit = following) {
      const int ty = int(busy[unit]) / segmentsX, tx0 = (int(busy[unit]) % segmentsX) * kSegmentTiles;
      const int count = std::min(kSegmentTiles, bins.tilesX - tx0), first = ty * bins.tilesX + tx0;
      for (int i = 0; i < count; ++i) {
        // (ids kept for depth only too: a pixel's depth is its winner's plane, whatever the outputs)
        tiled::rasterizeTile(bins, first + i, depth, true, scratch[i], state.orders[worker],
                             state.counters[size_t(first + i)], false, &background);
        tiled::prepareResolve(bins, first + i, opt.outputs, &shade, opt.background, scratch[i], &background);
      }
      // The next segment is claimed before this one's frame writes: a locked read-modify-write
      // waits until every streaming store before it has drained to memory.
      following = state.tileWork.next(part);
      for (int row = 0; row < tiled::kTileSize; row += kResolveBand)
        for (int i = 0; i < count; ++i)
          state.covered[size_t(first + i)] += tiled::resolveTile(bins, first + i, depth, opt.outputs, &shade,
                                                                 opt.background, scratch[i], frame, row, row + kResolveBand);
    }
    tiled::drainBackground(background);  // (the idle segments no pump has claimed yet, too)
    tiled::finishResolves();
  });
  for (int tile = 0; tile < bins.tileCount(); ++tile) {
    total.add(state.counters[size_t(tile)]);
    n.covered += state.covered[size_t(tile)];
  }
}

}  // namespace

// What the tiled z-buffer keeps from one frame to the next: its bins and tile buffers, and the
// occlusion buffer of mesh culling.
struct TiledZBuffer::State {
  TiledState tiles;
  OcclusionBuffer occluders;
};

TiledZBuffer::TiledZBuffer() = default;
TiledZBuffer::~TiledZBuffer() = default;

void TiledZBuffer::draw(const Scene& scene, const Camera& cam, const RenderOptions& opt, Frame& frame) {
  Timer timer;
  Stats& st = frame.stats;
  Counters n;
  tiled::RasterCounters tiledCounters;
  if (!state_) state_ = std::make_unique<State>();
  TiledState& state = state_->tiles;
  const TriangleShader shade(scene, cam, opt.shading);  // back faces' colour, when they show
  st.setDetail("rasterizer", "tiled");
  st.depth_format = opt.depthFormat.name();

  // Many meshes and enough triangles: mesh culling (docs/occlusion.md) through the occlusion
  // buffer this object keeps: the buffer's first pass, then this path's frame of the meshes not
  // found hidden (algo::cullMeshes), when it pays (cullsByMeshes).
  const bool byMeshes = cullsByMeshes(scene, cam, opt);
  OcclusionBuffer& occluders = state_->occluders;
  const DepthSetup depth{opt.depthFormat, cam.near, cam.far, cam.orthographic};
  const MeshCulling* culling = nullptr;
  if (byMeshes) {
    culling = &cullMeshes(occluders, scene, cam, opt);
    setUpAndBin(scene, cam, opt, depth, state, culling->vertices, &culling->ranges);
  } else {
    setUpAndBin(scene, cam, opt, depth, state);
  }
  st.addTime("frontend", timer.lap());
  drawTiled(opt, depth, shade, frame, state, n, tiledCounters);
  st.addTime("raster", timer.lap());

  tiledStats(st, state.fe, &state.bins, tiledCounters);
  // Fragments that won the depth test: each writes the colour in the textbook z-buffer; this
  // path writes the winner's id instead and its colour once per pixel at resolve (deferred),
  // counted like the textbook's, one per winning fragment.
  st.color_writes = has(opt.outputs, FrameOutputs::Color) ? st.depth_writes : 0;
  if (culling) {  // the first pass's tests and writes too (depth only: no colour)
    st.depth_tests += culling->depthTests;
    st.depth_writes += culling->depthWrites;
    st.culled_frustum += culling->trianglesOutside;
    st.setDetail("occlusion_passes", culling->passes);
    st.setDetail("meshes_culled_occlusion", culling->meshesCulled);
    st.setDetail("triangles_culled_occlusion", culling->trianglesCulled);
  }
  st.covered_pixels = n.covered;
  st.addMemory("tiled_state", state.memoryBytes());
  if (culling) st.addMemory("occlusion_buffer", culling->memoryBytes);
  st.addMemory("front_end", state.fe.memoryBytes());
  addFrameMemory(st, frame);
}

const std::vector<TriangleRange>* TiledZBuffer::visibleMeshes(const Scene& scene, const Camera& cam,
                                                             const RenderOptions& opt, uint64_t& meshesCulled) {
  meshesCulled = 0;
  if (!cullsByMeshes(scene, cam, opt)) return nullptr;
  if (!state_) state_ = std::make_unique<State>();
  const MeshCulling& culling = cullMeshes(state_->occluders, scene, cam, opt);
  meshesCulled = culling.meshesCulled;
  return &culling.ranges;
}

const DepthSetup TiledZBuffer::kPriorityDepth{DepthFormat{DepthStorage::F32, DepthMapping::Linear}, 0.0, 1.0, false};

double TiledZBuffer::setPriority(SetupTriangle& t, size_t k) {
  const double value = double(k + 1) * 0x1p-24;
  t.depthNum = Plane{0, 0, value};
  t.depthDen = Plane{0, 0, 1};
  return value;
}

TiledZBuffer::InOrderCounts TiledZBuffer::drawInOrder(std::span<const SetupTriangle> triangles, bool firstWins,
                                                      const Camera& cam, const RenderOptions& opt,
                                                      const TriangleShader& shade, Frame& frame) {
  if (firstWins && triangles.size() > kMostFirstWins)
    throw std::length_error("drawInOrder: more triangles than priority keys");
  if (!state_) state_ = std::make_unique<State>();
  TiledState& state = state_->tiles;
  const DepthSetup depth = firstWins ? kPriorityDepth : DepthSetup{opt.depthFormat, cam.near, cam.far, cam.orthographic};

  // The list cut into front-end chunks, drawn as copies: triangle k of the list is scene triangle
  // k of its chunk (so the kernel's keys are the list's order), on the priority keys' planes when
  // firstWins; each chunk binned by the worker that copied it.
  FrontEndOutput& fe = state.fe;
  const size_t perChunk = kChunkTriangles, chunks = (triangles.size() + perChunk - 1) / perChunk;
  if (fe.chunks.size() < chunks) fe.chunks.resize(chunks);
  fe.chunkCount = chunks;
  fe.chunkTriangles = perChunk;
  tiled::Bins& bins = state.bins;
  tiled::prepareBins(bins, cam.width, cam.height, chunks);
  bins.resolveRecords.assign(2 * chunks, nullptr);
  parallelFor(0, chunks, resolveThreads(opt.threads), [&](size_t c) {
    FrontEndChunk& chunk = fe.chunks[c];
    const size_t first = c * perChunk, count = std::min(perChunk, triangles.size() - first);
    chunk.firstTriangle = uint32_t(first);
    chunk.triangles.assign(triangles.begin() + ptrdiff_t(first), triangles.begin() + ptrdiff_t(first + count));
    chunk.nearest.resize(count);
    chunk.deferred.clear();
    chunk.clusters.clear();
    chunk.counters = {};
    for (size_t k = 0; k < count; ++k) {
      SetupTriangle& t = chunk.triangles[k];
      t.triangle = uint32_t(first + k);
      // (a constant plane's nearest bound is its value: its margins round back to it in f32)
      chunk.nearest[k] = firstWins ? setPriority(t, first + k) : nearestStored(t, depth);
      if (t.maxX - t.minX + 1 >= kLargeBoxPixels && t.maxY - t.minY + 1 >= kLargeBoxPixels) ++chunk.counters.large;
    }
    bins.chunks[c].producer = uint32_t(currentPart());
    tiled::binChunk(bins, c, chunk, &depth);
    bins.resolveRecords[2 * c] = triangles.data() + first;
  });
  bins.projected = nullptr;  // (nothing deferred: no set-up in the tile pass)
  bins.camera = &cam;
  bins.sceneTriangles = nullptr;

  Counters n;
  tiled::RasterCounters counters;
  drawTiled(opt, depth, shade, frame, state, n, counters);
  bins.resolveRecords.clear();
  return {counters.depthTests, counters.depthWrites, counters.culledTiles, n.covered,
          state.memoryBytes() + fe.memoryBytes()};
}

}  // namespace hsr::algo

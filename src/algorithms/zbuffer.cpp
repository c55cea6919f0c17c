// The z-buffer (documents 000, 001, 003, 004). Two implementations of one algorithm:
//  - the textbook reference every fast path is checked against (--raster halfspace|scanline):
//    a depth buffer and a frame buffer of the image's size; depth cleared to "far", colour to
//    the background; every fragment of every triangle, in submission order, is compared with
//    the stored depth and, when strictly nearer, overwrites depth, colour and the triangle id;
//    a resolve pass then turns triangle ids into face ids and exact eye depths;
//  - the default, tiled (raster/tiled.hpp): the same fragments, compared and stored with the
//    same arithmetic, but binned into tiles that threads own whole, each tile's triangles
//    visited nearest first (a tie goes to the triangle submitted first, so the image is the
//    submission order's), rasterized with SIMD, with early rejection of triangles behind a
//    tile's or block's farthest stored depth, whole tiles and blocks replaced at once by a
//    triangle in front of all they hold, and colour, ids and depth resolved per tile into a
//    frame that is never cleared separately. Bit-identical results, with less work: its
//    depth_tests and depth_writes count what it did (fewer than the reference's).
#include <algorithm>
#include <bit>
#include <atomic>
#include <cmath>
#include <limits>

#include <hsr/occlusion.hpp>

#include "algorithms/algorithms.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "core/shading.hpp"
#include "core/timer.hpp"
#include "frontend/frontend.hpp"
#include "raster/fragment_depth.hpp"
#include "raster/halfspace.hpp"
#include "raster/scanline.hpp"
#include "raster/tiled.hpp"
#include "algorithms/tiled_pass.hpp"

namespace hsr::algo {
namespace {

struct Counters {
  uint64_t tests = 0, writes = 0, covered = 0;
};

// ---------------------------------------------------------------------------------------------
// The reference: one frame for depth storage S and mapping M, fragment by fragment.
template <DepthStorage S, DepthMapping M>
void drawReference(const std::vector<SetupTriangle>& tris, const Camera& cam, const RenderOptions& opt,
                   const TriangleShader& shade, Frame& frame, Counters& n, uint64_t& bufferBytes) {
  using T = DepthT<S>;
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  const double n0 = cam.near, f0 = cam.far;
  const bool ortho = cam.orthographic;
  const bool color = has(opt.outputs, FrameOutputs::Color), ids = opt.outputs != FrameOutputs::DepthOnly;
  const bool faceIds = has(opt.outputs, FrameOutputs::FaceIds), triangleIds = has(opt.outputs, FrameOutputs::TriangleIds);
  const T clear = quantizeDepth<S>(opt.depthFormat.clearValue());
  frame.clear(opt.background, resolveThreads(opt.threads));
  std::vector<T> zbuf(size_t(cam.width) * cam.height, clear);
  std::vector<uint32_t> triOf(ids ? zbuf.size() : 0, 0);  // 0 = nothing drawn, else index + 1
  bufferBytes = zbuf.size() * sizeof(T) + triOf.size() * sizeof(uint32_t);
  for (uint32_t i = 0; i < tris.size(); ++i) {
    const SetupTriangle& t = tris[i];
    const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, n0, f0, ortho);
    auto fragment = [&](int x, int y, double eyeDepth) {
      // Half-space: the stored value from the pixel centre (raster/fragment_depth.hpp), which
      // the tiled rasterizer reproduces bit for bit. Scanline (003): the eye depth it stepped
      // along the span, mapped.
      const T z = opt.raster == RasterKind::Scanline
                      ? quantizeDepth<S>(mapDepth<M>(eyeDepth, n0, f0, ortho))
                      : T(fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5)));
      const size_t idx = size_t(y) * size_t(cam.width) + size_t(x);
      ++n.tests;
      if (greater ? z > zbuf[idx] : z < zbuf[idx]) {  // strictly nearer: ties keep the first
        zbuf[idx] = z;
        if (ids) triOf[idx] = i + 1;
        ++n.writes;
      }
    };
    if (opt.raster == RasterKind::Scanline) rasterizeScanline(t, fragment);
    else rasterizeHalfSpace(t, fragment);
  }

  // Resolve: face id, colour and exact eye depth (from the winning triangle's plane) per pixel;
  // depth only: the eye depth of the stored value. (Colour is that of the last fragment written,
  // i.e. the winner's: writing it here, once, gives the same image.)
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const size_t idx = frame.index(x, y);
      if (!ids) {
        if (zbuf[idx] == clear) continue;
        frame.depth[idx] = float(eyeDepthOfStored<S, M>(double(zbuf[idx]), n0, f0, ortho));
      } else {
        if (!triOf[idx]) continue;
        const SetupTriangle& t = tris[triOf[idx] - 1];
        if (faceIds) frame.faceId[idx] = int32_t(t.face);
        if (triangleIds) frame.triangleId[idx] = int32_t(t.triangle);
        frame.depth[idx] = float(t.eyeDepth(x + 0.5, y + 0.5));
        if (color) frame.color[idx] = triangleColor(t, shade);
      }
      ++n.covered;
    }
}

// ---------------------------------------------------------------------------------------------
// The tiled path (its state, front end and binning shared with the occlusion buffer: tiled_pass.hpp).

// A worker's unit: up to 8 tiles side by side (512 pixels), resolved 8 rows at a time across
// them. Measured writing 1920x1080x4 buffers in this order: 5.4 ms, vs 27 ms tile by tile.
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
// their background while the others are rasterized (IdleSegments; off with
// HSR_BACKGROUND_PUMP=off, the same bits) — cubes frame 0.91x the time with 2 threads, 0.87x
// with one; random 0.99x; city, layers and sphere unchanged.
void drawTiled(const RenderOptions& opt, const DepthSetup& depth, const TriangleShader& shade, Frame& frame,
               TiledState& state, Counters& n, tiled::RasterCounters& total) {
  const tiled::Bins& bins = state.bins;
  const int segmentsX = (bins.tilesX + kSegmentTiles - 1) / kSegmentTiles;
  const size_t allSegments = size_t(segmentsX) * size_t(bins.tilesY);
  const int workers = std::min(prepareTilePass(state, resolveThreads(opt.threads)), int(allSegments));
  if (state.scratch.size() < size_t(workers) * kSegmentTiles) state.scratch.resize(size_t(workers) * kSegmentTiles);
  const bool ids = opt.outputs != FrameOutputs::DepthOnly;
  std::vector<uint32_t>& busy = state.busySegments;
  std::vector<uint32_t>& idleList = state.idleSegments;
  busy.clear();
  idleList.clear();
  const bool pump = !switchedOff("HSR_BACKGROUND_PUMP");
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
        tiled::rasterizeTile(bins, first + i, depth, ids, scratch[i], state.orders[worker],
                             state.counters[size_t(first + i)], false, &background);
        if (ids)
          tiled::prepareResolve(bins, first + i, opt.outputs, &shade, opt.background, scratch[i], &background);
      }
      // The next segment is claimed before this one's frame writes: a locked read-modify-write
      // waits until every streaming store before it has drained to memory (claimed after them,
      // each segment's writes stalled the worker; claimed here, city frames take 0.89-0.92 of
      // the time, other scenes the same).
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

void zbuffer(const Scene& scene, const Camera& cam, const RenderOptions& opt, Frame& frame) {
  Timer timer;
  Stats& st = frame.stats;
  Counters n;
  tiled::RasterCounters tiledCounters;
  uint64_t bufferBytes = 0;
  // The tiled path's buffers, kept for the next frame by the calling thread. (Used through this
  // reference: in a lambda run by a pool worker, the name would denote the worker's own copy.)
  thread_local TiledState callerState;
  TiledState& state = callerState;
  FrontEndOutput referenceFe;
  const bool isTiled = opt.raster == RasterKind::Tiled;
  const TriangleShader shade(scene, cam, opt.shading);  // back faces' colour, when they show
  FrontEndOutput& fe = isTiled ? state.fe : referenceFe;

  // Many meshes and enough triangles: mesh culling (docs/occlusion.md), through an occlusion
  // buffer kept by the calling thread. Depth only: the buffer's passes, then its depth image (bit
  // for bit this path's); city 1.08x. With ids: the buffer's first pass, then this path's frame
  // of the meshes not found hidden (algo::cullMeshes). On the 64 stacked layers (128 triangles)
  // the kept tiles' extra pass cost more than culling saved (depth only 0.89x), hence the
  // triangle count.
  constexpr size_t kByMeshesTriangles = 8192;
  const bool depthOnly = opt.outputs == FrameOutputs::DepthOnly;
  const bool byMeshes = isTiled && scene.triangles.size() >= kByMeshesTriangles &&
                        (depthOnly ? meshCullingApplies(scene, cam) : meshCullingPaysForFrame(scene, cam));
  thread_local OcclusionBuffer callerOccluders;
  OcclusionBuffer& occluders = callerOccluders;
  if (byMeshes && depthOnly) {
    occluders.render(scene, cam, {opt.depthFormat, opt.cull, opt.threads});
    timer.lap();
    occluders.depthImage(frame);  // (its statistics: the buffer's, and covered_pixels)
    std::erase_if(st.time_ms, [](const auto& stage) { return stage.first == "total"; });
    st.addTime("resolve", timer.lap());
    st.algorithm = "zbuffer";
    st.color_writes = 0;
    st.memory_bytes += frame.depth.size() * sizeof(float);
    return;
  }
  const MeshCulling* culling = nullptr;
  if (isTiled) {
    const DepthSetup depth{opt.depthFormat, cam.near, cam.far, cam.orthographic};
    if (byMeshes) {
      culling = &cullMeshes(occluders, scene, cam, opt);
      setUpAndBin(scene, cam, opt, depth, state, culling->vertices, &culling->ranges);
    } else {
      setUpAndBin(scene, cam, opt, depth, state);
    }
    st.addTime("frontend", timer.lap());
    drawTiled(opt, depth, shade, frame, state, n, tiledCounters);
    st.addTime("raster", timer.lap());
    bufferBytes = state.memoryBytes();
    if (culling) bufferBytes += culling->memoryBytes;
  } else {
    runFrontEnd(scene, cam, opt, fe);
    const std::vector<SetupTriangle> tris = fe.flatten();
    st.addTime("frontend", timer.lap());
    visitDepthFormat(opt.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
      drawReference<S, M>(tris, cam, opt, shade, frame, n, bufferBytes);
    });
    bufferBytes += tris.capacity() * sizeof(SetupTriangle);
    st.addTime("raster", timer.lap());
  }

  st.algorithm = "zbuffer";
  st.depth_format = opt.depthFormat.name();
  if (!isTiled) {  // the reference's counts, in the tile pass's fields
    tiledCounters.depthTests = n.tests;
    tiledCounters.depthWrites = n.writes;
  }
  tiledStats(st, fe, isTiled ? &state.bins : nullptr, tiledCounters);
  // Fragments that won the depth test: each writes the colour in the reference; the tiled path
  // writes the winner's id instead and its colour once per pixel at resolve (deferred), counted
  // like the reference, one per winning fragment.
  st.color_writes = has(opt.outputs, FrameOutputs::Color) ? st.depth_writes : 0;
  if (culling) {  // the first pass's tests and writes too (depth only: no colour)
    st.depth_tests += culling->depthTests;
    st.depth_writes += culling->depthWrites;
    st.culled_frustum += culling->trianglesOutside;
    st.occlusion_passes = culling->passes;
    st.meshes_culled_occlusion = culling->meshesCulled;
    st.triangles_culled_occlusion = culling->trianglesCulled;
  }
  st.covered_pixels = n.covered;
  const uint64_t frameBytes = frame.depth.size() * sizeof(float) + frame.faceId.size() * sizeof(int32_t) +
                              frame.triangleId.size() * sizeof(int32_t) + frame.color.size() * sizeof(Rgba8);
  st.memory_bytes = bufferBytes + frameBytes + fe.memoryBytes();
}

}  // namespace hsr::algo

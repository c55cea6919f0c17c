// What the tiled z-buffer (zbuffer.cpp) and the occlusion buffer (occlusion.cpp) share: the
// state the tiled path keeps from frame to frame, the front end with binning, the choice of how
// many workers a tile pass is worth, and the statistics of the tile pass.
#pragma once
#include <hsr/frame.hpp>
#include <hsr/options.hpp>

#include <algorithm>
#include <vector>

#include "core/parallel.hpp"
#include "frontend/frontend.hpp"
#include "raster/tiled.hpp"

namespace hsr::algo {

/// Everything the tiled path needs from frame to frame, kept by its owner so that a warm frame
/// allocates nothing: the front end's output, the bins, the workers' tile scratch (the occlusion
/// buffer stores each tile from there into its own kept tiles) and visit lists, the per-tile
/// counters.
struct TiledState {
  FrontEndOutput fe;
  tiled::Bins bins;
  std::vector<tiled::TileScratch> scratch;
  std::vector<tiled::TileOrder> orders;         // per worker
  std::vector<tiled::RasterCounters> counters;  // per tile
  std::vector<uint64_t> covered;                // per tile
  WorkQueue tileWork;                           // the tile pass's units, per worker (assignUnits)
  std::vector<uint32_t> unitOwner, unitOrder;   // scratch of assignUnits
  std::vector<size_t> unitBounds, recordsByPart, partRecords;
  std::vector<uint32_t> busySegments, idleSegments;  // scratch of the z-buffer's tile pass (zbuffer.cpp)
  uint64_t memoryBytes() const;
};

/// Whether a frame defers its back faces (raster/tiled.hpp, binChunk): when it draws both sides
/// (cull none) and the switch is on (RenderOptions::tiled; the image is the same bits either way).
/// Whole clusters that face away go too unless TiledSwitches::deferClusters is off.
bool deferBackFaces(const RenderOptions& opt);

/// Sets up the scene's triangles (runFrontEnd) and bins each chunk on the worker that set it up,
/// while it is in that core's cache.
/// With `vertices` (the frame's vertex pass, runVertexPass), set-up only, of the triangles of
/// `only` (runSetUp), into state.fe's chunks.
void setUpAndBin(const Scene& scene, const Camera& cam, const RenderOptions& opt, const DepthSetup& depth,
                 TiledState& state, const FrontEndOutput* vertices = nullptr,
                 const std::vector<TriangleRange>* only = nullptr);

/// Mesh culling for render()'s frames with ids (zbuffer.cpp): the occlusion buffer's first pass
/// of mesh culling (occlusion.cpp) drawn depth only into its kept tiles, every other mesh tested
/// against them, and what is left to draw. A mesh is dropped only if every pixel of its box stores
/// a value strictly nearer than any fragment of it can be (a tie may go to the mesh submitted
/// first, so ties are not dropped): each pixel's nearest fragment, and the first submitted among
/// equals, is then the same with it or without it — the same image, bit for bit.
struct MeshCulling {
  /// The vertex pass (runVertexPass) of every mesh in `ranges`, for runSetUp.
  const FrontEndOutput* vertices = nullptr;
  /// The triangles of every mesh neither outside the view nor hidden, ascending.
  std::vector<TriangleRange> ranges;
  uint64_t meshesCulled = 0, trianglesCulled = 0;  // hidden
  uint64_t trianglesOutside = 0;                   // of the meshes outside the view (culled_frustum)
  uint64_t depthTests = 0, depthWrites = 0;        // the first pass's
  uint64_t memoryBytes = 0;                        // the occlusion buffer's
  uint64_t passes = 0;                             // tile passes: the first (if drawn) and the frame's
};

/// How many workers the binned frame's tile pass is worth (at most `threads`; a frame of one
/// tile with few triangles runs on one, as handing work to a pool thread costs about as much as
/// the kernel spends on ~4000 small triangles; each tile is worth a worker), with one visit list
/// each, and the per-tile counters cleared.
/// With `touched`: a pass over only the tiles that have items, listed there in order.
int prepareTilePass(TiledState& state, int threads, std::vector<uint32_t>* touched = nullptr);

/// Hands the tile pass's `units` to its `workers` (state.tileWork, parts [0, workers)): unit u is
/// the tiles [tilesOf(u).first, + tilesOf(u).second) of one tile row; each goes first to the
/// worker whose part set up most of the records binned there (ChunkBins::producer: they are in
/// its core's caches), then to whoever is free; units with no records (only the frame's
/// background to write) go to the part that set up the fewest. (Any assignment gives the same
/// image.)
template <class TilesOf>
void assignUnits(TiledState& state, int workers, size_t units, TilesOf&& tilesOf);

/// The statistics every tiled pass reports (docs/conventions.md keys): the front end's counts and the
/// tile pass's tests, writes and triangle-tile pairs culled (with `bins`: also those culled when binned). covered_pixels, colour writes,
/// memory and times are the caller's.
void tiledStats(Stats& st, const FrontEndOutput& fe, const tiled::Bins* bins, const tiled::RasterCounters& counters);

template <class TilesOf>
void assignUnits(TiledState& state, int workers, size_t units, TilesOf&& tilesOf) {
  const size_t parts = size_t(workers);
  const tiled::Bins& bins = state.bins;
  // Per tile and part, how many of the records binned there that part set up.
  std::vector<size_t>& records = state.recordsByPart;
  records.assign(size_t(bins.tileCount()) * parts, 0);
  state.partRecords.assign(parts, 0);
  for (size_t c = 0; c < bins.chunkCount; ++c) {
    const tiled::ChunkBins& cb = bins.chunks[c];
    const size_t part = std::min<size_t>(cb.producer, parts - 1);
    for (uint32_t t : cb.touched) {
      const size_t n = cb.start[t + 1] - cb.start[t];
      records[t * parts + part] += n;
      state.partRecords[part] += n;
    }
  }
  // The part that set up the fewest records (the last one on a tie): the units without records
  // are its own. They are pure memory traffic (streaming the background), the others mostly
  // computation, and one core streams about as fast as two, so the background is best written
  // while the other parts rasterize. (Spreading them over all parts in consecutive runs was
  // slower where one part sets up most triangles: see docs/benchmarks.md.)
  size_t lightest = parts - 1;
  for (size_t p = parts; p-- > 0;)
    if (state.partRecords[p] < state.partRecords[lightest]) lightest = p;
  // Each unit's owner: the part with the most records over its tiles (none: the lightest part).
  state.unitOwner.resize(units);
  state.unitBounds.assign(parts + 1, 0);
  for (size_t u = 0; u < units; ++u) {
    const auto [first, count] = tilesOf(u);
    size_t owner = lightest, most = 0;
    for (size_t p = 0; p < parts; ++p) {
      size_t n = 0;
      for (int t = first; t < first + count; ++t) n += records[size_t(t) * parts + p];
      if (n > most) owner = p, most = n;
    }
    state.unitOwner[u] = uint32_t(owner);
    ++state.unitBounds[owner + 1];
  }
  // The units part by part, in order within each (a counting sort).
  for (size_t p = 0; p < parts; ++p) state.unitBounds[p + 1] += state.unitBounds[p];
  state.unitOrder.resize(units);
  records.assign(state.unitBounds.begin(), state.unitBounds.end() - 1);  // (now each part's next place)
  for (size_t u = 0; u < units; ++u) state.unitOrder[records[state.unitOwner[u]]++] = uint32_t(u);
  state.tileWork.reset(state.unitOrder.data(), units, state.unitBounds.data(), parts);
}

}  // namespace hsr::algo

// What the tiled z-buffer (zbuffer.cpp) and the occlusion buffer (occlusion.cpp) share: the
// state the tiled path keeps from frame to frame, the front end with binning, the choice of how
// many workers a tile pass is worth, and the statistics of the tile pass.
#pragma once
#include <hsr/frame.hpp>
#include <hsr/render.hpp>

#include <vector>

#include "frontend/frontend.hpp"
#include "raster/tiled.hpp"

namespace hsr::algo {

/// Everything the tiled path needs from frame to frame, kept by its owner so that a warm frame
/// allocates nothing: the front end's output, the bins, the workers' tile scratch (the z-buffer
/// only: the occlusion buffer keeps one tile per tile) and visit lists, the per-tile counters.
struct TiledState {
  FrontEndOutput fe;
  tiled::Bins bins;
  std::vector<tiled::TileScratch> scratch;
  std::vector<tiled::TileOrder> orders;         // per worker
  std::vector<tiled::RasterCounters> counters;  // per tile
  std::vector<uint64_t> covered;                // per tile
  uint64_t memoryBytes() const;
};

/// Whether a frame defers its back faces (raster/tiled.hpp, binChunk): when it draws both sides
/// (cull none). The environment variable HSR_DEFER_BACK_FACES=off turns it off, for tests and
/// measurements: the image is the same bits either way.
bool deferBackFaces(const RenderOptions& opt);
/// Whether the deferral takes whole clusters that face away too (Scene::clusters, deferCluster):
/// unless HSR_DEFER_CLUSTERS=off (same bits either way).
bool deferClusters();

/// Sets up the scene's triangles (runFrontEnd) and bins each chunk on the worker that set it up,
/// while it is in that core's cache.
void setUpAndBin(const Scene& scene, const Camera& cam, const RenderOptions& opt, const DepthSetup& depth,
                 TiledState& state);

/// How many workers the binned frame's tile pass is worth (at most `threads`; small frames run
/// on fewer, as handing work to a pool thread costs about as much as the kernel spends on ~4000
/// small triangles), with one visit list each, and the per-tile counters cleared.
int prepareTilePass(TiledState& state, int threads);

/// The statistics every tiled pass reports (CONVENTIONS.md keys): the front end's counts and the
/// tile pass's tests, writes and triangle-tile pairs culled (with `bins`: also those culled when binned). covered_pixels, colour writes,
/// memory and times are the caller's.
void tiledStats(Stats& st, const FrontEndOutput& fe, const tiled::Bins* bins, const tiled::RasterCounters& counters);

}  // namespace hsr::algo

// The tiled path's shared steps (tiled_pass.hpp).
#include "algorithms/tiled_pass.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace hsr::algo {
namespace {

// Threads pay off only with enough work: handing work to a pool thread costs about as much as
// the kernel spends on ~4000 small binned triangles. A tile (cleared and resolved, or loaded,
// drawn onto and stored again) justifies a worker of its own, so that frames of a few dozen
// tiles use two workers rather than one (see docs/benchmarks.md).
constexpr size_t kWorkPerThread = 4000;
constexpr size_t kWorkPerTile = kWorkPerThread;

}  // namespace

uint64_t TiledState::memoryBytes() const {
  uint64_t bytes = bins.memoryBytes() + scratch.size() * sizeof(tiled::TileScratch) +
                   counters.capacity() * sizeof(tiled::RasterCounters) + covered.capacity() * sizeof(uint64_t) +
                   (unitOwner.capacity() + unitOrder.capacity() + busySegments.capacity() + idleSegments.capacity()) *
                       sizeof(uint32_t) +
                   (unitBounds.capacity() + recordsByPart.capacity() + partRecords.capacity()) * sizeof(size_t);
  for (const tiled::TileOrder& order : orders) bytes += order.memoryBytes();
  return bytes;
}

bool deferBackFaces(const RenderOptions& opt) {
  // Culled already, or (cull front) nothing in front to draw first.
  return opt.cull == Cull::None && opt.tiled.deferBackFaces;
}

void setUpAndBin(const Scene& scene, const Camera& cam, const RenderOptions& opt, const DepthSetup& depth,
                 TiledState& state, const FrontEndOutput* vertices, const std::vector<TriangleRange>* only) {
  const size_t triangles = scene.triangles.size(), perChunk = chunkTrianglesFor(triangles);
  tiled::prepareBins(state.bins, cam.width, cam.height, (triangles + perChunk - 1) / perChunk);
  const ChunkConsumer bin = [&](size_t chunk) {
    state.bins.chunks[chunk].producer = uint32_t(currentPart());  // (for assignUnits)
    tiled::binChunk(state.bins, chunk, state.fe.chunks[chunk], &depth);
  };
  const FrontEndOptions frontEnd{
      .nearestFor = &depth, .deferBackFaces = deferBackFaces(opt), .deferClusters = opt.tiled.deferClusters, .only = only};
  if (vertices)
    runSetUp(scene, cam, opt, *vertices, state.fe, bin, frontEnd);
  else
    runFrontEnd(scene, cam, opt, state.fe, bin, frontEnd);
  state.bins.projected = (vertices ? *vertices : state.fe).projected.data();  // (for setting deferred triangles up)
  state.bins.camera = &cam;
  state.bins.sceneTriangles = scene.triangles.data();
}

int prepareTilePass(TiledState& state, int threads, std::vector<uint32_t>* touched) {
  const tiled::Bins& bins = state.bins;
  const size_t tiles = size_t(bins.tileCount());
  // Every worker's lists sized for the fullest tile (which worker meets which tile varies from
  // frame to frame: sized by the tiles met, a warm frame could still allocate).
  state.bins.countEntries();
  size_t most = 0, mostLate = 0;
  if (touched) touched->clear();
  for (size_t t = 0; t < tiles; ++t) {
    most = std::max<size_t>(most, bins.tileEntries[t]);
    const size_t late = bins.tileEntries[tiles + t] + bins.tileEntries[2 * tiles + t] * kClusterTriangles;
    mostLate = std::max<size_t>(mostLate, late);
    if (touched && bins.tileEntries[t] + late > 0) touched->push_back(uint32_t(t));
  }
  // Every binned pair and deferred face, chunk by chunk (not tile by tile: that is a pass over
  // every chunk's lists per tile, on one thread).
  size_t work = (touched ? touched->size() : tiles) * kWorkPerTile;
  for (size_t c = 0; c < bins.chunkCount; ++c)
    work += bins.chunks[c].items.size() + bins.late[c].items.size() + bins.clusters[c].items.size();
  const int workers = int(std::clamp<size_t>(work / kWorkPerThread, 1, size_t(threads)));
  if (state.orders.size() < size_t(workers)) state.orders.resize(size_t(workers));
  for (tiled::TileOrder& order : state.orders) {
    order.entries.reserve(most);
    order.ordered.reserve(most);
    order.bucket.reserve(most);
    order.late.reserve(mostLate);
  }
  state.counters.assign(size_t(bins.tileCount()), {});
  state.covered.assign(size_t(bins.tileCount()), 0);
  return workers;
}

void tiledStats(Stats& st, const FrontEndOutput& fe, const tiled::Bins* bins, const tiled::RasterCounters& counters) {
  st.triangles_clipped = fe.clipped;
  st.triangles_degenerate = fe.degenerate;
  st.culled_backface = fe.culledBackface;
  st.culled_frustum = fe.culledFrustum;
  // Triangle-tile pairs skipped because the triangle lies behind all the tile holds: when
  // binned (behind a triangle covering the tile) or when the tile was rasterized.
  st.culled_occlusion = counters.culledTiles + (bins ? bins->culled() : 0);
  // Only fragments not rejected early by a tile or block bound (or, pixel by pixel, the
  // triangle's nearest bound) are compared.
  st.depth_tests = counters.depthTests;
  st.depth_writes = counters.depthWrites;
  if (bins) {
    uint64_t faces = 0, clusters = 0;
    for (size_t c = 0; c < fe.chunkCount; ++c) {
      faces += fe.chunks[c].deferred.size();
      clusters += fe.chunks[c].clusters.size();
    }
    st.setDetail("triangles_deferred", faces + clusters * kClusterTriangles);
    st.setDetail("clusters_deferred", clusters);
    st.setDetail("triangles_set_up_late", counters.setUpLate);
  }
}

}  // namespace hsr::algo

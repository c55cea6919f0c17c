// Queries on kept tiles (tiled.hpp: storedAt, anyFarther) and loadTile, which brings a kept tile
// back into a worker's scratch: scalar code that computes the kernel's bits from a KeptTile's
// states and values. Called by the occlusion buffer (algorithms/occlusion.cpp), from any thread
// once the tiles are stored, while the frame's set-up triangles are alive.
#include <algorithm>
#include <cstdint>

#include "core/depth_map.hpp"
#include "raster/tiled.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr::tiled {

namespace {

template <DepthMapping M>
MappedPlanes planesOf(const SetupTriangle& t, const DepthSetup& depth) {
  return mapPlanes<M>(t.depthNum, t.depthDen, depth.near, depth.far, depth.orthographic);
}

// The stored value of plane m at image pixel (x, y), as the kernel computes it.
template <DepthStorage S>
double planeStored(const MappedPlanes& m, int x, int y) {
  const double Y = double(y) + 0.5;
  return fragmentStored<S>(m, double(x) + 0.5, m.p.b * Y, m.q.b * Y);
}

// Calls fn(stored value) for the tile-local pixels [x0, x1] x [y0, y1] of one 8x8 block (or of
// any part of a tile in state Clear or Plane), until it returns true; returns whether it did. The
// planes are mapped once, not per pixel.
template <DepthStorage S, DepthMapping M, class Fn>
bool anyStoredIn(const KeptTile& s, const DepthSetup& depth, int tx0, int ty0, int x0, int y0, int x1, int y1,
                 Fn&& fn) {
  constexpr int kBlocksX = kTileSize / kBlockSize;
  const int block = (y0 / kBlockSize) * kBlocksX + x0 / kBlockSize;  // (state Pixels: the only one)
  const SetupTriangle* plane = s.state == TileState::Plane                            ? s.plane
                               : s.state == TileState::Pixels && s.blockKey[block] ? s.blockTriangle[block]
                                                                                    : nullptr;
  const bool cleared = s.state == TileState::Clear || (s.state == TileState::Pixels && s.blockClear[block]);
  const double clear = double(quantizeDepth<S>(depth.format.clearValue()));
  const MappedPlanes m = plane ? planesOf<M>(*plane, depth) : MappedPlanes{};
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double v = plane     ? planeStored<S>(m, tx0 + x, ty0 + y)
                       : cleared ? clear
                                 : keptStored<S>(s.depth[KeptTile::at(x, y)]);
      if (fn(v)) return true;
    }
  return false;
}

template <DepthStorage S, DepthMapping M>
bool anyFartherT(const KeptTile& s, const DepthSetup& depth, int tx0, int ty0, int x0, int y0, int x1, int y1,
                 double q) {
  constexpr int kBlocksX = kTileSize / kBlockSize;
  // Bounds: every stored value is nearer than or equal to the farthest bound (the tile's, or
  // the farthest of its blocks' while it is stale), and farther than or equal to the nearest.
  if (s.state == TileState::Clear) return storedNearer<M>(q, double(quantizeDepth<S>(depth.format.clearValue())));
  double far = s.tileFar;
  if (s.state == TileState::Pixels && s.tileFarStale)
    for (int b = 0; b < kBlocksPerTile; ++b)
      if (b == 0 || storedNearer<M>(far, s.blockFar[b])) far = s.blockFar[b];
  if (!storedNearer<M>(q, far)) return false;
  if (storedNearer<M>(q, s.tileNear)) return true;
  auto anyPixel = [&](int px0, int py0, int px1, int py1) {
    return anyStoredIn<S, M>(s, depth, tx0, ty0, px0, py0, px1, py1,
                             [&](double v) { return storedNearer<M>(q, v); });
  };
  if (s.state == TileState::Plane) return anyPixel(x0, y0, x1, y1);
  for (int by = y0 / kBlockSize; by <= y1 / kBlockSize; ++by)
    for (int bx = x0 / kBlockSize; bx <= x1 / kBlockSize; ++bx) {
      const int b = by * kBlocksX + bx;
      if (!storedNearer<M>(q, s.blockFar[b])) continue;
      if (storedNearer<M>(q, s.blockNear[b])) return true;
      if (anyPixel(std::max(x0, bx * kBlockSize), std::max(y0, by * kBlockSize),
                   std::min(x1, bx * kBlockSize + kBlockSize - 1), std::min(y1, by * kBlockSize + kBlockSize - 1)))
        return true;
    }
  return false;
}

}  // namespace

double storedAt(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x, int y) {
  double v = 0;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    anyStoredIn<S, M>(kept, depth, (tile % bins.tilesX) * kTileSize, (tile / bins.tilesX) * kTileSize, x, y, x, y,
                      [&](double stored) {
                        v = stored;
                        return true;
                      });
  });
  return v;
}

bool anyFarther(const Bins& bins, int tile, const DepthSetup& depth, const KeptTile& kept, int x0, int y0,
                int x1, int y1, double stored) {
  bool any = false;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    any = anyFartherT<S, M>(kept, depth, (tile % bins.tilesX) * kTileSize, (tile / bins.tilesX) * kTileSize, x0,
                            y0, x1, y1, stored);
  });
  return any;
}

void loadTile(const KeptTile& from, const DepthSetup& depth, TileScratch& to) {
  static_cast<TileSummary&>(to) = from;
  if (from.state != TileState::Pixels) return;
  constexpr int kBlocksX = kTileSize / kBlockSize;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping M>() {
    for (int b = 0; b < kBlocksPerTile; ++b) {
      if (from.blockKey[b] != 0 || from.blockClear[b]) continue;  // uniform: storeTile kept no values
      const int bx = b % kBlocksX * kBlockSize, by = b / kBlocksX * kBlockSize;
      for (int y = by; y < by + kBlockSize; ++y)
        for (int x = bx; x < bx + kBlockSize; ++x)
          to.depth[size_t(y) * kTileSize + size_t(x)] = keptStored<S>(from.depth[KeptTile::at(x, y)]);
    }
  });
}

}  // namespace hsr::tiled

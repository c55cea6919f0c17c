// The tile pass's choice of late triangles: selectLate lists the deferred back faces and clusters'
// triangles that may still show once the tile's Front pass is drawn, setting them up again.
// Called only by rasterizeTile (tiled.cpp) between the kernel's Front and Late passes, on the
// worker that owns the tile; defined in tile_pass.cpp.
#pragma once
#include "raster/tiled.hpp"

namespace hsr::tiled {

/// The deferred back faces and clusters binned to `tile` that may change it, as rasterizeTile's
/// Front pass left it in `s`: set up (their records in Bins::late) and listed in order.late. A face
/// or a cluster is hidden when every block its box touches holds nothing farther than its nearest
/// bound (Beaten, with the kernel's tie rule) — by the block's farthest value, or else by the
/// stored values of the box's part of the block; so is each triangle of a cluster that is not;
/// hidden ones are counted as culled triangle-tile pairs (a hidden cluster as all its triangles).
void selectLate(const Bins& bins, int tile, const DepthSetup& depth, bool ids, const TileScratch& s, TileOrder& order,
                RasterCounters& counters);

}  // namespace hsr::tiled

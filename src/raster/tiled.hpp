// The tiled (sort-middle) rasterizer behind the default z-buffer: prepareBins()/binRange() sort
// set-up triangles into per-tile lists in submission order, rasterizeTile() runs every triangle
// of one tile through the SIMD kernel (raster/tile_kernel-inl.h) into a worker's tile-sized
// depth and triangle buffers, resolveTile() writes that tile into the Frame. Plain functions
// without threads: the z-buffer (algorithms/zbuffer.cpp) calls them via parallelFor, one owner
// per tile, so no locks; per-tile counters are summed in tile order.
//
// Exactness: the kernel evaluates coverage with the same integer edge functions and depth with
// the same double operations in the same order as the reference (raster/halfspace.hpp +
// zbuffer.cpp), so face ids and stored depths are bit-identical to it for any thread count.
//
// Early rejection (the base for a hierarchical z-buffer): each tile and each 8x8 block keeps
// its farthest stored value; a triangle whose conservative nearest value (Bins::nearest) is
// not nearer is skipped for the tile, the block, or a SIMD row. Statistics it defines:
// depth_tests = fragments whose depth was computed and compared (rejected ones are not);
// culled_occlusion = triangle-tile pairs skipped whole. depth_writes is the reference's.
#pragma once
#include <hsr/frame.hpp>
#include <hsr/render.hpp>

#include <cstdint>
#include <vector>

#include "frontend/frontend.hpp"

// Block counters of the kernel (RasterCounters::blocks*, rowsCulled), on unless built with
// -DHSR_RASTER_COUNTERS=0.
#ifndef HSR_RASTER_COUNTERS
#define HSR_RASTER_COUNTERS 1
#endif

namespace hsr::tiled {

inline constexpr bool kCountBlocks = HSR_RASTER_COUNTERS;

/// Tile edge in pixels (a multiple of kBlockSize). Measured at 1920x1080: 32 and 64 within
/// noise of each other, 128 slower on the million-triangle sphere; 64 has fewer tiles to manage.
inline constexpr int kTileSize = 64;
/// The kernel's block: classified empty/partial/full by its corners, one SIMD row per line.
inline constexpr int kBlockSize = 8;
inline constexpr int kBlocksPerTile = (kTileSize / kBlockSize) * (kTileSize / kBlockSize);

/// Depth buffer settings of a frame.
struct DepthSetup {
  DepthFormat format;
  double near = 0, far = 0;
  bool orthographic = false;
};

/// Per-tile triangle lists, filled by binRange() and reused across frames (capacity is kept).
struct Bins {
  int width = 0, height = 0, tilesX = 0, tilesY = 0;
  /// lists[range][tile]: triangle indices of contiguous submission range `range` touching the
  /// tile. Read in range order, they are one list in submission order; ranges let binning run
  /// on several threads without changing the result.
  std::vector<std::vector<std::vector<uint32_t>>> lists;
  /// Per triangle: a stored depth value no fragment of it can be nearer than (conservative,
  /// format specific), or the nearest possible value when no safe bound exists.
  std::vector<double> nearest;

  int tileCount() const { return tilesX * tilesY; }
  size_t entries(int tile) const;
  uint64_t memoryBytes() const;
};

/// Counts of the tile pass. depth_tests/writes of the statistics come from here.
struct RasterCounters {
  uint64_t depthTests = 0;    // fragments whose depth was computed and compared with the buffer
  uint64_t depthWrites = 0;   // fragments strictly nearer than the buffer (they win, as in the reference)
  uint64_t culledTiles = 0;   // triangle-tile pairs skipped: the triangle is behind everything stored there
  // Blocks (8x8) met by the kernel; counted only when kCountBlocks.
  uint64_t blocksEmpty = 0, blocksPartial = 0, blocksFull = 0;
  uint64_t blocksCulled = 0;  // skipped: the triangle is behind everything stored in the block
  uint64_t rowsCulled = 0;    // SIMD rows of covered pixels skipped: nothing stored there is farther
  void add(const RasterCounters& o);
};

/// A worker's tile: stored depth (as double: every format's values are exact in it) and the
/// winning triangle (index + 1, 0 = none), row-major kTileSize x kTileSize, plus the farthest
/// stored value per block and per tile that reject triangles early. Reused tile after tile.
struct alignas(64) TileScratch {
  alignas(64) double depth[kTileSize * kTileSize];
  alignas(64) uint64_t triangle[kTileSize * kTileSize];
  alignas(64) double blockFar[kBlocksPerTile];
  double tileFar;
  bool tileFarStale;
};

/// Binning, in two steps so the caller can run the second on several threads: prepareBins()
/// sizes the bins for a width x height image and splits the triangles into `ranges` contiguous
/// parts; binRange(r) sorts part r into its own lists (clearing them first) and computes
/// Bins::nearest of its triangles for the depth setup. Ranges share no output.
void prepareBins(Bins& bins, int width, int height, size_t triangleCount, int ranges);
void binRange(Bins& bins, const std::vector<SetupTriangle>& tris, const DepthSetup& depth, int range);

/// Rasterizes every triangle binned to `tile` into `scratch` (cleared first). With ids false,
/// only depth is kept (no triangle ids). Adds to `counters`.
void rasterizeTile(const Bins& bins, int tile, const std::vector<SetupTriangle>& tris, const DepthSetup& depth,
                   bool ids, TileScratch& scratch, RasterCounters& counters);

/// Writes the tile of `scratch` into `frame` as `outputs` asks: ids, eye depth of the winning
/// triangle's plane at the pixel centre (exactly as the reference resolves it), colour; or, for
/// DepthOnly, the eye depth of the stored value. Returns the number of covered pixels.
uint64_t resolveTile(const Bins& bins, int tile, const std::vector<SetupTriangle>& tris, const DepthSetup& depth,
                     FrameOutputs outputs, const TileScratch& scratch, Frame& frame);

/// What the kernel (tile_kernel-inl.h) needs for one tile (scratch and counters: rasterizing only).
struct TileJob {
  const Bins* bins;
  int tile;
  const SetupTriangle* triangles;
  DepthSetup depth;
  bool ids;  // keep the winning triangle per pixel (false: depth only)
  TileScratch* scratch;
  RasterCounters* counters;
};

/// Name of the instruction set the kernel dispatches to on this machine (e.g. "AVX3").
const char* kernelTarget();

}  // namespace hsr::tiled

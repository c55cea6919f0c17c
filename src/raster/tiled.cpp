// The tiled rasterizer's SIMD unit: Highway compiles the tile kernel (tile_kernel-inl.h) here once
// per instruction set, and the functions below dispatch to the best one at run time. Called by the
// z-buffer (algorithms/zbuffer_tiled.cpp), the occlusion buffer and the benchmarks, on the caller's
// thread. Nothing else lives here: binning, tile order, the late pass and kept tiles are plain code.
//
// Built with -ffp-contract=off (CMakeLists.txt), like all of hsr: no fused multiply-add may change
// a bit of the depth arithmetic that the kernel shares with the reference.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/tile_kernel-inl.h"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include "raster/tile_kernel-inl.h"

#if HWY_ONCE
#include <algorithm>
#include <cstdint>

#include "raster/tile_pass.hpp"
#include "raster/tiled.hpp"

namespace hsr::tiled {

HWY_EXPORT(RasterizeTile);
HWY_EXPORT(ResolveTile);
HWY_EXPORT(ResolveStoredDepth);
HWY_EXPORT(PrepareResolve);
HWY_EXPORT(KernelTarget);
HWY_EXPORT(FlushStreams);
HWY_EXPORT(StoreTile);
HWY_EXPORT(DrainPump);

void rasterizeTile(const Bins& bins, int tile, const DepthSetup& depth, bool ids, TileScratch& scratch,
                   TileOrder& order, RasterCounters& counters, bool keep, BackgroundPump* pump) {
  const bool late = bins.entries(tile, true) > 0;
  TileJob job{&bins, tile, depth, ids, &scratch, &counters, nullptr, &order, late ? TileJob::Pass::Front : TileJob::Pass::Whole, keep, pump};
  HWY_DYNAMIC_DISPATCH(RasterizeTile)(job);
  if (!late) return;
  selectLate(bins, tile, depth, ids, scratch, order, counters);
  if (order.late.empty()) return;
  job.pass = TileJob::Pass::Late;
  HWY_DYNAMIC_DISPATCH(RasterizeTile)(job);
}

void prepareResolve(const Bins& bins, int tile, FrameOutputs outputs, const TriangleShader* shader, Rgba8 background,
                    TileScratch& scratch, BackgroundPump* pump) {
  TileJob job{&bins, tile, DepthSetup{}, true, &scratch, nullptr, shader, nullptr};  // (depth: not read)
  job.pump = pump;
  HWY_DYNAMIC_DISPATCH(PrepareResolve)(job, outputs, background);
}

uint64_t resolveTile(const Bins& bins, int tile, const DepthSetup& depth, FrameOutputs outputs,
                     const TriangleShader* shader, Rgba8 background, const TileScratch& scratch, Frame& frame,
                     int rowBegin, int rowEnd) {
  const TileJob job{&bins, tile, depth, true, nullptr, nullptr, shader, nullptr};
  return HWY_DYNAMIC_DISPATCH(ResolveTile)(job, scratch, outputs, background, rowBegin, rowEnd, frame);
}

uint64_t resolveStoredDepth(const Bins& bins, int tile, const DepthSetup& depth, const TileScratch& scratch,
                            Frame& frame, int rowBegin, int rowEnd) {
  const TileJob job{&bins, tile, depth, false, nullptr, nullptr, nullptr, nullptr};
  return HWY_DYNAMIC_DISPATCH(ResolveStoredDepth)(job, scratch, rowBegin, rowEnd, frame);
}

const char* kernelTarget() { return HWY_DYNAMIC_DISPATCH(KernelTarget)(); }

void finishResolves() { HWY_DYNAMIC_DISPATCH(FlushStreams)(); }
void drainBackground(BackgroundPump& pump) { HWY_DYNAMIC_DISPATCH(DrainPump)(pump); }

bool BackgroundPump::setPiece(uint32_t* start, size_t count, uint32_t fill) {
  constexpr size_t kLine = stream::HWY_NAMESPACE::kLineValues;
  const size_t head = std::min(count, (kLine - reinterpret_cast<uintptr_t>(start) / sizeof(uint32_t) % kLine) % kLine);
  const size_t whole = (count - head) / kLine;
  std::fill(start, start + head, fill);
  std::fill(start + head + whole * kLine, start + count, fill);
  dst = start + head;
  lines = uint32_t(whole);
  value = fill;
  return whole > 0;
}

void storeTile(const TileScratch& from, const DepthSetup& depth, KeptTile& to) {
  HWY_DYNAMIC_DISPATCH(StoreTile)(from, depth, to);
}

}  // namespace hsr::tiled
#endif  // HWY_ONCE

// The drawing service every algorithm composes: set-up triangles drawn in a given order under a
// write rule, on a scalar rasterizer (one thread, the reference) or binned into tiles that
// threads own, with the counters of the statistics counted one way for everyone. A list-priority
// algorithm orders (and splits) faces and calls drawScene; the textbook z-buffer is drawScene in
// submission order with the depth test. Runs on the caller's thread and the pool (core/parallel.hpp).
#pragma once
#include <hsr/algorithm.hpp>
#include <hsr/render.hpp>

#include <cstdint>
#include <functional>
#include <span>
#include <type_traits>
#include <vector>

#include "core/timer.hpp"
#include "frontend/frontend.hpp"

namespace hsr::algo {

/// What a fragment does to its pixel.
enum class WriteRule : uint8_t {
  DepthTest,       // the z-buffer: written where strictly nearer than the stored depth (ties keep the first)
  Overwrite,       // the painter's: every fragment overwrites; no depth buffer
  WhereUnwritten,  // the reverse painter's: written only where nothing was written yet; stops when all is
  Blend,           // transparency: the colour composited over by the triangle's alpha; ids and depth overwritten
  DepthTestBlend,  // the z-buffer's transparent pass: depth-tested; an opaque triangle (alpha 255) writes depth
                   // and colour, a transparent one writes no depth and composites its colour over
  BlendUnder,      // the reverse painter's with transparency: front to back, each fragment composited under what
                   // the pixel holds until it is opaque; ids the first (nearest); the background under all at the end
};
const char* writeRuleName(WriteRule rule);

/// How fragments are produced. Every rasterizer covers the same pixel centres (edge functions,
/// top-left rule); HalfSpace and Binned compute the same depth at each, Scanline steps it along spans.
enum class DrawRaster : uint8_t {
  HalfSpace,  // the scalar half-space rasterizer over the whole frame, on one thread (the reference)
  Scanline,   // the lecture notes' scanline rasterizer, depth stepped by the plane equation, one thread
  Binned,     // the half-space rasterizer per 64x64 tile, tiles on threads (the same bits as HalfSpace)
};
const char* drawRasterName(DrawRaster raster);
/// The `raster` parameter of an algorithm that draws through the service, and its value.
ParamSpec drawRasterParam(const char* defaultValue);
DrawRaster drawRasterOf(const AlgorithmParams& params);

/// The per-pixel buffers the drawing service draws with (a depth buffer of each storage type,
/// the winning triangles), owned by the algorithm object that draws and kept from one frame to
/// the next: a warm frame rewrites warm pages instead of faulting fresh ones in.
class DrawBuffers {
 public:
  /// The depth buffer of values of type T (uint16_t, uint32_t or float: DepthT).
  template <class T>
  std::vector<T>& depth() {
    if constexpr (std::is_same_v<T, uint16_t>) return depth16_;
    else if constexpr (std::is_same_v<T, float>) return depthF32_;
    else return depth32_;
  }
  /// Per pixel: 1 + the index of the winning (or last written) triangle, 0 = none.
  std::vector<uint32_t>& winner() { return winner_; }

 private:
  std::vector<uint16_t> depth16_;
  std::vector<uint32_t> depth32_;
  std::vector<float> depthF32_;
  std::vector<uint32_t> winner_;
};

/// The counters of the statistics, as every algorithm counts them.
struct DrawCounters {
  uint64_t depthTests = 0;   // z comparisons (DepthTest only)
  uint64_t depthWrites = 0;  // depth values stored (DepthTest only)
  uint64_t colorWrites = 0;  // fragments that wrote a pixel's colour (0 when the frame keeps no colour)
  uint64_t covered = 0;      // pixels showing a surface at the end
  uint64_t written = 0;      // fragments that wrote a pixel (with or without colour)
  uint64_t skippedFull = 0;  // WhereUnwritten: triangles (binned: triangle-tile pairs) not drawn, all full
  uint64_t filled = 0;       // WhereUnwritten, BlendUnder: pixels nothing drawn later can change (written; opaque)
  void add(const DrawCounters& o) {
    depthTests += o.depthTests;
    depthWrites += o.depthWrites;
    colorWrites += o.colorWrites;
    covered += o.covered;
    written += o.written;
    skippedFull += o.skippedFull;
    filled += o.filled;
  }
};

/// Geometry an algorithm made from the scene (a BSP tree's or Newell's split polygons): drawn
/// instead of the scene's own faces, each of its faces and triangles mapped back to the scene's.
/// Face ids, triangle ids and colours in the frame are then the scene's: a fragment shows its
/// original face, shaded as that face is.
struct DerivedScene {
  const Scene* scene = nullptr;          // the geometry drawn (finalized)
  std::vector<uint32_t> face;            // per face of `scene`: the original face
  std::vector<uint32_t> triangle;        // per triangle of `scene`: a triangle of the original face
};

// ---- The z-buffer core: the pieces every way of drawing shares (draw.cpp) ----

/// A copy of t that covers only the pixels of [x0, x1] x [y0, y1] (an empty box when none).
SetupTriangle clippedTo(const SetupTriangle& t, int x0, int y0, int x1, int y1);

/// Per cell of a grid of `columns` x `rows` cells of cellWidth x cellHeight pixels (row by row),
/// the indices of the triangles whose box meets it, in drawing order; a triangle whose box holds
/// no pixel is in no cell.
std::vector<std::vector<uint32_t>> binByCell(std::span<const SetupTriangle> triangles, int cellWidth, int cellHeight,
                                             int columns, int rows);
/// The bytes of such bins.
uint64_t binBytes(const std::vector<std::vector<uint32_t>>& bins);

/// Pixel (x, y) = idx of the frame from the set-up triangle that won it: its face and triangle ids
/// (the scene's, through `derived`), as the outputs ask, and its exact eye depth at the centre. The
/// caller writes the colour, which depends on its rule.
inline void resolveWinner(const SetupTriangle& t, int x, int y, size_t idx, FrameOutputs outputs,
                          const DerivedScene* derived, Frame& frame) {
  if (has(outputs, FrameOutputs::FaceIds)) frame.faceId[idx] = int32_t(derived ? derived->face[t.face] : t.face);
  if (has(outputs, FrameOutputs::TriangleIds))
    frame.triangleId[idx] = int32_t(derived ? derived->triangle[t.triangle] : t.triangle);
  frame.depth[idx] = float(t.eyeDepth(x + 0.5, y + 0.5));
}

/// A frame's first step, the same for every drawing: the front end over `scene`, its set-up
/// triangles flattened in submission order, timed on `timer` as the stage "frontend".
std::vector<SetupTriangle> frontEndStep(const Scene& scene, const Camera& camera, const RenderOptions& options,
                                        FrontEndOutput& fe, Timer& timer, Stats& st);

/// The statistics every drawing fills, one way for all: the front end's counts, the counters,
/// the memory of the set-up triangles, the front end's and the frame's (the caller adds its own
/// buffers'), and the depth format when the drawing tested depth (`depthFormat` not null).
void recordDrawStats(Stats& st, const FrontEndCounters& fe, uint64_t frontEndBytes, size_t setupTriangles,
                     const DrawCounters& n, const DepthFormat* depthFormat, const Frame& frame);

/// Draws `triangles` in their order into `frame` (sized by render(); cleared here) under `rule`
/// and adds to `counters`; Frame::writes, when sized, gets each pixel's written fragments. With
/// `derived`, the triangles are its scene's, and ids and colours are mapped back (DerivedScene).
/// Adds the buffers it used to frame.stats.memory.
void drawOrdered(std::span<const SetupTriangle> triangles, WriteRule rule, DrawRaster raster, const Camera& camera,
                 const RenderOptions& options, const TriangleShader& shade, DrawBuffers& buffers, Frame& frame,
                 DrawCounters& counters, const DerivedScene* derived = nullptr);

/// Puts the set-up triangles (submission order on entry) into drawing order.
using OrderFn = std::function<void(std::vector<SetupTriangle>& triangles)>;

/// A whole frame: the front end sets up the scene's triangles (or, with `derived`, its scene's)
/// in submission order, `order` (if any) reorders them, drawOrdered draws them; the statistics
/// common to every algorithm are filled (front-end counts, counters, memory, times "frontend",
/// "order", "raster"), and the details "rasterizer" and "write_rule".
void drawScene(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
               DrawRaster raster, const OrderFn& order, DrawBuffers& buffers, Frame& frame,
               const DerivedScene* derived = nullptr);

}  // namespace hsr::algo

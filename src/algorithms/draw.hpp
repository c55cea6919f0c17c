// The drawing service every algorithm composes: set-up triangles drawn in a given order under a
// write rule, on a scalar rasterizer (one thread, the reference) or binned into tiles that
// threads own, with the counters of the statistics counted one way for everyone. A list-priority
// algorithm orders (and splits) faces and calls drawScene; the textbook z-buffer is drawScene in
// submission order with the depth test. Runs on the caller's thread and the pool (core/parallel.hpp).
#pragma once
#include <hsr/algorithm.hpp>
#include <hsr/options.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/timer.hpp"
#include "core/depth_map.hpp"
#include "scene/shading.hpp"
#include "frontend/frontend.hpp"
#include "setup/fragment_depth.hpp"

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
  DepthPeel,       // depth peeling: DepthTest among the fragments beyond the layer peeled before
                   // (DrawBuffers::keepPeeledLayer), ordered by (stored depth, drawing order)
};
const char* writeRuleName(WriteRule rule);

/// How fragments are produced. Every rasterizer covers the same pixel centres (edge functions,
/// top-left rule); HalfSpace and Binned compute the same depth at each, Scanline steps it along spans.
enum class DrawRaster : uint8_t {
  HalfSpace,  // the scalar half-space rasterizer over the whole frame, on one thread (the reference)
  Scanline,   // the lecture notes' scanline rasterizer, depth stepped by the plane equation, one thread
  Binned,     // the half-space rasterizer per 64x64 tile, tiles on threads (the same bits as HalfSpace)
  Tiled,      // the z-buffer's SIMD tile kernel (TiledZBuffer::drawInOrder): DepthTest, Overwrite,
              // WhereUnwritten, Blend and BlendUnder, the same bits as HalfSpace; the others draw Binned
};
const char* drawRasterName(DrawRaster raster);
/// The `raster` parameter of an algorithm that draws through the service (with `kernel`, drawScene
/// with a rule DrawRaster::Tiled draws: "tiled" is offered), and its value.
ParamSpec drawRasterParam(const char* defaultValue, bool kernel = false);
DrawRaster drawRasterOf(const AlgorithmParams& params);

/// The per-pixel buffers the drawing service draws with (a depth buffer of each storage type,
/// the winning triangles), owned by the algorithm object that draws and kept from one frame to
/// the next: a warm frame rewrites warm pages instead of faulting fresh ones in.
class TiledZBuffer;

class DrawBuffers {
 public:
  DrawBuffers();
  ~DrawBuffers();
  DrawBuffers(DrawBuffers&&) noexcept;
  DrawBuffers& operator=(DrawBuffers&&) noexcept;

  /// The depth buffer of values of type T (uint16_t, uint32_t or float: DepthT).
  template <class T>
  std::vector<T>& depth() { return drawn_.depth.get<T>(); }
  /// Per pixel: 1 + the index of the winning (or last written) triangle, 0 = none.
  std::vector<uint32_t>& winner() { return drawn_.winner; }

  /// DepthPeel: the layer peeled before, its depth values and winners (empty: none yet, so the
  /// next layer is the nearest).
  template <class T>
  std::vector<T>& peeledDepth() { return peeled_.depth.get<T>(); }
  std::vector<uint32_t>& peeledWinner() { return peeled_.winner; }
  /// The layer just drawn under DepthPeel becomes the one the next layer lies beyond.
  void keepPeeledLayer() { std::swap(drawn_, peeled_); }
  /// Forgets the peeled layer: the next DepthPeel layer is the nearest.
  void forgetPeeledLayer() { peeled_.clear(); }

  /// DrawRaster::Tiled: the tile kernel's bins and tile buffers.
  TiledZBuffer& tiled();

  /// What a frame's steps keep from one frame to the next (drawFrame with FrameSteps::buffers):
  /// the front end's output, the set-up triangles, and room to reorder them (byFaceRank).
  struct FrameScratch {
    FrontEndOutput frontEnd;
    std::vector<SetupTriangle> triangles, reordered;
    std::vector<TriangleRange> only;  // the derived triangles of the meshes left after culling
  };
  FrameScratch& frameScratch() { return frameScratch_; }
  /// DrawRaster::Tiled with blending: each pixel's deciding opaque fragment (its triangle ids).
  Frame& opaqueLayer() { return opaqueLayer_; }

 private:
  // A depth buffer of each storage type.
  struct DepthOfEachType {
    std::vector<uint16_t> u16;
    std::vector<uint32_t> u32;
    std::vector<float> f32;
    template <class T>
    std::vector<T>& get() {
      if constexpr (std::is_same_v<T, uint16_t>) return u16;
      else if constexpr (std::is_same_v<T, float>) return f32;
      else return u32;
    }
  };
  // One layer: its depth values and its winners.
  struct Layer {
    DepthOfEachType depth;
    std::vector<uint32_t> winner;
    void clear() {  // keeping the memory, for the next frame's warm pages
      depth.u16.clear();
      depth.u32.clear();
      depth.f32.clear();
      winner.clear();
    }
  };
  Layer drawn_, peeled_;
  std::unique_ptr<TiledZBuffer> tiled_;
  FrameScratch frameScratch_;
  Frame opaqueLayer_;
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

/// Puts the set-up triangles (submission order on entry) into drawing order.
using OrderFn = std::function<void(std::vector<SetupTriangle>& triangles)>;

// ---- The z-buffer core: the pieces every way of drawing shares (draw.cpp) ----

/// The depth test, one copy for every z-buffer: counts the test and says whether stored value z
/// is strictly nearer (mapping M) than the pixel's `stored` (a tie keeps what was drawn first).
template <DepthMapping M, class T>
inline bool passesDepthTest(T z, T stored, DrawCounters& n) {
  ++n.depthTests;
  return storedNearer<M>(double(z), double(stored));
}
/// Stores z as the pixel's depth and counts the write.
template <class T>
inline void storeDepth(T z, T& stored, DrawCounters& n) {
  stored = z;
  ++n.depthWrites;
}
/// The z-buffer's step for one fragment: the test, and the store where it passes.
template <DepthMapping M, class T>
inline bool depthTest(T z, T& stored, DrawCounters& n) {
  if (!passesDepthTest<M>(z, stored, n)) return false;
  storeDepth(z, stored, n);
  return true;
}
/// A fragment that wrote the frame's pixel idx, counted one way for every rule: a write, a colour
/// write when the frame keeps colour, and the pixel's count in Frame::writes when sized.
inline void countWritten(size_t idx, Frame& frame, DrawCounters& n) {
  ++n.written;
  if (!frame.color.empty()) ++n.colorWrites;
  if (!frame.writes.empty()) ++frame.writes[idx];
}

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

/// The shaded colour of set-up triangle t: its original face's, when it is derived geometry.
inline Rgba8 colorOf(const SetupTriangle& t, const TriangleShader& shade, const DerivedScene* derived) {
  return derived ? shade(derived->triangle[t.triangle]) : triangleColor(t, shade);
}
/// Every triangle's shaded colour, once (on `threads` of the pool), for resolving: far fewer
/// triangles than pixels, and a colour is the same all over its triangle.
std::vector<Rgba8> triangleColors(std::span<const SetupTriangle> tris, const TriangleShader& shade,
                                  const DerivedScene* derived, int threads);

/// The pixels [x0, x1] x [y0, y1] of a frame and where a buffer covering them (row length
/// `stride`, starting at (x0, y0)) holds each: the whole image, a row of it, or one region.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
  size_t stride = 0;
  size_t at(int x, int y) const { return size_t(y - y0) * stride + size_t(x - x0); }
};

/// The resolve, one copy for every z-buffer: each pixel of `rect` from its winner (1 + the index
/// into `tris` of the last triangle written, 0 = none): its ids and exact eye depth from that
/// triangle (resolveWinner), for every set of outputs, and `color(winner index, frame index)` for
/// the colour. Counts the pixels covered.
template <class Color>
void resolvePixels(const PixelRect& rect, std::span<const uint32_t> winner, std::span<const SetupTriangle> tris,
                   FrameOutputs outputs, const DerivedScene* derived, Color&& color, Frame& frame, DrawCounters& n) {
  for (int y = rect.y0; y <= rect.y1; ++y)
    for (int x = rect.x0; x <= rect.x1; ++x) {
      const size_t at = rect.at(x, y), idx = frame.index(x, y);
      if (!winner[at]) continue;
      resolveWinner(tris[winner[at] - 1], x, y, idx, outputs, derived, frame);
      color(winner[at] - 1, idx);
      ++n.covered;
    }
}

/// What the steps of one frame share: the set-up triangles (in drawing order once ordered), the
/// front end's counts and memory, and the counters.
struct FrameWork {
  std::vector<SetupTriangle> triangles;
  FrontEndCounters frontEnd;
  uint64_t frontEndBytes = 0;
  DrawCounters counters;
};

/// Where an algorithm's frame departs from the common one (drawFrame).
struct FrameSteps {
  OrderFn order;                          // the drawing order; none: submission order
  bool depthTested = true;                // the statistics name the depth format
  bool clearFrame = true;                 // false: the draw step writes every pixel itself
  bool setUp = true;                      // false: the draw step sets up the triangles itself and fills
                                          // the work's front-end counts (occlusion culling interleaves them)
  const DerivedScene* derived = nullptr;  // draw its scene's triangles (DerivedScene)
  DrawBuffers* buffers = nullptr;         // keeps the front end's output and the triangles (none: a frame's own)
  const std::vector<TriangleRange>* only = nullptr;  // set up only these triangles (of the scene drawn)
};

/// A frame's drawing step: draws `work.triangles` into the frame and resolves them, counting into
/// `work.counters`, adding its buffers to the frame's memory and timing its own stages if it
/// likes (what it does not time is "raster").
using DrawStep = std::function<void(FrameWork& work, const TriangleShader& shade)>;

/// One frame, in the same steps for every drawing algorithm: the front end sets up the scene's
/// triangles (or, with `derived`, its scene's) in submission order ("frontend"); `order`
/// reorders them ("order"); the frame is cleared ("clear"); `draw` draws and resolves them
/// ("raster", less the stages it timed itself); the statistics common to all are filled
/// (recordDrawStats).
void drawFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, const FrameSteps& steps,
               const DrawStep& draw, Frame& frame);

/// The statistics every drawing fills, one way for all: the front end's counts, the counters,
/// the memory of the set-up triangles, the front end's and the frame's (the caller adds its own
/// buffers'), and the depth format when the drawing tested depth (`depthFormat` not null).
void recordDrawStats(Stats& st, const FrontEndCounters& fe, uint64_t frontEndBytes, size_t setupTriangles,
                     const DrawCounters& n, const DepthFormat* depthFormat, const Frame& frame);

/// A frame through the drawing service: drawFrame whose draw step draws the triangles in their
/// order under `rule` on `raster` (each pixel's written fragments in Frame::writes, when sized),
/// with the details "rasterizer" and "write_rule". `exactOrder`: the order is right for every
/// pair of fragments that overlap (the BSP tree's), so each pixel keeps its nearest fragment;
/// on DrawRaster::Tiled, that rule and the depth test cull hidden meshes first
/// (TiledZBuffer::visibleMeshes: the same image, fewer triangles set up).
void drawScene(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
               DrawRaster raster, const OrderFn& order, DrawBuffers& buffers, Frame& frame,
               const DerivedScene* derived = nullptr, bool exactOrder = false);

}  // namespace hsr::algo

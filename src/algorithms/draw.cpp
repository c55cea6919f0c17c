// The drawing service (draw.hpp): fragments of set-up triangles, in the caller's order, applied
// to the frame under a write rule, then resolved into face ids, exact eye depths and colours.
#include "algorithms/draw.hpp"

#include <algorithm>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "scene/shading.hpp"
#include "core/timer.hpp"
#include "setup/fragment_depth.hpp"
#include "raster/halfspace.hpp"
#include "raster/scanline.hpp"

namespace hsr::algo {
namespace {

constexpr int kBinTile = 64;  // the Binned rasterizer's tile side, in pixels

// `src` composited over `dst` with src's alpha (the "over" operator, 8 bits, rounded).
Rgba8 over(Rgba8 src, Rgba8 dst) {
  const unsigned a = src.a, keep = 255 - a;
  auto mix = [&](uint8_t s, uint8_t d) { return uint8_t((s * a + d * keep + 127) / 255); };
  return {mix(src.r, dst.r), mix(src.g, dst.g), mix(src.b, dst.b), uint8_t(a + (dst.a * keep + 127) / 255)};
}

// What front-to-back blending keeps per pixel: the premultiplied colour of the fragments so far
// (0..255 scale) and the share of light still coming through them (1: nothing yet; 0: opaque).
struct UnderSum {
  float r = 0, g = 0, b = 0, through = 1;
  // `src` (straight alpha) composited under what is there: the "under" operator.
  void addUnder(Rgba8 src) {
    const float w = through * (src.a / 255.0f);
    r += w * src.r;
    g += w * src.g;
    b += w * src.b;
    through = src.a == 255 ? 0.0f : through * (1 - src.a / 255.0f);
  }
  // The pixel over an opaque background, rounded once to 8 bits (half away from zero, as
  // std::lround: v is never negative, and v + 0.5 is exact in double).
  Rgba8 over(Rgba8 background) const {
    auto byte = [](float v) { return uint8_t(std::clamp(std::floor(double(v) + 0.5), 0.0, 255.0)); };
    return {byte(r + through * background.r), byte(g + through * background.g), byte(b + through * background.b),
            255};
  }
};

// ---- The write rules, each a policy: what a fragment does to its pixel ----
//
// A rule's write(p, f, n) applies fragment f to its pixel in the per-pixel state p (Pixels
// below) and says whether it wrote; the writer counts a write one way for all (countWritten).
// kDepth: it keeps a depth buffer; kColorAtResolve: a pixel's colour is its winner's, written
// when resolved (else the rule composites colour as it draws); kStopsWhenFull: nothing drawn
// once every pixel is `filled` can change the image.

// What a rule sees of one fragment: its triangle's index, its pixel and stored depth value.
template <class T>
struct Fragment {
  uint32_t i;
  int x, y;
  size_t idx;
  T z;
};

// The z-buffer: written where strictly nearer than the stored depth (ties keep the first).
struct DepthTestRule {
  static constexpr WriteRule kRule = WriteRule::DepthTest;
  static constexpr bool kDepth = true, kColorAtResolve = true, kStopsWhenFull = false;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters& n) {
    if (!depthTest<P::kMapping>(f.z, p.depth[f.idx], n)) return false;
    p.winner[f.idx] = f.i + 1;
    return true;
  }
};

// The painter's: every fragment overwrites.
struct OverwriteRule {
  static constexpr WriteRule kRule = WriteRule::Overwrite;
  static constexpr bool kDepth = false, kColorAtResolve = true, kStopsWhenFull = false;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters&) {
    p.winner[f.idx] = f.i + 1;
    return true;
  }
};

// The reverse painter's: written only where nothing was written yet.
struct WhereUnwrittenRule {
  static constexpr WriteRule kRule = WriteRule::WhereUnwritten;
  static constexpr bool kDepth = false, kColorAtResolve = true, kStopsWhenFull = true;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters& n) {
    if (p.winner[f.idx]) return false;
    ++n.filled;
    p.winner[f.idx] = f.i + 1;
    return true;
  }
};

// Transparency back to front: the colour composited over by the triangle's alpha; ids overwritten.
struct BlendRule {
  static constexpr WriteRule kRule = WriteRule::Blend;
  static constexpr bool kDepth = false, kColorAtResolve = false, kStopsWhenFull = false;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters&) {
    p.winner[f.idx] = f.i + 1;
    if (p.color) p.frame.color[f.idx] = over(p.colorOf(f.i), p.frame.color[f.idx]);
    return true;
  }
};

// The z-buffer's transparent pass: depth-tested; an opaque triangle writes depth, a transparent
// one only composites its colour over. The ids show the nearest fragment drawn, transparent or not.
struct DepthTestBlendRule {
  static constexpr WriteRule kRule = WriteRule::DepthTestBlend;
  static constexpr bool kDepth = true, kColorAtResolve = false, kStopsWhenFull = false;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters& n) {
    if (!passesDepthTest<P::kMapping>(f.z, p.depth[f.idx], n)) return false;
    const Rgba8 c = p.colorOf(f.i);
    if (c.a == 255) storeDepth(f.z, p.depth[f.idx], n);
    const double d = p.tris[f.i].eyeDepth(f.x + 0.5, f.y + 0.5);
    if (d < p.nearest[f.idx]) {
      p.nearest[f.idx] = d;
      p.winner[f.idx] = f.i + 1;
    }
    if (p.color) p.frame.color[f.idx] = over(c, p.frame.color[f.idx]);
    return true;
  }
};

// The reverse painter's with transparency: front to back, each fragment composited under what
// the pixel holds until it is opaque; ids the first (nearest); the background under all at the end.
struct BlendUnderRule {
  static constexpr WriteRule kRule = WriteRule::BlendUnder;
  static constexpr bool kDepth = false, kColorAtResolve = false, kStopsWhenFull = true;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters& n) {
    if (p.color ? p.sums[f.idx].through == 0 : p.winner[f.idx] != 0) return false;  // opaque: nothing behind shows
    if (!p.winner[f.idx]) p.winner[f.idx] = f.i + 1;  // the first fragment is the nearest
    if (!p.color) {
      ++n.filled;
      return true;
    }
    p.sums[f.idx].addUnder(p.colorOf(f.i));
    if (p.sums[f.idx].through == 0) ++n.filled;
    return true;
  }
};

// Depth peeling: the z-buffer among the fragments that come after the layer peeled before in the
// order (stored depth, drawing order), so that layer after layer visits every fragment of a pixel
// once, ties in depth included.
struct DepthPeelRule {
  static constexpr WriteRule kRule = WriteRule::DepthPeel;
  static constexpr bool kDepth = true, kColorAtResolve = true, kStopsWhenFull = false;
  template <class P, class T>
  static bool write(P& p, const Fragment<T>& f, DrawCounters& n) {
    if (!p.peeledWinner.empty()) {
      const uint32_t before = p.peeledWinner[f.idx];
      if (!before) return false;  // the layer before was empty here: nothing lies beyond
      const T floor = p.peeledDepth[f.idx];
      ++n.depthTests;
      if (!(storedNearer<P::kMapping>(double(floor), double(f.z)) || (floor == f.z && f.i + 1 > before))) return false;
    }
    return DepthTestRule::write(p, f, n);
  }
};

// One frame's per-pixel state, for depth storage S and mapping M (the depth buffer is used by the
// depth rules only): what the rules read and write.
template <DepthStorage S, DepthMapping M>
struct Pixels {
  using T = DepthT<S>;
  static constexpr DepthMapping kMapping = M;
  std::span<const SetupTriangle> tris;
  const TriangleShader& shade;
  const DerivedScene* derived;
  Frame& frame;
  bool color;
  std::vector<T>& depth;           // the depth rules: the stored values
  std::vector<uint32_t>& winner;   // 1 + the index of the winning (last written) triangle, 0 = none
  std::vector<double> nearest;     // DepthTestBlend: the eye depth of the winner's fragment
  std::vector<UnderSum> sums;      // BlendUnder: each pixel's blend so far
  const std::vector<T>& peeledDepth;           // DepthPeel: the layer peeled before (DrawBuffers)
  const std::vector<uint32_t>& peeledWinner;

  Rgba8 colorOf(uint32_t i) const { return algo::colorOf(tris[i], shade, derived); }
};

// The drawing service's writer under rule R: the frame's pixels, fragment by fragment, then
// resolved into face ids, exact eye depths and colours.
template <class R, DepthStorage S, DepthMapping M>
class FragmentWriter {
 public:
  using T = DepthT<S>;

  FragmentWriter(std::span<const SetupTriangle> tris, const Camera& cam, const RenderOptions& opt,
                 const TriangleShader& shade, DrawBuffers& buffers, Frame& frame, const DerivedScene* derived)
      : cam_(cam), opt_(opt), clear_(quantizeDepth<S>(opt.depthFormat.clearValue())),
        p_{tris,
           shade,
           derived,
           frame,
           /*color=*/has(opt.outputs, FrameOutputs::Color),
           buffers.depth<T>(),
           buffers.winner(),
           {},
           {},
           buffers.peeledDepth<T>(),
           buffers.peeledWinner()} {
    const size_t pixels = size_t(cam.width) * size_t(cam.height);
    if constexpr (R::kDepth) p_.depth.assign(pixels, clear_);
    else p_.depth.clear();
    if constexpr (R::kRule == WriteRule::DepthTestBlend) p_.nearest.assign(pixels, INFINITY);
    if constexpr (R::kRule == WriteRule::BlendUnder)
      if (p_.color) p_.sums.assign(pixels, UnderSum{});
    p_.winner.assign(pixels, 0);
  }

  void addMemory(Stats& st) const {
    st.addMemory("depth_buffer", p_.depth.size() * sizeof(T));
    st.addMemory("winner_ids", p_.winner.size() * sizeof(uint32_t));
    st.addMemory("triangle_colors", colors_.size() * sizeof(Rgba8));
    st.addMemory("nearest_depths", p_.nearest.size() * sizeof(double));
    st.addMemory("blend_sums", p_.sums.size() * sizeof(UnderSum));
  }

  // Every triangle's shaded colour, once, for resolving (triangleColors).
  void shadeTriangles(int threads) {
    if (p_.color && R::kColorAtResolve) colors_ = triangleColors(p_.tris, p_.shade, p_.derived, threads);
  }

  // Every fragment of triangle i inside pixels [x0, x1] x [y0, y1], through the rule.
  void draw(uint32_t i, DrawRaster raster, int x0, int y0, int x1, int y1, DrawCounters& counters) {
    const SetupTriangle t = clippedTo(p_.tris[i], x0, y0, x1, y1);
    if (t.minX > t.maxX || t.minY > t.maxY) return;
    const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, cam_.near, cam_.far, cam_.orthographic);
    DrawCounters n;  // counted in registers, added once per triangle
    if (raster == DrawRaster::Scanline) {
      // The eye depth stepped along the span, mapped and stored (the lecture notes' inner loop).
      rasterizeScanline(t, [&](int x, int y, double eyeDepth) {
        apply(i, x, y, [&] { return quantizeDepth<S>(mapDepth<M>(eyeDepth, cam_.near, cam_.far, cam_.orthographic)); }, n);
      });
    } else {
      // The stored value from the plane at the pixel centre, as the tiled kernel computes it.
      rasterizeHalfSpace(t, [&](int x, int y, double) {
        apply(i, x, y, [&] { return T(fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5))); }, n);
      });
    }
    counters.add(n);
  }

  // Rows [y0, y1) resolved (resolvePixels): the colours drawn as the rule composited them, or each
  // winner's; under BlendUnder, the background under everything drawn first.
  void resolveRows(int y0, int y1, DrawCounters& n) {
    Frame& frame = p_.frame;
    if constexpr (R::kRule == WriteRule::BlendUnder)
      if (p_.color)
        for (int y = y0; y < y1; ++y)
          for (int x = 0; x < cam_.width; ++x) frame.color[frame.index(x, y)] = p_.sums[frame.index(x, y)].over(opt_.background);
    const PixelRect rows{0, y0, cam_.width - 1, y1 - 1, size_t(cam_.width)};
    const size_t offset = size_t(y0) * size_t(cam_.width);
    const std::span<const uint32_t> winner = std::span<const uint32_t>(p_.winner).subspan(offset);
    const bool colorAtResolve = p_.color && R::kColorAtResolve;
    resolvePixels(
        rows, winner, p_.tris, opt_.outputs, p_.derived,
        [&](uint32_t w, size_t idx) {
          if (colorAtResolve) frame.color[idx] = colors_[w];
        },
        frame, n);
  }

 private:
  // One fragment of triangle i at pixel (x, y) through the rule; `stored()` gives its depth value
  // when the rule keeps depth.
  template <class Stored>
  void apply(uint32_t i, int x, int y, Stored&& stored, DrawCounters& n) {
    const size_t idx = p_.frame.index(x, y);
    T z{};
    if constexpr (R::kDepth) z = stored();
    if (R::write(p_, Fragment<T>{i, x, y, idx, z}, n)) countWritten(idx, p_.frame, n);
  }

  const Camera& cam_;
  const RenderOptions& opt_;
  const T clear_;
  Pixels<S, M> p_;
  std::vector<Rgba8> colors_;  // per triangle: its colour (shadeTriangles)
};

// The Binned rasterizer's tiles of the camera's frame, row by row.
size_t binnedTiles(const Camera& cam) {
  return size_t((cam.width + kBinTile - 1) / kBinTile) * size_t((cam.height + kBinTile - 1) / kBinTile);
}

// The triangles binned into the Binned rasterizer's tiles (binByCell), and fn(tile, x0, y0, x1,
// y1, bin) for each tile on up to `threads` threads of the pool: its pixels [x0, x1] x [y0, y1],
// which are its own, and its triangles in drawing order. Returns the bins' bytes.
template <class Fn>
uint64_t forEachBinnedTile(std::span<const SetupTriangle> tris, const Camera& cam, int threads, Fn&& fn) {
  const int tilesX = (cam.width + kBinTile - 1) / kBinTile, tilesY = (cam.height + kBinTile - 1) / kBinTile;
  const std::vector<std::vector<uint32_t>> bins = binByCell(tris, kBinTile, kBinTile, tilesX, tilesY);
  parallelFor(0, bins.size(), threads, [&](size_t tile) {
    const int x0 = int(tile % size_t(tilesX)) * kBinTile, y0 = int(tile / size_t(tilesX)) * kBinTile;
    const int x1 = std::min(x0 + kBinTile, cam.width) - 1, y1 = std::min(y0 + kBinTile, cam.height) - 1;
    fn(tile, x0, y0, x1, y1, std::span<const uint32_t>(bins[tile]));
  });
  return binBytes(bins);
}

// The frame drawn and resolved by one writer: on one thread over the whole image, or binned,
// tile by tile on the pool (each tile's pixels are its own; counters summed in tile order).
template <class R, DepthStorage S, DepthMapping M>
void drawWith(std::span<const SetupTriangle> tris, DrawRaster raster, const Camera& cam, const RenderOptions& opt,
              const TriangleShader& shade, DrawBuffers& buffers, Frame& frame, DrawCounters& counters,
              const DerivedScene* derived) {
  FragmentWriter<R, S, M> writer(tris, cam, opt, shade, buffers, frame, derived);
  const int threads = resolveThreads(opt.threads);
  // The reverse painter's stops where every pixel is written: nothing more can show.
  auto full = [](const DrawCounters& n, uint64_t pixels) {
    return R::kStopsWhenFull && n.filled == pixels;
  };
  if (raster != DrawRaster::Binned) {
    const uint64_t pixels = uint64_t(cam.width) * uint64_t(cam.height);
    for (uint32_t i = 0; i < tris.size(); ++i) {
      if (full(counters, pixels)) {
        counters.skippedFull += tris.size() - i;
        break;
      }
      writer.draw(i, raster, 0, 0, cam.width - 1, cam.height - 1, counters);
    }
    writer.shadeTriangles(1);
    writer.resolveRows(0, cam.height, counters);
    writer.addMemory(frame.stats);
    return;
  }
  std::vector<DrawCounters> perTile(binnedTiles(cam));
  const uint64_t binsBytes = forEachBinnedTile(
      tris, cam, threads, [&](size_t tile, int x0, int y0, int x1, int y1, std::span<const uint32_t> bin) {
        const uint64_t pixels = uint64_t(x1 - x0 + 1) * uint64_t(y1 - y0 + 1);
        for (size_t k = 0; k < bin.size(); ++k) {
          if (full(perTile[tile], pixels)) {
            perTile[tile].skippedFull += bin.size() - k;
            break;
          }
          writer.draw(bin[k], DrawRaster::HalfSpace, x0, y0, x1, y1, perTile[tile]);
        }
      });
  writer.shadeTriangles(threads);
  std::vector<DrawCounters> perRow(size_t(cam.height));
  parallelFor(0, size_t(cam.height), threads, [&](size_t y) { writer.resolveRows(int(y), int(y) + 1, perRow[y]); });
  for (const DrawCounters& c : perTile) counters.add(c);
  for (const DrawCounters& c : perRow) counters.add(c);
  writer.addMemory(frame.stats);
  frame.stats.addMemory("bins", binsBytes);
}

// The triangles drawn in their order under `rule` into the cleared frame, counted into
// `counters`: one writer per rule and, for the depth rules, per depth format.
void drawOrdered(std::span<const SetupTriangle> triangles, WriteRule rule, DrawRaster raster, const Camera& camera,
                 const RenderOptions& options, const TriangleShader& shade, DrawBuffers& buffers, Frame& frame,
                 DrawCounters& counters, const DerivedScene* derived) {
  auto withRule = [&]<class R>() {
    if constexpr (R::kDepth)
      visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
        drawWith<R, S, M>(triangles, raster, camera, options, shade, buffers, frame, counters, derived);
      });
    else  // no depth buffer: one instance
      drawWith<R, DepthStorage::F32, DepthMapping::Reversed>(triangles, raster, camera, options, shade, buffers,
                                                             frame, counters, derived);
  };
  switch (rule) {
    case WriteRule::DepthTest: return withRule.template operator()<DepthTestRule>();
    case WriteRule::Overwrite: return withRule.template operator()<OverwriteRule>();
    case WriteRule::WhereUnwritten: return withRule.template operator()<WhereUnwrittenRule>();
    case WriteRule::Blend: return withRule.template operator()<BlendRule>();
    case WriteRule::DepthTestBlend: return withRule.template operator()<DepthTestBlendRule>();
    case WriteRule::BlendUnder: return withRule.template operator()<BlendUnderRule>();
    case WriteRule::DepthPeel: return withRule.template operator()<DepthPeelRule>();
  }
}

// The colours of Blend and BlendUnder drawn with the tile kernel, into frame.color: the same bits
// as the rules' scalar forms. An opaque fragment hides what Blend drew before it and what
// BlendUnder draws after it, so (1) a first-wins kernel pass over the opaque triangles finds each
// pixel's deciding one (the last in the list under Blend, the first under BlendUnder), and (2) the
// scalar rasterizer, binned on threads, composites only the transparent fragments that still show:
// after it, over its colour (Blend), or before it, with its colour under them (BlendUnder).
// Returns the fragments that wrote colour.
uint64_t blendOnKernel(std::span<const SetupTriangle> list, WriteRule rule, const Camera& camera,
                       const RenderOptions& options, const TriangleShader& shade, DrawBuffers& buffers, Frame& frame) {
  const bool under = rule == WriteRule::BlendUnder;
  std::vector<Rgba8> colors(list.size());
  for (size_t i = 0; i < list.size(); ++i) colors[i] = triangleColor(list[i], shade);
  // The opaque triangles, each carrying its place in the list as its triangle id, in the order
  // whose first wins; the transparent ones and their places, in the list's order.
  std::vector<SetupTriangle> opaque, clear;
  std::vector<uint32_t> clearAt;
  for (size_t k = 0; k < list.size(); ++k) {
    const size_t i = under ? k : list.size() - 1 - k;
    if (colors[i].a == 255) opaque.push_back(list[i]), opaque.back().triangle = uint32_t(i);
  }
  for (size_t i = 0; i < list.size(); ++i)
    if (colors[i].a != 255) clear.push_back(list[i]), clearAt.push_back(uint32_t(i));

  // 1. Each pixel's deciding opaque fragment: its place in the list, -1 where none.
  Frame& decided = buffers.opaqueLayer();
  decided.allocate(camera.width, camera.height, FrameOutputs::TriangleIds);
  RenderOptions idsOnly = options;
  idsOnly.outputs = FrameOutputs::TriangleIds;
  const TiledZBuffer::InOrderCounts c =
      buffers.tiled().drawInOrder(opaque, /*firstWins=*/true, camera, idsOnly, shade, decided);
  const std::span<const int32_t> opaqueAt(decided.triangleId);

  // 2. The transparent fragments that still show, tile by tile.
  std::vector<uint64_t> composited(binnedTiles(camera), 0);
  auto composite = [&](size_t tile, int x0, int y0, int x1, int y1, std::span<const uint32_t> bin) {
    auto pixels = [&](auto&& visit) {
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) visit(frame.index(x, y), size_t(y - y0) * kBinTile + size_t(x - x0));
    };
    std::vector<UnderSum> sums(under ? size_t(kBinTile) * kBinTile : 0);
    if (!under)  // Blend starts from the deciding fragment's colour, or the background
      pixels([&](size_t idx, size_t) {
        frame.color[idx] = opaqueAt[idx] >= 0 ? colors[size_t(opaqueAt[idx])] : options.background;
      });
    for (uint32_t k : bin) {
      const SetupTriangle t = clippedTo(clear[k], x0, y0, x1, y1);
      if (t.minX > t.maxX || t.minY > t.maxY) continue;
      const int64_t at = clearAt[k];
      const Rgba8 src = colors[at];
      rasterizeHalfSpace(t, [&](int x, int y, double) {
        const size_t idx = frame.index(x, y);
        const int64_t deciding = opaqueAt[idx];
        if (!under) {
          if (at < deciding) return;  // hidden by a later opaque fragment
          frame.color[idx] = over(src, frame.color[idx]);
        } else {
          UnderSum& sum = sums[size_t(y - y0) * kBinTile + size_t(x - x0)];
          if ((deciding >= 0 && at > deciding) || sum.through == 0) return;  // behind what is opaque
          sum.addUnder(src);
        }
        ++composited[tile];
      });
    }
    if (under)  // the deciding fragment under the transparent ones, then the background
      pixels([&](size_t idx, size_t s) {
        if (opaqueAt[idx] >= 0 && sums[s].through != 0) sums[s].addUnder(colors[size_t(opaqueAt[idx])]);
        frame.color[idx] = sums[s].over(options.background);
      });
  };
  const uint64_t binsBytes = forEachBinnedTile(clear, camera, resolveThreads(options.threads), composite);
  frame.stats.addMemory("opaque_layer", decided.depth.size() * (sizeof(float) + sizeof(int32_t)));
  frame.stats.addMemory("bins", binsBytes);
  uint64_t writes = c.wins;
  for (uint64_t n : composited) writes += n;
  return writes;
}

// The frame's triangles through the tile kernel (DrawRaster::Tiled, TiledZBuffer::drawInOrder),
// counted as the drawing service counts: a list-priority rule as "the first in a list wins" (the
// drawing order under WhereUnwritten; reversed under Overwrite, whose last fragment wins; Blend's
// and BlendUnder's ids and depths as theirs, their colours by blendOnKernel), with the scene's ids
// and colours when the triangles are derived geometry. Returns the rasterizer that drew: Binned
// for a list longer than the priority keys.
DrawRaster drawOnKernel(FrameWork& work, WriteRule rule, const Camera& camera, const RenderOptions& options,
                  const TriangleShader& shade, const DerivedScene* derived, DrawBuffers& buffers, Frame& frame) {
  std::vector<SetupTriangle>& list = work.triangles;
  const bool depthTest = rule == WriteRule::DepthTest;
  if (!depthTest && list.size() > TiledZBuffer::kMostFirstWins) {  // more than it has priority keys for
    frame.clear(options.background, resolveThreads(options.threads));
    drawOrdered(list, rule, DrawRaster::Binned, camera, options, shade, buffers, frame, work.counters, derived);
    return DrawRaster::Binned;
  }
  const bool color = has(options.outputs, FrameOutputs::Color);
  if (derived) {
    std::vector<uint32_t> originals(color ? list.size() : 0);
    for (size_t i = 0; i < list.size(); ++i) {
      SetupTriangle& t = list[i];
      t.face = derived->face[t.face];
      t.triangle = derived->triangle[t.triangle];
      if (color) originals[i] = t.triangle;
    }
    if (color) {  // each its original triangle's colour (colorOf), shaded in SIMD batches
      std::vector<Rgba8> colors(list.size());
      shade.shadeMany(originals.data(), originals.size(), colors.data());
      for (size_t i = 0; i < list.size(); ++i) list[i].color = colors[i], list[i].frontFacing = true;
    }
  }
  // Blending: the colours composited first (in the list's order); the ids and depths are the
  // last fragment's (Blend, as Overwrite) or the first's (BlendUnder, as WhereUnwritten).
  const bool blends = rule == WriteRule::Blend || rule == WriteRule::BlendUnder;
  const uint64_t blended = blends && color ? blendOnKernel(list, rule, camera, options, shade, buffers, frame) : 0;
  RenderOptions drawn = options;
  if (blends) drawn.outputs = FrameOutputs(uint8_t(options.outputs) & ~uint8_t(FrameOutputs::Color));
  if (rule == WriteRule::Overwrite || rule == WriteRule::Blend) std::reverse(list.begin(), list.end());
  const TiledZBuffer::InOrderCounts c =
      buffers.tiled().drawInOrder(list, /*firstWins=*/!depthTest, camera, drawn, shade, frame);
  DrawCounters& n = work.counters;
  if (depthTest) n.depthTests = c.tests, n.depthWrites = c.wins;
  n.written = c.wins;
  n.colorWrites = !color ? 0 : blends ? blended : c.wins;
  n.covered = c.covered;
  n.skippedFull = depthTest ? 0 : c.skippedPairs;
  frame.stats.addMemory("tiled_state", c.memoryBytes);
  return DrawRaster::Tiled;
}

// Whether DrawRaster::Tiled draws `rule` (else the frame is drawn Binned): the depth test and
// the list-priority rules, blending or not. It does not count each pixel's writes: a frame that
// asks is refused.
bool kernelDraws(WriteRule rule, const Frame& frame) {
  const bool draws = rule == WriteRule::DepthTest || rule == WriteRule::Overwrite ||
                     rule == WriteRule::WhereUnwritten || rule == WriteRule::Blend || rule == WriteRule::BlendUnder;
  if (draws && !frame.writes.empty())
    throw InputError(Setting::OverdrawImage, "",
                     "raster=tiled does not count writes per pixel (the tile kernel replaces whole blocks at once); "
                     "raster=binned draws the same image and does");
  return draws;
}

}  // namespace

DrawBuffers::DrawBuffers() = default;
DrawBuffers::~DrawBuffers() = default;
DrawBuffers::DrawBuffers(DrawBuffers&&) noexcept = default;
DrawBuffers& DrawBuffers::operator=(DrawBuffers&&) noexcept = default;

TiledZBuffer& DrawBuffers::tiled() {
  if (!tiled_) tiled_ = std::make_unique<TiledZBuffer>();
  return *tiled_;
}

SetupTriangle clippedTo(const SetupTriangle& t, int x0, int y0, int x1, int y1) {
  SetupTriangle c = t;
  c.minX = int16_t(std::max<int>(t.minX, x0));
  c.minY = int16_t(std::max<int>(t.minY, y0));
  c.maxX = int16_t(std::min<int>(t.maxX, x1));
  c.maxY = int16_t(std::min<int>(t.maxY, y1));
  return c;
}

std::vector<std::vector<uint32_t>> binByCell(std::span<const SetupTriangle> triangles, int cellWidth, int cellHeight,
                                             int columns, int rows) {
  std::vector<std::vector<uint32_t>> bins(size_t(columns) * size_t(rows));
  for (uint32_t i = 0; i < triangles.size(); ++i) {
    const SetupTriangle& t = triangles[i];
    if (t.minX > t.maxX || t.minY > t.maxY) continue;
    for (int cy = t.minY / cellHeight; cy <= t.maxY / cellHeight; ++cy)
      for (int cx = t.minX / cellWidth; cx <= t.maxX / cellWidth; ++cx)
        bins[size_t(cy) * size_t(columns) + size_t(cx)].push_back(i);
  }
  return bins;
}

std::vector<Rgba8> triangleColors(std::span<const SetupTriangle> tris, const TriangleShader& shade,
                                  const DerivedScene* derived, int threads) {
  std::vector<Rgba8> colors(tris.size());
  constexpr size_t kChunk = 4096;
  parallelFor(0, (tris.size() + kChunk - 1) / kChunk, threads, [&](size_t chunk) {
    for (size_t i = chunk * kChunk; i < std::min(tris.size(), (chunk + 1) * kChunk); ++i)
      colors[i] = colorOf(tris[i], shade, derived);
  });
  return colors;
}

uint64_t binBytes(const std::vector<std::vector<uint32_t>>& bins) {
  uint64_t bytes = bins.capacity() * sizeof(bins[0]);
  for (const auto& b : bins) bytes += b.capacity() * sizeof(uint32_t);
  return bytes;
}

void recordDrawStats(Stats& st, const FrontEndCounters& fe, uint64_t frontEndBytes, size_t setupTriangles,
                     const DrawCounters& n, const DepthFormat* depthFormat, const Frame& frame) {
  if (depthFormat) st.depth_format = depthFormat->name();
  st.triangles_clipped = fe.clipped;
  st.triangles_degenerate = fe.degenerate;
  st.culled_backface = fe.culledBackface;
  st.culled_frustum = fe.culledFrustum;
  st.depth_tests = n.depthTests;
  st.depth_writes = n.depthWrites;
  st.color_writes = n.colorWrites;
  st.covered_pixels = n.covered;
  st.addMemory("setup_triangles", setupTriangles * sizeof(SetupTriangle));
  st.addMemory("front_end", frontEndBytes);
  addFrameMemory(st, frame);
}

const char* writeRuleName(WriteRule rule) {
  switch (rule) {
    case WriteRule::DepthTest: return "depth-test";
    case WriteRule::Overwrite: return "overwrite";
    case WriteRule::WhereUnwritten: return "where-unwritten";
    case WriteRule::Blend: return "blend";
    case WriteRule::DepthTestBlend: return "depth-test-blend";
    case WriteRule::BlendUnder: return "blend-under";
    case WriteRule::DepthPeel: return "depth-peel";
  }
  return "?";
}

const char* drawRasterName(DrawRaster raster) {
  switch (raster) {
    case DrawRaster::HalfSpace: return "halfspace";
    case DrawRaster::Scanline: return "scanline";
    case DrawRaster::Binned: return "binned";
    case DrawRaster::Tiled: return "tiled";
  }
  return "?";
}

ParamSpec drawRasterParam(const char* defaultValue, bool kernel) {
  if (!kernel)
    return {"raster", ParamType::Choice, defaultValue, {"halfspace", "scanline", "binned"}, -1e300, 1e300,
            "fragments from the scalar half-space rasterizer on one thread (the reference), the lecture notes' "
            "scanline rasterizer, or the half-space rasterizer binned into 64x64 tiles on threads"};
  return {"raster", ParamType::Choice, defaultValue, {"halfspace", "scanline", "binned", "tiled"}, -1e300, 1e300,
          "fragments from the scalar half-space rasterizer on one thread (the reference), the lecture notes' "
          "scanline rasterizer, the half-space rasterizer binned into 64x64 tiles on threads, or the z-buffer's "
          "SIMD tile kernel: the same image, the first fragment in priority order winning each pixel (the "
          "sorted z-buffer's transparent pass draws binned; no overdraw picture)"};
}

DrawRaster drawRasterOf(const AlgorithmParams& params) {
  const std::string& name = params.text("raster");
  return name == "scanline" ? DrawRaster::Scanline
         : name == "binned"  ? DrawRaster::Binned
         : name == "tiled"   ? DrawRaster::Tiled
                             : DrawRaster::HalfSpace;
}

void drawFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, const FrameSteps& steps,
               const DrawStep& draw, Frame& frame) {
  Timer timer;
  Stats& st = frame.stats;
  const TriangleShader shade(scene, camera, options.shading);  // (the original scene's faces)
  FrameWork work;
  DrawBuffers::FrameScratch* kept = steps.buffers ? &steps.buffers->frameScratch() : nullptr;
  if (kept) work.triangles.swap(kept->triangles);  // (given back below)
  if (steps.setUp) {
    FrontEndOutput own;
    FrontEndOutput& fe = kept ? kept->frontEnd : own;
    // (with `only`, clusters are not culled whole: its ranges need not be unions of meshes)
    const FrontEndOptions only{.deferClusters = steps.only == nullptr, .only = steps.only};
    if (steps.derived) {  // unshaded: a derived triangle takes its original's colour (colorOf)
      RenderOptions unshaded = options;
      unshaded.outputs = FrameOutputs(uint8_t(options.outputs) & ~uint8_t(FrameOutputs::Color));
      runFrontEnd(*steps.derived->scene, camera, unshaded, fe, {}, only);
    } else {
      runFrontEnd(scene, camera, options, fe, {}, only);
    }
    fe.flattenInto(work.triangles);
    work.frontEnd = fe;
    work.frontEndBytes = fe.memoryBytes();
    st.addTime("frontend", timer.lap());
  }
  if (steps.order) {
    steps.order(work.triangles);
    st.addTime("order", timer.lap());
  }
  if (steps.clearFrame) {
    frame.clear(options.background, resolveThreads(options.threads));
    st.addTime("clear", timer.lap());
  }
  auto timed = [&] {
    double ms = 0;
    for (const auto& [stage, t] : st.time_ms) ms += t;
    return ms;
  };
  const double before = timed();
  draw(work, shade);
  const double elapsed = timer.lap(), ownStages = timed() - before;
  st.addTime("raster", std::max(0.0, elapsed - ownStages));
  // (the frame's set-up triangles, not the kept buffers' capacity, which depends on earlier frames)
  recordDrawStats(st, work.frontEnd, work.frontEndBytes, work.triangles.size(), work.counters,
                  steps.depthTested ? &options.depthFormat : nullptr, frame);
  if (kept) work.triangles.swap(kept->triangles);
}

// The triangles of the scene drawn (derived geometry's, when given) whose scene meshes mesh
// culling left (TiledZBuffer::visibleMeshes), or null: all of them. Counts the meshes culled.
const std::vector<TriangleRange>* unculledTriangles(const Scene& scene, const Camera& camera,
                                                   const RenderOptions& options, const DerivedScene* derived,
                                                   DrawBuffers& buffers, uint64_t& meshesCulled) {
  const std::vector<TriangleRange>* visible = buffers.tiled().visibleMeshes(scene, camera, options, meshesCulled);
  if (!visible || !derived) return visible;
  // The derived triangles whose original triangle is left, as runs.
  std::vector<uint8_t> left(scene.triangles.size(), 0);
  for (const TriangleRange& r : *visible) std::fill(left.begin() + r.first, left.begin() + r.end, uint8_t(1));
  std::vector<TriangleRange>& only = buffers.frameScratch().only;
  only.clear();
  for (uint32_t t = 0; t < derived->triangle.size(); ++t) {
    if (!left[derived->triangle[t]]) continue;
    if (!only.empty() && only.back().end == t) ++only.back().end;
    else only.push_back({t, t + 1});
  }
  return &only;
}

void drawScene(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
               DrawRaster raster, const OrderFn& order, DrawBuffers& buffers, Frame& frame,
               const DerivedScene* derived, bool exactOrder) {
  const bool depthTested =
      rule == WriteRule::DepthTest || rule == WriteRule::DepthTestBlend || rule == WriteRule::DepthPeel;
  uint64_t skippedFull = 0;
  if (raster == DrawRaster::Tiled && !kernelDraws(rule, frame)) raster = DrawRaster::Binned;
  const bool onKernel = raster == DrawRaster::Tiled;
  uint64_t meshesCulled = 0;
  Timer culling;
  // (mesh culling hides what lies behind opaque meshes: not for the blending rules)
  const bool blends = rule == WriteRule::Blend || rule == WriteRule::BlendUnder;
  const bool keepsNearest = rule == WriteRule::DepthTest || (exactOrder && !blends);
  const std::vector<TriangleRange>* only =
      onKernel && keepsNearest ? unculledTriangles(scene, camera, options, derived, buffers, meshesCulled) : nullptr;
  if (only) frame.stats.addTime("cull", culling.ms());
  drawFrame(scene, camera, options,
            {.order = order, .depthTested = depthTested, .clearFrame = !onKernel, .derived = derived,
             .buffers = &buffers, .only = only},
            [&](FrameWork& work, const TriangleShader& shade) {
              if (onKernel)
                raster = drawOnKernel(work, rule, camera, options, shade, derived, buffers, frame);
              else
                drawOrdered(work.triangles, rule, raster, camera, options, shade, buffers, frame, work.counters,
                            derived);
              skippedFull = work.counters.skippedFull;
            },
            frame);
  Stats& st = frame.stats;
  st.setDetail("rasterizer", drawRasterName(raster));
  st.setDetail("write_rule", writeRuleName(rule));
  if (rule == WriteRule::WhereUnwritten || rule == WriteRule::BlendUnder) st.setDetail("skipped_full", skippedFull);
  if (only) st.setDetail("meshes_culled_occlusion", meshesCulled);
}

}  // namespace hsr::algo

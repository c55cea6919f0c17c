// The drawing service (draw.hpp): fragments of set-up triangles, in the caller's order, applied
// to the frame under a write rule, then resolved into face ids, exact eye depths and colours.
#include "algorithms/draw.hpp"

#include <algorithm>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "core/shading.hpp"
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
  // The pixel over an opaque background, rounded once to 8 bits.
  Rgba8 over(Rgba8 background) const {
    auto byte = [](float v) { return uint8_t(std::clamp(std::lround(v), 0l, 255l)); };
    return {byte(r + through * background.r), byte(g + through * background.g), byte(b + through * background.b),
            255};
  }
};

// One frame's per-pixel state and the rule's work on it, for depth storage S and mapping M
// (used by DepthTest only; the other rules keep no depth buffer).
template <WriteRule R, DepthStorage S, DepthMapping M>
class FragmentWriter {
 public:
  using T = DepthT<S>;
  static constexpr bool kDepth = R == WriteRule::DepthTest || R == WriteRule::DepthTestBlend;

  FragmentWriter(std::span<const SetupTriangle> tris, const Camera& cam, const RenderOptions& opt,
                 const TriangleShader& shade, Frame& frame, const DerivedScene* derived)
      : tris_(tris), cam_(cam), opt_(opt), shade_(shade), frame_(frame), derived_(derived),
        keepWinner_(R != WriteRule::DepthTest || opt.outputs != FrameOutputs::DepthOnly),
        color_(has(opt.outputs, FrameOutputs::Color)),
        clear_(quantizeDepth<S>(opt.depthFormat.clearValue())) {
    const size_t pixels = size_t(cam.width) * size_t(cam.height);
    if constexpr (kDepth) depth_.assign(pixels, clear_);
    else depth_.clear();
    if constexpr (R == WriteRule::DepthTestBlend) nearest_.assign(pixels, INFINITY);
    if constexpr (R == WriteRule::BlendUnder) {
      if (color_) sums_.assign(pixels, UnderSum{});
      else sums_.clear();
    }
    if (keepWinner_) winner_.assign(pixels, 0);
    else winner_.clear();
  }

  void addMemory(Stats& st) const {
    st.addMemory("depth_buffer", depth_.size() * sizeof(T));
    st.addMemory("winner_ids", winner_.size() * sizeof(uint32_t));
    st.addMemory("triangle_colors", colors_.size() * sizeof(Rgba8));
    st.addMemory("nearest_depths", nearest_.size() * sizeof(double));
    st.addMemory("blend_sums", sums_.size() * sizeof(UnderSum));
  }

  // Every triangle's shaded colour, once (on the pool), for resolving: far fewer triangles than
  // pixels, and a colour is the same all over its triangle.
  void shadeTriangles(int threads) {
    if (!color_ || R == WriteRule::Blend || R == WriteRule::DepthTestBlend || R == WriteRule::BlendUnder) return;
    colors_.resize(tris_.size());
    constexpr size_t kChunk = 4096;
    parallelFor(0, (tris_.size() + kChunk - 1) / kChunk, threads, [&](size_t chunk) {
      for (size_t i = chunk * kChunk; i < std::min(tris_.size(), (chunk + 1) * kChunk); ++i) colors_[i] = colorOf(tris_[i]);
    });
  }

  // Every fragment of triangle i inside pixels [x0, x1] x [y0, y1], through the rule.
  void draw(uint32_t i, DrawRaster raster, int x0, int y0, int x1, int y1, DrawCounters& counters) {
    SetupTriangle t = tris_[i];
    t.minX = int16_t(std::max<int>(t.minX, x0));
    t.minY = int16_t(std::max<int>(t.minY, y0));
    t.maxX = int16_t(std::min<int>(t.maxX, x1));
    t.maxY = int16_t(std::min<int>(t.maxY, y1));
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

  // Face ids, exact eye depths and colours of rows [y0, y1) from the last fragment written to
  // each pixel; depth only under the depth test: the eye depth of the stored value.
  void resolveRows(int y0, int y1, DrawCounters& n) {
    const bool faceIds = has(opt_.outputs, FrameOutputs::FaceIds);
    const bool triangleIds = has(opt_.outputs, FrameOutputs::TriangleIds);
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < cam_.width; ++x) {
        const size_t idx = frame_.index(x, y);
        if constexpr (R == WriteRule::BlendUnder)  // the background under everything drawn
          if (color_) frame_.color[idx] = sums_[idx].over(opt_.background);
        if (!keepWinner_) {
          if (depth_[idx] == clear_) continue;
          frame_.depth[idx] = float(eyeDepthOfStored<S, M>(double(depth_[idx]), cam_.near, cam_.far, cam_.orthographic));
        } else {
          if (!winner_[idx]) continue;
          const SetupTriangle& t = tris_[winner_[idx] - 1];
          if (faceIds) frame_.faceId[idx] = int32_t(derived_ ? derived_->face[t.face] : t.face);
          if (triangleIds) frame_.triangleId[idx] = int32_t(derived_ ? derived_->triangle[t.triangle] : t.triangle);
          frame_.depth[idx] = float(t.eyeDepth(x + 0.5, y + 0.5));
          // (Blend composited its colours as it drew; the others show the last written.)
          if (color_ && R != WriteRule::Blend && R != WriteRule::DepthTestBlend && R != WriteRule::BlendUnder)
            frame_.color[idx] = colors_[winner_[idx] - 1];
        }
        ++n.covered;
      }
  }

 private:
  // One fragment of triangle i at pixel (x, y); `stored()` gives its depth value when the rule
  // needs one.
  template <class Stored>
  void apply(uint32_t i, int x, int y, Stored&& stored, DrawCounters& n) {
    const size_t idx = frame_.index(x, y);
    if constexpr (kDepth) {
      constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
      const T z = stored();
      ++n.depthTests;
      if (!(greater ? z > depth_[idx] : z < depth_[idx])) return;  // strictly nearer: ties keep the first
      if (R == WriteRule::DepthTest || colorOf(tris_[i]).a == 255) {
        depth_[idx] = z;
        ++n.depthWrites;
      }
    } else if constexpr (R == WriteRule::WhereUnwritten) {
      if (winner_[idx]) return;
      ++n.filled;
    } else if constexpr (R == WriteRule::BlendUnder) {
      if (color_ ? sums_[idx].through == 0 : winner_[idx] != 0) return;  // opaque: nothing behind shows
    }
    if constexpr (R == WriteRule::DepthTestBlend) {
      // The ids show the nearest fragment drawn, transparent or not (transparent ones write no depth).
      const double d = tris_[i].eyeDepth(x + 0.5, y + 0.5);
      if (d < nearest_[idx]) {
        nearest_[idx] = d;
        winner_[idx] = i + 1;
      }
    } else if (R == WriteRule::BlendUnder) {
      if (!winner_[idx]) winner_[idx] = i + 1;  // the first fragment is the nearest
      if (!color_) ++n.filled;
    } else if (keepWinner_) {
      winner_[idx] = i + 1;
    }
    ++n.written;
    if (color_) {
      ++n.colorWrites;
      if constexpr (R == WriteRule::Blend || R == WriteRule::DepthTestBlend)
        frame_.color[idx] = over(colorOf(tris_[i]), frame_.color[idx]);
      if constexpr (R == WriteRule::BlendUnder) {
        sums_[idx].addUnder(colorOf(tris_[i]));
        if (sums_[idx].through == 0) ++n.filled;
      }
    }
    if (!frame_.writes.empty()) ++frame_.writes[idx];
  }

  // The shaded colour of a set-up triangle: its original face's, when it is derived geometry.
  Rgba8 colorOf(const SetupTriangle& t) const {
    return derived_ ? shade_(derived_->triangle[t.triangle]) : triangleColor(t, shade_);
  }

  std::span<const SetupTriangle> tris_;
  const Camera& cam_;
  const RenderOptions& opt_;
  const TriangleShader& shade_;
  Frame& frame_;
  const DerivedScene* derived_;
  const bool keepWinner_, color_;
  const T clear_;
  std::vector<T>& depth_ = scratch<T, Scratch::Depth>();  // DepthTest: the stored values
  // Per pixel: 1 + the index of the last fragment's triangle, 0 = none.
  std::vector<uint32_t>& winner_ = scratch<uint32_t, Scratch::Winner>();
  std::vector<Rgba8> colors_;     // per triangle: its colour (shadeTriangles)
  std::vector<double> nearest_;   // DepthTestBlend: the eye depth of the winner's fragment
  std::vector<UnderSum> sums_;    // BlendUnder: each pixel's blend so far
};

// Per tile of kBinTile pixels, the triangles whose box meets it, in drawing order.
std::vector<std::vector<uint32_t>> binTriangles(std::span<const SetupTriangle> tris, int tilesX, int tilesY) {
  std::vector<std::vector<uint32_t>> bins(size_t(tilesX) * size_t(tilesY));
  for (uint32_t i = 0; i < tris.size(); ++i) {
    const SetupTriangle& t = tris[i];
    for (int ty = t.minY / kBinTile; ty <= t.maxY / kBinTile; ++ty)
      for (int tx = t.minX / kBinTile; tx <= t.maxX / kBinTile; ++tx) bins[size_t(ty) * size_t(tilesX) + size_t(tx)].push_back(i);
  }
  return bins;
}

// The frame drawn and resolved by one writer: on one thread over the whole image, or binned,
// tile by tile on the pool (each tile's pixels are its own; counters summed in tile order).
template <WriteRule R, DepthStorage S, DepthMapping M>
void drawWith(std::span<const SetupTriangle> tris, DrawRaster raster, const Camera& cam, const RenderOptions& opt,
                  const TriangleShader& shade, Frame& frame, DrawCounters& counters, const DerivedScene* derived) {
  FragmentWriter<R, S, M> writer(tris, cam, opt, shade, frame, derived);
  const int threads = resolveThreads(opt.threads);
  // The reverse painter's stops where every pixel is written: nothing more can show.
  auto full = [](const DrawCounters& n, uint64_t pixels) {
    return (R == WriteRule::WhereUnwritten || R == WriteRule::BlendUnder) && n.filled == pixels;
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
  const int tilesX = (cam.width + kBinTile - 1) / kBinTile, tilesY = (cam.height + kBinTile - 1) / kBinTile;
  const std::vector<std::vector<uint32_t>> bins = binTriangles(tris, tilesX, tilesY);
  std::vector<DrawCounters> perTile(bins.size());
  parallelFor(0, bins.size(), threads, [&](size_t tile) {
    const int x0 = int(tile % size_t(tilesX)) * kBinTile, y0 = int(tile / size_t(tilesX)) * kBinTile;
    const int x1 = std::min(x0 + kBinTile, cam.width) - 1, y1 = std::min(y0 + kBinTile, cam.height) - 1;
    const uint64_t pixels = uint64_t(x1 - x0 + 1) * uint64_t(y1 - y0 + 1);
    for (size_t k = 0; k < bins[tile].size(); ++k) {
      if (full(perTile[tile], pixels)) {
        perTile[tile].skippedFull += bins[tile].size() - k;
        break;
      }
      writer.draw(bins[tile][k], DrawRaster::HalfSpace, x0, y0, x1, y1, perTile[tile]);
    }
  });
  writer.shadeTriangles(threads);
  std::vector<DrawCounters> perRow(size_t(cam.height));
  parallelFor(0, size_t(cam.height), threads, [&](size_t y) { writer.resolveRows(int(y), int(y) + 1, perRow[y]); });
  for (const DrawCounters& c : perTile) counters.add(c);
  for (const DrawCounters& c : perRow) counters.add(c);
  uint64_t binBytes = bins.capacity() * sizeof(bins[0]);
  for (const auto& b : bins) binBytes += b.capacity() * sizeof(uint32_t);
  writer.addMemory(frame.stats);
  frame.stats.addMemory("bins", binBytes);
}

}  // namespace

const char* writeRuleName(WriteRule rule) {
  switch (rule) {
    case WriteRule::DepthTest: return "depth-test";
    case WriteRule::Overwrite: return "overwrite";
    case WriteRule::WhereUnwritten: return "where-unwritten";
    case WriteRule::Blend: return "blend";
    case WriteRule::DepthTestBlend: return "depth-test-blend";
    case WriteRule::BlendUnder: return "blend-under";
  }
  return "?";
}

const char* drawRasterName(DrawRaster raster) {
  switch (raster) {
    case DrawRaster::HalfSpace: return "halfspace";
    case DrawRaster::Scanline: return "scanline";
    case DrawRaster::Binned: return "binned";
  }
  return "?";
}

ParamSpec drawRasterParam(const char* defaultValue) {
  return {"raster", ParamType::Choice, defaultValue, {"halfspace", "scanline", "binned"}, -1e300, 1e300,
          "fragments from the scalar half-space rasterizer on one thread (the reference), the lecture notes' "
          "scanline rasterizer, or the half-space rasterizer binned into 64x64 tiles on threads"};
}

DrawRaster drawRasterOf(const AlgorithmParams& params) {
  const std::string& name = params.text("raster");
  return name == "scanline" ? DrawRaster::Scanline : name == "binned" ? DrawRaster::Binned : DrawRaster::HalfSpace;
}

void drawOrdered(std::span<const SetupTriangle> triangles, WriteRule rule, DrawRaster raster, const Camera& camera,
                 const RenderOptions& options, const TriangleShader& shade, Frame& frame, DrawCounters& counters,
                 const DerivedScene* derived) {
  frame.clear(options.background, resolveThreads(options.threads));
  auto withRule = [&]<WriteRule R>() {
    if constexpr (R == WriteRule::DepthTest || R == WriteRule::DepthTestBlend)
      visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
        drawWith<R, S, M>(triangles, raster, camera, options, shade, frame, counters, derived);
      });
    else  // no depth buffer: one instance
      drawWith<R, DepthStorage::F32, DepthMapping::Reversed>(triangles, raster, camera, options, shade, frame,
                                                             counters, derived);
  };
  switch (rule) {
    case WriteRule::DepthTest: return withRule.template operator()<WriteRule::DepthTest>();
    case WriteRule::Overwrite: return withRule.template operator()<WriteRule::Overwrite>();
    case WriteRule::WhereUnwritten: return withRule.template operator()<WriteRule::WhereUnwritten>();
    case WriteRule::Blend: return withRule.template operator()<WriteRule::Blend>();
    case WriteRule::DepthTestBlend: return withRule.template operator()<WriteRule::DepthTestBlend>();
    case WriteRule::BlendUnder: return withRule.template operator()<WriteRule::BlendUnder>();
  }
}

void drawScene(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
               DrawRaster raster, const OrderFn& order, Frame& frame, const DerivedScene* derived) {
  Timer timer;
  Stats& st = frame.stats;
  const TriangleShader shade(scene, camera, options.shading);  // (the original scene's faces)
  FrontEndOutput fe;
  runFrontEnd(derived ? *derived->scene : scene, camera, options, fe);
  std::vector<SetupTriangle> triangles = fe.flatten();
  st.addTime("frontend", timer.lap());
  if (order) {
    order(triangles);
    st.addTime("order", timer.lap());
  }
  DrawCounters n;
  drawOrdered(triangles, rule, raster, camera, options, shade, frame, n, derived);
  st.addTime("raster", timer.lap());

  if (rule == WriteRule::DepthTest || rule == WriteRule::DepthTestBlend) st.depth_format = options.depthFormat.name();
  st.triangles_clipped = fe.clipped;
  st.triangles_degenerate = fe.degenerate;
  st.culled_backface = fe.culledBackface;
  st.culled_frustum = fe.culledFrustum;
  st.depth_tests = n.depthTests;
  st.depth_writes = n.depthWrites;
  st.color_writes = n.colorWrites;
  st.covered_pixels = n.covered;
  st.addMemory("setup_triangles", triangles.capacity() * sizeof(SetupTriangle));
  st.addMemory("front_end", fe.memoryBytes());
  addFrameMemory(st, frame);
  st.setDetail("rasterizer", drawRasterName(raster));
  st.setDetail("write_rule", writeRuleName(rule));
  if (rule == WriteRule::WhereUnwritten || rule == WriteRule::BlendUnder) st.setDetail("skipped_full", n.skippedFull);
}

}  // namespace hsr::algo

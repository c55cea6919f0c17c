// The z-buffer's memory and clearing savers that the Ukrainian paper lists, on the textbook loop
// (a depth test per fragment, triangles in submission order, the scalar half-space rasterizer):
//
//   region=WxH — "a smaller z-buffer reused region by region": the image is cut into regions of
//   W x H pixels; each region is drawn on its own, from the triangles whose screen box meets it,
//   with one z-buffer the size of a region, and resolved into the frame before the next. Each
//   pixel sees the same fragments in the same order as with a whole-image buffer: the same image,
//   bit for bit, with a region's buffer instead of an image's.
//
//   clear=half-range — "half the depth range per frame to avoid clearing": the buffer is kept by
//   the algorithm object (HalfRangeZBuffer) and not cleared between the frames it draws. Even frames store keys in the
//   lower half of the buffer's values (nearer = smaller), odd frames in the upper half (nearer =
//   larger), so every key left by the frame before is farther than any of this frame's and loses
//   its test as a cleared pixel would. A pixel not drawn this frame is reset to the boundary
//   between the halves when the frame is resolved (that pass visits every pixel anyway), so no
//   stale key survives two frames. The price is one bit of depth precision: two fragments whose
//   stored values differ only in the last bit tie, and the first drawn stays.
#include <bit>
#include <limits>
#include <span>
#include <type_traits>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/zbuffer_pixels.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "raster/halfspace.hpp"

namespace hsr::algo {
namespace {

// Fills the frame's pixel idx from the set-up triangle that won it.
void resolvePixel(const SetupTriangle& t, Rgba8 color, const RenderOptions& options, int x, int y, size_t idx,
                  Frame& frame) {
  resolveWinner(t, x, y, idx, options.outputs, nullptr, frame);
  if (has(options.outputs, FrameOutputs::Color)) frame.color[idx] = color;
}

// Fills the frame's pixel idx with the background.
void resolveBackground(const RenderOptions& options, size_t idx, Frame& frame) {
  if (!frame.faceId.empty()) frame.faceId[idx] = -1;
  if (!frame.triangleId.empty()) frame.triangleId[idx] = -1;
  frame.depth[idx] = std::numeric_limits<float>::infinity();
  if (!frame.color.empty()) frame.color[idx] = options.background;
}

// ---- region by region ----

template <DepthStorage S, DepthMapping M>
void drawRegions(const std::vector<SetupTriangle>& tris, const Camera& camera, const RenderOptions& options,
                 std::span<const Rgba8> colors, int rw, int rh, DrawBuffers& buffers, Frame& frame, DrawCounters& n) {
  using Pixels = ZBufferPixels<S, M>;
  using T = typename Pixels::T;
  const int columns = (camera.width + rw - 1) / rw, rows = (camera.height + rh - 1) / rh;
  const std::vector<std::vector<uint32_t>> bins = binByCell(tris, rw, rh, columns, rows);
  const T clear = quantizeDepth<S>(options.depthFormat.clearValue());
  Timer timer;
  double clearMs = 0, rasterMs = 0, resolveMs = 0;
  std::vector<T>& depth = buffers.depth<T>();  // the one z-buffer, a region's size
  std::vector<uint32_t>& winner = buffers.winner();  // 1 + the winning triangle, 0 = none
  depth.resize(size_t(rw) * size_t(rh));
  winner.resize(depth.size());
  for (int ry = 0; ry < rows; ++ry)
    for (int rx = 0; rx < columns; ++rx) {
      const int x0 = rx * rw, y0 = ry * rh;
      const int x1 = std::min(x0 + rw, camera.width) - 1, y1 = std::min(y0 + rh, camera.height) - 1;
      std::fill(depth.begin(), depth.end(), clear);
      std::fill(winner.begin(), winner.end(), 0);
      clearMs += timer.lap();
      for (const uint32_t i : bins[size_t(ry) * size_t(columns) + size_t(rx)]) {
        const MappedPlanes m = mapPlanes<M>(tris[i].depthNum, tris[i].depthDen, camera.near, camera.far,
                                            camera.orthographic);
        rasterizeHalfSpace(clippedTo(tris[i], x0, y0, x1, y1), [&](int x, int y, double) {
          const size_t local = size_t(y - y0) * size_t(rw) + size_t(x - x0);
          const T z = Pixels::fragment(m, x, y);
          ++n.depthTests;
          if (!Pixels::nearer(z, depth[local])) return;
          depth[local] = z;
          winner[local] = i + 1;
          ++n.depthWrites;
          ++n.written;
          if (!frame.color.empty()) ++n.colorWrites;
          if (!frame.writes.empty()) ++frame.writes[frame.index(x, y)];
        });
      }
      rasterMs += timer.lap();
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const uint32_t w = winner[size_t(y - y0) * size_t(rw) + size_t(x - x0)];
          if (!w) continue;
          resolvePixel(tris[w - 1], colors.empty() ? Rgba8{} : colors[w - 1], options, x, y, frame.index(x, y), frame);
          ++n.covered;
        }
      resolveMs += timer.lap();
    }
  Stats& st = frame.stats;
  st.addTime("clear", clearMs);
  st.addTime("raster", rasterMs);
  st.addTime("resolve", resolveMs);
  st.addMemory("depth_buffer", depth.size() * sizeof(T));
  st.addMemory("winner_ids", winner.size() * sizeof(uint32_t));
  st.addMemory("region_bins", binBytes(bins));
  st.setDetail("regions", uint64_t(columns) * uint64_t(rows));
}

// ---- half the range per frame ----

// The keys of the half-range buffer for stored values of type DepthT<S>: a key type K as wide as
// the stored value, and for each stored value its "farness" (an unsigned code, larger = farther,
// whatever the mapping's direction), halved into the frame's half.
template <DepthStorage S, DepthMapping M>
struct HalfRangeKeys {
  using T = DepthT<S>;
  using K = std::conditional_t<sizeof(T) == 2, uint16_t, uint32_t>;
  static constexpr K kMax = std::numeric_limits<K>::max();
  static constexpr K kHalf = kMax >> 1;      // farness >> 1 is at most this
  static constexpr K kBoundary = kHalf;      // between the halves: no fragment's key, the "cleared" value
  static constexpr bool kGreaterNearer = M == DepthMapping::Reversed || M == DepthMapping::Inv;

  static K farness(T v) {
    K code;
    if constexpr (std::is_floating_point_v<T>) code = v > 0 ? std::bit_cast<uint32_t>(v) : 0;  // (mapped v >= 0)
    else code = K(v);
    return kGreaterNearer ? K(kMax - code) : code;
  }
  // Even frames: keys in [0, kHalf - 1], nearer = smaller; odd frames: [kHalf + 2, kMax], nearer
  // = larger. (The farthest two codes of a half merge with the next: the boundary stays free.)
  static K key(T v, bool odd) {
    const K h = std::min<K>(K(farness(v) >> 1), K(kHalf - 1));
    return odd ? K(kMax - h) : h;
  }
  static bool nearer(K a, K b, bool odd) { return odd ? a > b : a < b; }
  static bool inHalf(K k, bool odd) { return odd ? k > kHalf + 1 : k < kHalf; }
};

}  // namespace

// What the half-range z-buffer keeps between frames, of whichever depth format it was made for.
struct HalfRangeZBuffer::Buffer {
  virtual ~Buffer() = default;
};

namespace {

// The keys, the winners (valid where the key is in the frame's half), the frame count and what
// the buffer was made for.
template <DepthStorage S, DepthMapping M>
struct HalfRangeBuffer : HalfRangeZBuffer::Buffer {
  using K = typename HalfRangeKeys<S, M>::K;
  int width = 0, height = 0;
  uint64_t frames = 0;
  std::vector<K> keys;
  std::vector<uint32_t> winner;
};

template <DepthStorage S, DepthMapping M>
void drawHalfRange(const std::vector<SetupTriangle>& tris, const Camera& camera, const RenderOptions& options,
                   std::span<const Rgba8> colors, std::unique_ptr<HalfRangeZBuffer::Buffer>& kept, Frame& frame,
                   DrawCounters& n) {
  using Keys = HalfRangeKeys<S, M>;
  using Buffer = HalfRangeBuffer<S, M>;
  using T = DepthT<S>;
  Stats& st = frame.stats;
  Timer timer;
  Buffer* buffer = dynamic_cast<Buffer*>(kept.get());
  const bool fresh = !buffer || buffer->width != camera.width || buffer->height != camera.height;
  if (fresh) {  // the first frame (or a new size or depth format): cleared once
    auto made = std::make_unique<Buffer>();
    made->width = camera.width;
    made->height = camera.height;
    made->keys.assign(size_t(camera.width) * size_t(camera.height), Keys::kBoundary);
    made->winner.assign(made->keys.size(), 0);
    buffer = made.get();
    kept = std::move(made);
    st.addTime("clear", timer.lap());
  }
  const bool odd = buffer->frames % 2 == 1;
  const typename Keys::K clearFarness = Keys::farness(quantizeDepth<S>(options.depthFormat.clearValue()));
  for (uint32_t i = 0; i < tris.size(); ++i) {
    const MappedPlanes m = mapPlanes<M>(tris[i].depthNum, tris[i].depthDen, camera.near, camera.far, camera.orthographic);
    rasterizeHalfSpace(tris[i], [&](int x, int y, double) {
      const size_t idx = frame.index(x, y);
      const T z = ZBufferPixels<S, M>::fragment(m, x, y);
      ++n.depthTests;
      if (Keys::farness(z) >= clearFarness) return;  // no nearer than a cleared pixel: refused, as there
      const auto k = Keys::key(z, odd);
      if (!Keys::nearer(k, buffer->keys[idx], odd)) return;
      buffer->keys[idx] = k;
      buffer->winner[idx] = i + 1;
      ++n.depthWrites;
      ++n.written;
      if (!frame.color.empty()) ++n.colorWrites;
      if (!frame.writes.empty()) ++frame.writes[idx];
    });
  }
  st.addTime("raster", timer.lap());
  uint64_t reset = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const size_t idx = frame.index(x, y);
      if (Keys::inHalf(buffer->keys[idx], odd)) {
        const uint32_t w = buffer->winner[idx];
        resolvePixel(tris[w - 1], colors.empty() ? Rgba8{} : colors[w - 1], options, x, y, idx, frame);
        ++n.covered;
        continue;
      }
      resolveBackground(options, idx, frame);
      if (buffer->keys[idx] != Keys::kBoundary) {  // drawn last frame, not this one
        buffer->keys[idx] = Keys::kBoundary;
        ++reset;
      }
    }
  st.addTime("resolve", timer.lap());
  ++buffer->frames;
  st.addMemory("depth_buffer", buffer->keys.size() * sizeof(typename Keys::K));
  st.addMemory("winner_ids", buffer->winner.size() * sizeof(uint32_t));
  st.setDetail("frames_kept", buffer->frames);
  st.setDetail("half", odd ? "upper" : "lower");
  st.setDetail("cleared", uint64_t(fresh ? 1 : 0));
  st.setDetail("pixels_reset", reset);
}

// The front end, then `draw` under the depth format, then the statistics of the textbook z-buffer.
template <class Draw>
void drawWithFrontEnd(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame,
                      bool clearFrame, Draw&& draw) {
  Timer timer;
  Stats& st = frame.stats;
  const TriangleShader shade(scene, camera, options.shading);
  FrontEndOutput fe;
  const std::vector<SetupTriangle> triangles = frontEndStep(scene, camera, options, fe, timer, st);
  if (clearFrame) {
    frame.clear(options.background, resolveThreads(options.threads));
    st.addTime("clear", timer.lap());
  }
  std::vector<Rgba8> colors;  // each triangle's shaded colour, once (far fewer triangles than pixels)
  if (has(options.outputs, FrameOutputs::Color)) {
    colors.resize(triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i) colors[i] = triangleColor(triangles[i], shade);
  }
  DrawCounters n;  // (the draw times its stages: clear, raster, resolve)
  visitDepthFormat(options.depthFormat,
                   [&]<DepthStorage S, DepthMapping M>() { draw.template operator()<S, M>(triangles, colors, n); });
  st.addMemory("triangle_colors", colors.size() * sizeof(Rgba8));
  recordDrawStats(st, fe, fe.memoryBytes(), triangles.capacity(), n, &options.depthFormat, frame);
  st.setDetail("rasterizer", "halfspace");
}

}  // namespace

void zbufferInRegions(const Scene& scene, const Camera& camera, const RenderOptions& options, int regionWidth,
                      int regionHeight, DrawBuffers& buffers, Frame& frame) {
  const int rw = std::min(regionWidth, camera.width), rh = std::min(regionHeight, camera.height);
  drawWithFrontEnd(scene, camera, options, frame, /*clearFrame=*/true,
                   [&]<DepthStorage S, DepthMapping M>(const std::vector<SetupTriangle>& tris,
                                                       std::span<const Rgba8> colors, DrawCounters& n) {
                     drawRegions<S, M>(tris, camera, options, colors, rw, rh, buffers, frame, n);
                   });
}

HalfRangeZBuffer::HalfRangeZBuffer() = default;
HalfRangeZBuffer::~HalfRangeZBuffer() = default;

void HalfRangeZBuffer::draw(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame) {
  // (A frame of another depth format starts a new buffer: the kept one is of another type.)
  drawWithFrontEnd(scene, camera, options, frame, /*clearFrame=*/false,
                   [&]<DepthStorage S, DepthMapping M>(const std::vector<SetupTriangle>& tris,
                                                       std::span<const Rgba8> colors, DrawCounters& n) {
                     drawHalfRange<S, M>(tris, camera, options, colors, buffer_, frame, n);
                   });
}

}  // namespace hsr::algo

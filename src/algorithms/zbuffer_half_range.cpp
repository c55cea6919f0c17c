// The z-buffer without clearing: "half the depth range per frame to avoid clearing", one of the
// Ukrainian paper's clearing savers, on the textbook loop (a depth test per fragment, triangles in
// submission order, the scalar half-space rasterizer). The buffer is kept by the algorithm object
// and not cleared between the frames it draws. Even frames store keys in the lower half of the
// buffer's values (nearer = smaller), odd frames in the upper half (nearer = larger), so every key
// left by the frame before is farther than any of this frame's and loses its test as a cleared
// pixel would. A pixel not drawn this frame is reset to the boundary between the halves when the
// frame is resolved (that pass visits every pixel anyway), so no stale key survives two frames.
// The price is one bit of depth precision: two fragments whose stored values differ only in the
// last bit tie, and the first drawn stays.
#include <bit>
#include <limits>
#include <memory>
#include <span>
#include <type_traits>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "core/timer.hpp"
#include "raster/halfspace.hpp"

namespace hsr::algo {
namespace {

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

// What the object keeps between frames, of whichever depth format it was made for.
struct KeptBuffer {
  virtual ~KeptBuffer() = default;
};

// The keys, the winners (valid where the key is in the frame's half), the frame count and what
// the buffer was made for.
template <DepthStorage S, DepthMapping M>
struct HalfRangeBuffer : KeptBuffer {
  using K = typename HalfRangeKeys<S, M>::K;
  int width = 0, height = 0;
  uint64_t frames = 0;
  std::vector<K> keys;
  std::vector<uint32_t> winner;
};

// Fills the frame's pixel idx with the background.
void resolveBackground(const RenderOptions& options, size_t idx, Frame& frame) {
  if (!frame.faceId.empty()) frame.faceId[idx] = -1;
  if (!frame.triangleId.empty()) frame.triangleId[idx] = -1;
  frame.depth[idx] = std::numeric_limits<float>::infinity();
  if (!frame.color.empty()) frame.color[idx] = options.background;
}

// The triangles drawn into the kept buffer (made, and cleared, at the first frame of its size and
// depth format) and every pixel of the frame resolved from it; times "clear", "raster", "resolve".
template <DepthStorage S, DepthMapping M>
void drawHalfRange(std::span<const SetupTriangle> tris, const Camera& camera, const RenderOptions& options,
                   const TriangleShader& shade, std::unique_ptr<KeptBuffer>& kept, Frame& frame, DrawCounters& n) {
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
      const T z = T(fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5)));
      ++n.depthTests;
      if (Keys::farness(z) >= clearFarness) return;  // no nearer than a cleared pixel: refused, as there
      const auto k = Keys::key(z, odd);
      if (!Keys::nearer(k, buffer->keys[idx], odd)) return;
      buffer->keys[idx] = k;
      ++n.depthWrites;
      buffer->winner[idx] = i + 1;
      countWritten(idx, frame, n);
    });
  }
  st.addTime("raster", timer.lap());
  const std::vector<Rgba8> colors =
      has(options.outputs, FrameOutputs::Color) ? triangleColors(tris, shade, nullptr, 1) : std::vector<Rgba8>{};
  uint64_t reset = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const size_t idx = frame.index(x, y);
      if (Keys::inHalf(buffer->keys[idx], odd)) {
        const uint32_t w = buffer->winner[idx] - 1;
        resolveWinner(tris[w], x, y, idx, options.outputs, nullptr, frame);
        if (!colors.empty()) frame.color[idx] = colors[w];
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
  st.addMemory("triangle_colors", colors.size() * sizeof(Rgba8));
  st.addMemory("depth_buffer", buffer->keys.size() * sizeof(typename Keys::K));
  st.addMemory("winner_ids", buffer->winner.size() * sizeof(uint32_t));
  st.setDetail("frames_kept", buffer->frames);
  st.setDetail("half", odd ? "upper" : "lower");
  st.setDetail("cleared", uint64_t(fresh ? 1 : 0));
  st.setDetail("pixels_reset", reset);
}

// The object keeps the half-range buffer from one view to the next (a Renderer's, across its
// views); a frame of another size or depth format starts a new one.
class ZbufferHalfRange final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    drawFrame(scene_, camera, options, {.clearFrame = false}, [&](FrameWork& work, const TriangleShader& shade) {
      visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
        drawHalfRange<S, M>(work.triangles, camera, options, shade, kept_, frame, work.counters);
      });
    }, frame);
    frame.stats.setDetail("rasterizer", "halfspace");
  }

 private:
  std::unique_ptr<KeptBuffer> kept_;
};

}  // namespace

AlgorithmInfo zbufferHalfRangeAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer-half-range";
  a.summary = "the textbook z-buffer never cleared: even frames use the lower half of the depth values, odd frames "
              "the upper half";
  a.source = "Ukrainian paper";
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision less one bit: z-fighting is counted as ambiguous";
  a.create = factoryOf<ZbufferHalfRange>();
  return a;
}

}  // namespace hsr::algo

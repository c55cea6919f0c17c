// The visibility buffer every algorithm fills — per pixel: face id, world triangle id, eye depth
// and colour — and the statistics every algorithm reports (keys of docs/conventions.md).
// Produced by render(); consumed by the writers (io.hpp), --verify and compare.
#pragma once
#include <hsr/common.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace hsr {

/// What the z-buffer resolves into the Frame: depth always, and any of face ids, triangle ids
/// and colour (flags, combined with |). Buffers not asked for cost nothing: they are neither
/// cleared nor written, and stay empty.
/// - DepthOnly (no flag): depth is the eye depth recovered from the stored value by inverting
///   the depth mapping (so it carries the format's rounding), and the z-buffer keeps no ids.
/// - With any flag, depth is the exact eye depth of the winning triangle's planes.
/// All = FaceIds | TriangleIds | Color (the default); IdsAndDepth = FaceIds | TriangleIds.
/// FaceIds | Color is what OpenGL renders into colour + id + depth attachments (bench/peer).
enum class FrameOutputs : uint8_t {
  DepthOnly = 0,
  FaceIds = 1,
  TriangleIds = 2,
  Color = 4,
  IdsAndDepth = FaceIds | TriangleIds,
  All = FaceIds | TriangleIds | Color,
};
constexpr FrameOutputs operator|(FrameOutputs a, FrameOutputs b) { return FrameOutputs(uint8_t(a) | uint8_t(b)); }
/// Whether `outputs` holds every flag of `part` (a non-empty set).
constexpr bool has(FrameOutputs outputs, FrameOutputs part) {
  return part != FrameOutputs::DepthOnly && (uint8_t(outputs) & uint8_t(part)) == uint8_t(part);
}
/// "depth,face,triangle,color" (any order; depth alone = DepthOnly) <-> FrameOutputs; parse
/// throws InputError naming `what` (a front end's own name of the list) on an unknown word.
FrameOutputs parseFrameOutputs(const std::string& list, const std::string& what = "outputs");
std::string frameOutputsName(FrameOutputs outputs);

namespace detail {
/// Storage of `bytes` for a buffer, aligned to a 64-byte cache line. A buffer of at least
/// kHugePageBytes gets whole 2 MiB pages, aligned to them, and asks Linux to back them with
/// transparent huge pages (madvise; only advice: where the system does not offer them, the
/// memory is the same as without): a 1920x1080 frame's buffers then need a few TLB entries each
/// instead of thousands (docs/benchmarks.md). Throws std::bad_alloc.
void* allocateBuffer(size_t bytes);
/// Frees what allocateBuffer(bytes) returned (the same `bytes`).
void freeBuffer(void* p, size_t bytes) noexcept;
inline constexpr size_t kHugePageBytes = size_t(2) << 20;
}  // namespace detail

/// The allocator of Frame's buffers: memory aligned to a 64-byte cache line, so that the rows of
/// an image whose width is a multiple of 16 pixels start on a cache line and the tiled rasterizer
/// can write whole lines with streaming (non-temporal) stores; large buffers on huge pages
/// (detail::allocateBuffer). Otherwise as std::allocator, except that it may lend the buffer
/// memory the buffer does not own (lentBuffer): an allocation that fits takes it, its elements
/// are left as they are (not zeroed), it is never freed, and a copy of the buffer allocates its own.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  using propagate_on_container_move_assignment = std::true_type;
  using propagate_on_container_swap = std::true_type;
  using is_always_equal = std::false_type;
  CacheLineAllocator() = default;
  CacheLineAllocator(T* lent, size_t count) noexcept : lent_(lent), count_(count) {}
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}  // (lends nothing)
  T* allocate(size_t n) {
    if (lent_ && n <= count_) return lent_;
    if (n > std::numeric_limits<size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(detail::allocateBuffer(n * sizeof(T)));
  }
  void deallocate(T* p, size_t n) noexcept {
    if (!lent_ || p != lent_) detail::freeBuffer(p, n * sizeof(T));
  }
  /// Elements made without a value: value-initialized (zero) in memory of its own, left as they
  /// are in lent memory.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) {
      if (inLent(p)) ::new (static_cast<void*>(p)) U;
      else ::new (static_cast<void*>(p)) U();
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }
  CacheLineAllocator select_on_container_copy_construction() const noexcept { return {}; }
  /// The memory it lends, or null.
  T* lent() const noexcept { return lent_; }
  template <class U>
  bool operator==(const CacheLineAllocator<U>& o) const noexcept {
    return static_cast<const void*>(lent_) == static_cast<const void*>(o.lent());
  }

 private:
  bool inLent(const void* p) const noexcept {
    const uintptr_t at = reinterpret_cast<uintptr_t>(p), first = reinterpret_cast<uintptr_t>(lent_);
    return lent_ && at >= first && at < first + count_ * sizeof(T);
  }
  T* lent_ = nullptr;
  size_t count_ = 0;
};
/// A frame buffer: a std::vector with cache-line aligned storage.
template <class T>
using FrameBuffer = std::vector<T, CacheLineAllocator<T>>;

/// A buffer of `count` elements in `memory`, which it does not own: memory of the caller's (at
/// least `count` elements, cache-line aligned, outliving the buffer) that a frame is then rendered
/// straight into, its contents as they were. Grown past `count`, the buffer moves to memory of its own.
template <class T>
FrameBuffer<T> lentBuffer(T* memory, size_t count) {
  FrameBuffer<T> buffer{CacheLineAllocator<T>(memory, count)};
  buffer.resize(count);
  return buffer;
}

/// A name with static storage, as Stats keeps its buffers' and details' names: a string literal
/// (checked when compiled) or a name made at run time and interned for the program's life
/// (StaticName::interned). Stats stores the view, so a warm frame neither copies nor allocates it.
class StaticName {
 public:
  template <size_t N>
  consteval StaticName(const char (&literal)[N]) : text_(literal, N - 1) {}
  /// `name`'s text kept for the life of the program (thread-safe; the same text, the same storage).
  static StaticName interned(std::string_view name);
  operator std::string_view() const { return text_; }

 private:
  explicit StaticName(std::string_view text) : text_(text) {}
  std::string_view text_;
};

/// Counters and timings of one frame. Counts are exact integers; times in milliseconds.
struct Stats {
  std::string algorithm;
  int width = 0, height = 0;
  uint64_t faces = 0;              // polygons in the scene
  uint64_t triangles = 0;          // triangles in the scene's triangulation
  uint64_t triangles_clipped = 0;  // triangles that crossed a clipping plane and were clipped
  uint64_t triangles_degenerate = 0;  // zero area after snapping to the sub-pixel grid: not drawn
  uint64_t culled_backface = 0;
  uint64_t culled_frustum = 0;     // triangles rejected as wholly outside the view
  uint64_t culled_occlusion = 0;
  uint64_t depth_tests = 0;        // z comparisons
  uint64_t depth_writes = 0;
  uint64_t color_writes = 0;
  uint64_t covered_pixels = 0;     // pixels showing a surface in the final image
  uint64_t memory_bytes = 0;       // all per-frame buffers and structures: the sum of `memory`
  /// The bytes of each buffer or structure the frame used, by name ("depth_buffer", "frame.color",
  /// "bsp_tree"; docs/memory.md lists them), in the order first added (JSON "memory").
  std::vector<std::pair<std::string_view, uint64_t>> memory;
  std::string depth_format;        // e.g. "f32:reversed" (empty for algorithms without one)
  std::vector<std::pair<std::string, double>> time_ms;  // stage -> ms, in pipeline order
  std::optional<uint64_t> wrong_pixels, ambiguous_pixels;  // with --verify
  /// The parameters the algorithm ran with, in declaration order (JSON "params").
  std::vector<std::pair<std::string, std::string>> params;
  /// The algorithm's own counters and facts (which rasterizer ran, what it deferred or culled),
  /// written as a nested JSON object named after the algorithm; docs/algorithms/NAME.md lists them.
  /// Keys are StaticNames, so a warm frame allocates nothing for them.
  using Detail = std::variant<uint64_t, double, std::string>;
  std::vector<std::pair<std::string_view, Detail>> details;

  double overdraw() const { return covered_pixels ? double(color_writes) / double(covered_pixels) : 0.0; }
  void addTime(const std::string& stage, double ms);
  /// Adds `bytes` to buffer `name`'s entry of `memory` and to memory_bytes.
  void addMemory(StaticName name, uint64_t bytes);
  /// Adds the counters of `part` (a part of this frame drawn on its own: a depth slice, a region)
  /// to these: front-end counts, culls, tests and writes, and its times stage by stage.
  void addCounts(const Stats& part);
  /// Sets the detail `key` (replacing its value); addDetail adds to a count (0 if absent).
  void setDetail(StaticName key, Detail value);
  void addDetail(StaticName key, uint64_t count);
  /// The count `key` of the details, if the algorithm reported it.
  std::optional<uint64_t> detailCount(std::string_view key) const;
  /// The text detail `key` ("" if absent).
  std::string detailText(std::string_view key) const;
  /// The statistics as one JSON object (the keys of docs/conventions.md).
  std::string toJson(int indent = 2) const;
};

/// Per pixel, how many fragments wrote it: Frame::writes, for the overdraw picture.
using WriteCount = uint32_t;

struct Frame {
  int width = 0, height = 0;
  FrameBuffer<int32_t> faceId;      // face index, -1 background; row 0 = top
  FrameBuffer<int32_t> triangleId;  // index into Scene::triangles, -1 background
  FrameBuffer<float> depth;         // eye-space depth, +inf background
  FrameBuffer<Rgba8> color;         // shaded colour, background colour where empty
  /// With RenderOptions::countWrites: the fragments written per pixel (an algorithm's overdraw
  /// at each pixel); otherwise empty.
  FrameBuffer<WriteCount> writes;
  Stats stats;

  /// Sizes the buffers for w x h, reusing their memory: depth always, faceId, triangleId and
  /// color when `outputs` has them; the others are emptied. Contents are left as they are:
  /// render() allocates, and every algorithm then writes every pixel (or calls clear()).
  void allocate(int w, int h, FrameOutputs outputs = FrameOutputs::All);
  /// Clears the sized buffers to background / -1 / +inf, split over up to `threads` threads.
  void clear(Rgba8 background, int threads = 1);
  /// allocate(w, h) with every buffer, then clear().
  void resize(int w, int h, Rgba8 background, int threads = 1);
  size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

}  // namespace hsr

// Memory the module hands to NumPy without copying: an array's base is a capsule named
// "hsr.buffer" whose pointer is the array's data and whose context owns the memory (a moved
// Frame buffer or a block of hsr::detail::allocateBuffer). NumPy frees it through the capsule
// when the last array viewing it is gone.
#pragma once
#include "common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <type_traits>
#include <utility>
#include <variant>

namespace hsrpy {

inline constexpr const char* kBufferCapsule = "hsr.buffer";

struct Owner {
  virtual ~Owner() = default;
};

/// Storage of hsr::detail::allocateBuffer (cache-line aligned, huge pages when large), owned.
class RawBlock {
 public:
  RawBlock() = default;
  explicit RawBlock(size_t bytes) : data_(hsr::detail::allocateBuffer(bytes)), bytes_(bytes) {}
  RawBlock(RawBlock&& o) noexcept : data_(std::exchange(o.data_, nullptr)), bytes_(std::exchange(o.bytes_, 0)) {}
  RawBlock& operator=(RawBlock&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(bytes_, o.bytes_);
    return *this;
  }
  RawBlock(const RawBlock&) = delete;
  RawBlock& operator=(const RawBlock&) = delete;
  ~RawBlock() {
    if (data_) hsr::detail::freeBuffer(data_, bytes_);
  }
  void* data() const { return data_; }
  size_t capacity() const { return bytes_; }  // (bytes)

 private:
  void* data_ = nullptr;
  size_t bytes_ = 0;
};

/// Output buffers whose arrays NumPy has freed, kept for the next renders, single views (Frame
/// buffers) and batches (blocks) alike: memory new to the process costs page faults and the
/// kernel's zeroing, on this project's VMs 0.15 to 3 ms per MB, more than rendering into it
/// (docs/benchmarks.md, "The Python module"). The most recently freed are kept, up to kMaxBytes
/// (at most an eighth of the machine's memory) and kMaxEntries buffers; a buffer is reused only
/// for a request at most an eighth smaller, so an array never holds much more than its bytes.
class BufferPool {
 public:
  /// The one pool, never destroyed (arrays may outlive the module's static objects).
  static BufferPool& instance() {
    static BufferPool* pool = new BufferPool;
    return *pool;
  }
  template <class T>
  void give(T&& buffer) {
    static_assert(!std::is_lvalue_reference_v<T>);
    const size_t bytes = bytesOf(buffer);
    if (bytes == 0 || bytes > maxBytes_ || lends(buffer)) return;  // freed (or dropped) by the caller
    std::vector<Entry> evicted;                   // freed outside the lock
    std::lock_guard lock(m_);
    while (!kept_.empty() && (kept_.size() >= kMaxEntries || bytes_ + bytes > maxBytes_)) {
      bytes_ -= bytesOf(kept_.front());
      evicted.push_back(std::move(kept_.front()));
      kept_.erase(kept_.begin());  // the oldest first
    }
    bytes_ += bytes;
    kept_.emplace_back(std::move(buffer));
  }
  /// A kept buffer of type T (a FrameBuffer or a RawBlock) with room for n elements (RawBlock:
  /// bytes) and at most an eighth more, the most recently freed of them; else an empty one.
  template <class T>
  T take(size_t n) {
    std::lock_guard lock(m_);
    for (auto it = kept_.rbegin(); it != kept_.rend(); ++it) {
      T* b = std::get_if<T>(&*it);
      if (!b || b->capacity() < n || b->capacity() - n > n / 8) continue;
      T buffer = std::move(*b);
      bytes_ -= bytesOf(buffer);
      kept_.erase(std::next(it).base());
      return buffer;
    }
    return T{};
  }

 private:
  using Entry = std::variant<hsr::FrameBuffer<float>, hsr::FrameBuffer<int32_t>, hsr::FrameBuffer<hsr::Rgba8>, RawBlock>;
  static constexpr size_t kMaxEntries = 16, kMaxBytesCap = size_t(512) << 20;
  BufferPool() {
    const double memory = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
    maxBytes_ = memory > 0 ? std::min(kMaxBytesCap, size_t(memory / 8)) : size_t(64) << 20;
  }
  static size_t bytesOf(const RawBlock& b) { return b.capacity(); }
  // (a buffer lent memory of an array's: never kept)
  static bool lends(const RawBlock&) { return false; }
  template <class T>
  static bool lends(const hsr::FrameBuffer<T>& b) { return b.get_allocator().lent() != nullptr; }
  template <class T>
  static size_t bytesOf(const hsr::FrameBuffer<T>& b) { return b.capacity() * sizeof(T); }
  static size_t bytesOf(const Entry& e) { return std::visit([](const auto& b) { return bytesOf(b); }, e); }
  std::mutex m_;
  std::vector<Entry> kept_;  // oldest first
  size_t bytes_ = 0, maxBytes_ = 0;
};

/// A buffer (a Frame buffer moved out of its frame, or a RawBlock); back to the pool when NumPy
/// frees its array.
template <class Buffer>
struct PooledOwner : Owner {
  explicit PooledOwner(Buffer&& b) : buffer(std::move(b)) {}
  ~PooledOwner() override { BufferPool::instance().give(std::move(buffer)); }
  PooledOwner(const PooledOwner&) = delete;
  PooledOwner& operator=(const PooledOwner&) = delete;
  Buffer buffer;
};

/// A block of `bytes` for outputs the module fills itself: one the pool kept, else a new one.
/// Its contents are undefined.
inline RawBlock takeBlock(size_t bytes) {
  RawBlock b = BufferPool::instance().take<RawBlock>(bytes);
  return b.data() ? std::move(b) : RawBlock(bytes);
}

/// An array of `shape` (C order) over `data`, which `owner` keeps alive: no copy.
inline py::array handOver(std::unique_ptr<Owner> owner, void* data, const py::dtype& dtype,
                          std::vector<py::ssize_t> shape) {
  py::capsule base(data, kBufferCapsule, +[](PyObject* capsule) {
    delete static_cast<Owner*>(PyCapsule_GetContext(capsule));
  });
  if (PyCapsule_SetContext(base.ptr(), owner.get()) != 0) throw py::error_already_set();
  owner.release();  // the capsule owns it now
  return py::array(dtype, std::move(shape), data, base);
}

/// The array of `shape` over a buffer (a Frame buffer or a RawBlock), which it keeps.
template <class Buffer>
py::array handOver(Buffer&& buffer, std::vector<py::ssize_t> shape, const py::dtype& dtype) {
  auto owner = std::make_unique<PooledOwner<Buffer>>(std::move(buffer));
  void* data = owner->buffer.data();
  return handOver(std::move(owner), data, dtype, std::move(shape));
}

}  // namespace hsrpy

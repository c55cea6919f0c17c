// Memory the module hands to NumPy without copying: an array's base is a capsule named
// "hsr.buffer" whose pointer is the array's data and whose context owns the memory (a moved
// Frame buffer or a block of hsr::detail::allocateBuffer). NumPy frees it through the capsule
// when the last array viewing it is gone.
#pragma once
#include "common.hpp"

#include <mutex>
#include <type_traits>
#include <utility>

namespace hsrpy {

inline constexpr const char* kBufferCapsule = "hsr.buffer";

struct Owner {
  virtual ~Owner() = default;
};

/// Frame buffers whose arrays NumPy has freed, kept for the frames of the next single-view
/// renders: a buffer new to the process costs page faults and the kernel's zeroing on every call
/// (docs/benchmarks.md, "The Python module"). At most kMaxBuffers per type and kMaxBytes in all.
class BufferPool {
 public:
  /// The one pool, never destroyed (arrays may outlive the module's static objects).
  static BufferPool& instance() {
    static BufferPool* pool = new BufferPool;
    return *pool;
  }
  template <class T>
  void give(hsr::FrameBuffer<T>&& buffer) {
    const size_t bytes = buffer.capacity() * sizeof(T);
    std::lock_guard lock(m_);
    auto& kept = list<T>();
    if (bytes == 0 || kept.size() >= kMaxBuffers || bytes_ + bytes > kMaxBytes) return;  // freed by the caller
    bytes_ += bytes;
    kept.push_back(std::move(buffer));
  }
  /// A kept buffer with room for n elements (the smallest such), or an empty one.
  template <class T>
  hsr::FrameBuffer<T> take(size_t n) {
    std::lock_guard lock(m_);
    auto& kept = list<T>();
    auto best = kept.end();
    for (auto it = kept.begin(); it != kept.end(); ++it)
      if (it->capacity() >= n && (best == kept.end() || it->capacity() < best->capacity())) best = it;
    if (best == kept.end()) return {};
    hsr::FrameBuffer<T> buffer = std::move(*best);
    kept.erase(best);
    bytes_ -= buffer.capacity() * sizeof(T);
    return buffer;
  }

 private:
  static constexpr size_t kMaxBuffers = 4, kMaxBytes = size_t(256) << 20;
  template <class T>
  std::vector<hsr::FrameBuffer<T>>& list() {
    if constexpr (std::is_same_v<T, float>) return floats_;
    else if constexpr (std::is_same_v<T, int32_t>) return ints_;
    else return colors_;
  }
  std::mutex m_;
  std::vector<hsr::FrameBuffer<float>> floats_;
  std::vector<hsr::FrameBuffer<int32_t>> ints_;
  std::vector<hsr::FrameBuffer<hsr::Rgba8>> colors_;
  size_t bytes_ = 0;
};

/// A Frame buffer moved out of its frame; back to the pool when NumPy frees its array.
template <class T>
struct VectorOwner : Owner {
  explicit VectorOwner(hsr::FrameBuffer<T>&& v) : data(std::move(v)) {}
  ~VectorOwner() override { BufferPool::instance().give(std::move(data)); }
  VectorOwner(const VectorOwner&) = delete;
  VectorOwner& operator=(const VectorOwner&) = delete;
  hsr::FrameBuffer<T> data;
};

/// Uninitialised storage of `bytes` (cache-line aligned, huge pages when large), for outputs the
/// module fills itself.
struct BlockOwner : Owner {
  explicit BlockOwner(size_t size) : bytes(size), data(hsr::detail::allocateBuffer(size)) {}
  ~BlockOwner() override { hsr::detail::freeBuffer(data, bytes); }
  BlockOwner(const BlockOwner&) = delete;
  BlockOwner& operator=(const BlockOwner&) = delete;
  size_t bytes;
  void* data;
};

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

template <class T>
py::array handOver(hsr::FrameBuffer<T>&& buffer, std::vector<py::ssize_t> shape, const py::dtype& dtype) {
  auto owner = std::make_unique<VectorOwner<T>>(std::move(buffer));
  void* data = owner->data.data();
  return handOver(std::move(owner), data, dtype, std::move(shape));
}

}  // namespace hsrpy

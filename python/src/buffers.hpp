// Memory the module hands to NumPy without copying: an array's base is a capsule named
// "hsr.buffer" whose pointer is the array's data and whose context owns the memory (a moved
// Frame buffer or a block of hsr::detail::allocateBuffer). NumPy frees it through the capsule
// when the last array viewing it is gone.
#pragma once
#include "common.hpp"

#include <utility>

namespace hsrpy {

inline constexpr const char* kBufferCapsule = "hsr.buffer";

struct Owner {
  virtual ~Owner() = default;
};

/// A Frame buffer moved out of its frame.
template <class T>
struct VectorOwner : Owner {
  explicit VectorOwner(hsr::FrameBuffer<T>&& v) : data(std::move(v)) {}
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

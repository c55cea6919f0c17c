// UnwrittenAllocator: a std::allocator whose default construction writes nothing, so a list of
// plain records can grow by resize() and then be written in place. The front end's chunk lists
// (SetupTriangles, frontend/chunks.hpp) use it; each list is grown by the one worker that owns it.
#pragma once
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace hsr {

/// An allocator whose default construction writes nothing (for an aggregate, trivially copyable
/// type: the storage already holds such an object, whose values come later): a list that grows by
/// resize() and is then written in place, without a pass of zeros first (set-up's chunk lists).
template <class T>
struct UnwrittenAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UnwrittenAllocator<U>;
  };
  UnwrittenAllocator() = default;
  template <class U>
  UnwrittenAllocator(const UnwrittenAllocator<U>&) noexcept {}
  template <class U>
  void construct(U*) noexcept {
    static_assert(std::is_aggregate_v<U> && std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>);
  }
  template <class U, class... A>
  void construct(U* p, A&&... a) {
    ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
};

}  // namespace hsr

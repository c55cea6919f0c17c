// Memory behaviour of a warm frame: once the buffers have grown to a scene's size, rendering
// the next frame with the tiled z-buffer into the same Frame allocates no buffers — only a few
// small objects (the statistics' stage list, a task wrapper or two). Counted by replacing the
// global operator new for this test binary (it only counts; every test still gets its memory).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <hsr/hsr.hpp>
#include <new>

namespace {
std::atomic<bool> counting{false};
std::atomic<uint64_t> allocations{0}, largest{0};

void note(std::size_t size) {
  if (!counting.load(std::memory_order_relaxed)) return;
  allocations.fetch_add(1, std::memory_order_relaxed);
  uint64_t seen = largest.load(std::memory_order_relaxed);
  while (size > seen && !largest.compare_exchange_weak(seen, size, std::memory_order_relaxed)) {
  }
}

void* allocate(std::size_t size) {
  note(size);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}

void* allocateAligned(std::size_t size, std::align_val_t align) {
  note(size);
  const std::size_t a = static_cast<std::size_t>(align);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return allocateAligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocateAligned(size, a); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void* operator new[](std::size_t size) { return allocate(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
// The nothrow forms too (std::stable_sort's buffer uses them): a partial set would pair the
// library's allocation with this file's free.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  note(size);
  return std::malloc(size ? size : 1);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  note(size);
  return std::malloc(size ? size : 1);
}
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  note(size);
  const std::size_t align = static_cast<std::size_t>(a);
  return std::aligned_alloc(align, (size + align - 1) / align * align);
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t& t) noexcept {
  return operator new(size, a, t);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace hsr {
namespace {

// The scene's camera (or a framing of it) at 640x360.
Camera cameraOf(const Scene& scene) {
  return resolveCamera(scene.camera ? *scene.camera : frameBounds(scene.bounds()), 640, 360, scene.bounds());
}

// Runs f with the allocation counters reset and counting.
template <class F>
void counted(F&& f) {
  allocations = 0;
  largest = 0;
  counting = true;
  f();
  counting = false;
}

TEST(Memory, WarmTiledFramesAllocateNoBuffers) {
  for (const char* name : {"builtin:sphere?n=200000", "builtin:city", "builtin:layers?n=8"}) {
    const Scene scene = loadScene(name);
    const Camera cam = cameraOf(scene);
    for (FrameOutputs outputs : {FrameOutputs::All, FrameOutputs::DepthOnly}) {
      RenderOptions o;
      o.threads = 2;
      o.outputs = outputs;
      Renderer renderer(scene, o);  // the algorithm object keeps its buffers from frame to frame
      Frame frame;
      renderer.render(cam, frame);  // warm-up: buffers grow to this scene's size
      renderer.render(cam, frame);
      counted([&] { renderer.render(cam, frame); });
      EXPECT_LE(allocations.load(), 8u) << name;  // 4 at the time of writing, none above 160 bytes
      EXPECT_LE(largest.load(), 1024u) << name << ": a buffer was allocated during a warm frame";
      EXPECT_GT(frame.stats.covered_pixels, 1000u) << name;
    }
  }
}

// The occlusion buffer, with mesh culling's two passes on the city: a warm render allocates no
// buffer either (each pass's set-up records and bins are kept from frame to frame).
TEST(Memory, WarmOcclusionRendersAllocateNoBuffers) {
  for (const char* name : {"builtin:city", "builtin:layers?n=64", "builtin:cubes"}) {
    const Scene scene = loadScene(name);
    const Camera cam = cameraOf(scene);
    for (Cull cull : {Cull::None, Cull::Back}) {
      OcclusionBuffer buffer;
      buffer.render(scene, cam, {DepthFormat{}, cull, 2});  // warm-up
      buffer.render(scene, cam, {DepthFormat{}, cull, 2});
      const Stats* st = nullptr;
      counted([&] { st = &buffer.render(scene, cam, {DepthFormat{}, cull, 2}); });
      EXPECT_LE(allocations.load(), 8u) << name;
      EXPECT_LE(largest.load(), 1024u) << name << ": a buffer was allocated during a warm render";
      if (std::string(name) == "builtin:city") EXPECT_GT(st->detailCount("meshes_culled_occlusion").value_or(0), 500u);
    }
  }
}

}  // namespace
}  // namespace hsr

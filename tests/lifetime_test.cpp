// Library objects (scenes, cameras, frames, every algorithm's render, SVG output, a verification
// against the reference) created, used and destroyed thousands of times keep the process's
// resident memory flat: nothing leaks or accumulates across renders.
#include <gtest/gtest.h>
#include <hsr/hsr.hpp>

#include <fstream>
#include <unistd.h>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HSR_HAS_ASAN 1
#endif
#endif
#ifndef HSR_HAS_ASAN
#define HSR_HAS_ASAN 0
#endif

namespace hsr {
namespace {

// Resident memory of this process in bytes (/proc/self/statm's second field, in pages).
double residentBytes() {
  std::ifstream statm("/proc/self/statm");
  double size = 0, resident = 0;
  statm >> size >> resident;
  return resident * double(sysconf(_SC_PAGE_SIZE));
}

// One cycle: a fresh scene and camera, one algorithm's render into a fresh frame, and every
// eighth cycle an SVG and a verification; everything is destroyed at the end.
void cycle(size_t i) {
  const auto& all = algorithms();
  const Scene scene = loadScene("builtin:random?n=120&seed=" + std::to_string(i % 5));
  const Camera camera = resolveCamera(*scene.camera, 40, 30, scene.bounds());
  RenderOptions options;
  options.algorithm = all[i % all.size()].name;
  const Frame frame = render(scene, camera, options);
  ASSERT_EQ(frame.faceId.size(), size_t(40 * 30));
  if (i % 8 == 0) {
    RenderOptions painter;
    painter.algorithm = "bsp";
    EXPECT_FALSE(renderSvg(scene, camera, painter).empty());
    RenderOptions raycast;
    raycast.algorithm = "raycast";
    const VerifyResult check = verifyAgainstReference(scene, camera, options, frame, render(scene, camera, raycast));
    EXPECT_LE(check.wrong_pixels + check.ambiguous_pixels, frame.faceId.size());
  }
}

TEST(Lifetime, ThousandsOfObjectsCreatedAndDestroyedKeepResidentMemoryFlat) {
  const size_t algorithmCount = algorithms().size();
  // Warm up: each algorithm a few times, so that caches, pools and the allocator's arenas reach
  // their working size.
  for (size_t i = 0; i < 4 * algorithmCount; ++i) cycle(i);
  const double before = residentBytes();
  constexpr size_t kCycles = 3000;
  for (size_t i = 0; i < kCycles; ++i) cycle(i);
  const double growth = residentBytes() - before;
#if defined(__SANITIZE_ADDRESS__) || HSR_HAS_ASAN
  // AddressSanitizer's quarantine keeps freed memory (up to 256 MiB, with its shadow and
  // metadata besides) to catch use after free; its leak checker covers this case instead.
  constexpr double kAllowed = 448.0 * (1 << 20);
#else
  constexpr double kAllowed = 4.0 * (1 << 20);
#endif
  EXPECT_LT(growth, kAllowed) << kCycles << " cycles grew resident memory by " << growth / (1 << 20) << " MiB";
}

}  // namespace
}  // namespace hsr

// The memory limit (hsr/limits.hpp): absurd requests refused up front by each path that would
// otherwise grow until the out-of-memory killer; the explicit stacks of the tree builders and
// painters tested with inputs deep enough to overflow a recursive one; and renders from several
// threads over one shared scene (also run under ThreadSanitizer: scripts/sanitize.sh thread).
#include <gtest/gtest.h>
#include <hsr/hsr.hpp>

#include <cstring>
#include <thread>

namespace hsr {
namespace {

// Sets the limit for one test and restores the machine's default after it.
struct LimitGuard {
  explicit LimitGuard(uint64_t bytes) { setMemoryLimit(bytes); }
  ~LimitGuard() { setMemoryLimit(0); }
};

constexpr uint64_t kMiB = uint64_t(1) << 20;

// What `f` throws: its InputError, or an empty plain one when it throws none.
InputError refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e;
  }
  return InputError("");
}

TEST(MemoryLimit, DefaultsToTheMachinesAvailableMemory) {
  setMemoryLimit(0);
  EXPECT_GT(memoryLimit(), 64 * kMiB);
  setMemoryLimit(100 * kMiB);
  EXPECT_EQ(memoryLimit(), 100 * kMiB);
  setMemoryLimit(0);
}

TEST(MemoryLimit, ParsesSizes) {
  EXPECT_EQ(parseMemorySize("512M"), 512 * kMiB);
  EXPECT_EQ(parseMemorySize("2G"), 2048 * kMiB);
  EXPECT_EQ(parseMemorySize("2GiB"), 2048 * kMiB);
  EXPECT_EQ(parseMemorySize("1.5g"), 1536 * kMiB);
  EXPECT_EQ(parseMemorySize("1T"), 1024 * 1024 * kMiB);
  EXPECT_EQ(parseMemorySize("1048576"), kMiB);
  for (const char* bad : {"", "G", "12Q", "-1G", "nan", "1e400", "100K", "5 G"})
    EXPECT_THROW(parseMemorySize(bad), InputError) << bad;
}

TEST(MemoryLimit, RefusesABuiltinSceneBeforeGeneratingIt) {
  LimitGuard limit(64 * kMiB);
  const std::string why = refusal([] { loadScene("builtin:random?n=5000000"); }).what();
  EXPECT_NE(why.find("builtin:random?n=5000000 needs about 611 MiB, more than the memory limit of 64 MiB"),
            std::string::npos)
      << why;
  EXPECT_EQ(refusal([] { loadScene("builtin:city?blocks=1000"); }).setting(), Setting::MaxMemory);
  EXPECT_EQ(refusal([] { loadScene("builtin:clutter?n=5000&detail=16"); }).setting(), Setting::MaxMemory);
  EXPECT_STREQ(refusal([] { loadScene("builtin:random?n=1000"); }).what(), "");
}

TEST(MemoryLimit, RefusesAnImageTooLargeBeforeAllocatingIt) {
  LimitGuard limit(128 * kMiB);
  const Scene scene = loadScene("builtin:cubes");
  const Camera camera = resolveCamera(*scene.camera, 16384, 16384, scene.bounds());
  for (const AlgorithmInfo& a : algorithms()) {
    RenderOptions options;
    options.algorithm = a.name;
    const std::string why = refusal([&] { render(scene, camera, options); }).what();
    EXPECT_NE(why.find("a 16384x16384 image with 48 triangles needs about"), std::string::npos) << a.name << ": " << why;
  }
  // The same image fits with fewer buffers asked for but not with --verify's second frame.
  const Camera small = resolveCamera(*scene.camera, 2048, 2048, scene.bounds());
  RenderOptions options;
  EXPECT_STREQ(refusal([&] { render(scene, small, options); }).what(), "");
  options.verify = true;
  setMemoryLimit(40 * kMiB);
  EXPECT_EQ(refusal([&] { render(scene, small, options); }).setting(), Setting::MaxMemory);
}

// Random triangles of the size of the box cross each other everywhere: the BSP tree and the
// depth sort split them into many times their number of fragments.
TEST(MemoryLimit, StopsBspAndNewellSplittingAtTheLimit) {
  const Scene scene = loadScene("builtin:random?n=3000&size=1&seed=2");
  const Camera camera = resolveCamera(*scene.camera, 64, 48, scene.bounds());
  LimitGuard limit(4 * kMiB);
  for (const char* name : {"bsp", "newell"}) {
    RenderOptions options;
    options.algorithm = name;
    const InputError why = refusal([&] { render(scene, camera, options); });
    EXPECT_EQ(why.setting(), Setting::MaxMemory) << why.what();
    EXPECT_TRUE(why.subject().starts_with(std::string(name) + ": the ")) << why.what();
    EXPECT_TRUE(why.detail().ends_with("more than the memory limit of 4 MiB")) << why.what();
  }
}

// 20000 parallel layers drawn back to front: with heuristic=first every node of the BSP tree
// has one child, a tree 20000 deep; the depth sort and the midpoint subdivision (at its
// deepest) see the same stack. Each keeps its own explicit stack, so nothing overflows.
TEST(DeepStructures, AChainOfTwentyThousandLayers) {
  const Scene scene = loadScene("builtin:layers?n=20000&order=back-to-front");
  const Camera camera = resolveCamera(*scene.camera, 32, 24, scene.bounds());
  RenderOptions options;
  options.algorithm = "bsp";
  options.params["heuristic"] = "first";
  const Frame bsp = render(scene, camera, options);
  EXPECT_GE(bsp.stats.detailCount("depth").value_or(0), 20000u);
  options.algorithm = "raycast";
  options.params.clear();
  const Frame reference = render(scene, camera, options);
  EXPECT_EQ(std::memcmp(bsp.faceId.data(), reference.faceId.data(), bsp.faceId.size() * sizeof(int32_t)), 0);
  for (const char* name : {"newell", "midpoint"}) {
    options.algorithm = name;
    if (std::string(name) == "midpoint") options.params["max-depth"] = "16";
    const Frame f = render(scene, camera, options);
    EXPECT_EQ(std::memcmp(f.faceId.data(), reference.faceId.data(), f.faceId.size() * sizeof(int32_t)), 0) << name;
  }
}

// Every algorithm rendering one shared const scene from four threads at once, each into its
// own frame, gives the bits of rendering alone.
TEST(Concurrent, EveryAlgorithmFromFourThreadsOverOneSharedScene) {
  const Scene scene = loadScene("builtin:random?n=300&seed=9");
  const Camera camera = resolveCamera(*scene.camera, 48, 32, scene.bounds());
  for (const AlgorithmInfo& a : algorithms()) {
    RenderOptions options;
    options.algorithm = a.name;
    options.threads = 1;
    const Frame alone = render(scene, camera, options);
    std::vector<Frame> frames(4);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < frames.size(); ++t)
      threads.emplace_back([&, t] {
        RenderOptions mine = options;
        mine.threads = int(t % 2) + 1;
        frames[t] = render(scene, camera, mine);
      });
    for (std::thread& t : threads) t.join();
    for (const Frame& f : frames) {
      ASSERT_EQ(f.faceId.size(), alone.faceId.size()) << a.name;
      EXPECT_EQ(std::memcmp(f.faceId.data(), alone.faceId.data(), f.faceId.size() * sizeof(int32_t)), 0) << a.name;
      EXPECT_EQ(std::memcmp(f.depth.data(), alone.depth.data(), f.depth.size() * sizeof(float)), 0) << a.name;
      EXPECT_EQ(std::memcmp(f.color.data(), alone.color.data(), f.color.size() * sizeof(Rgba8)), 0) << a.name;
    }
  }
}

}  // namespace
}  // namespace hsr

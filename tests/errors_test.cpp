// Keyed input errors (hsr/common.hpp): a library error about a setting carries the setting, its
// subject and the detail, words them neutrally in what() (no front end's spelling), and lets a
// front end word them again in its own terms (InputError::worded).
#include <gtest/gtest.h>
#include <hsr/hsr.hpp>

#include <exception>
#include <functional>

namespace hsr {
namespace {

// The InputError `f` throws (a test failure, and an empty plain error, when it throws none).
InputError thrown(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError thrown";
  return InputError("");
}

TEST(KeyedError, CarriesItsSettingSubjectAndDetail) {
  const InputError e(Setting::Param, "raster=fast", "expected one of tiled, halfspace");
  EXPECT_EQ(e.setting(), Setting::Param);
  EXPECT_EQ(e.subject(), "raster=fast");
  EXPECT_EQ(e.detail(), "expected one of tiled, halfspace");
  EXPECT_STREQ(e.what(), "parameter raster=fast: expected one of tiled, halfspace");
  EXPECT_EQ(e.worded("--param"), "--param raster=fast: expected one of tiled, halfspace");
  EXPECT_EQ(e.worded("params={'raster': 'fast'}", ""), "params={'raster': 'fast'}: expected one of tiled, halfspace");

  // Copies, and a rethrow through std::exception_ptr, keep the key.
  const InputError copy = e;
  EXPECT_EQ(copy.setting(), Setting::Param);
  EXPECT_EQ(copy.subject(), "raster=fast");
  const InputError rethrown = thrown([&] { std::rethrow_exception(std::make_exception_ptr(e)); });
  EXPECT_EQ(rethrown.detail(), e.detail());
}

TEST(KeyedError, TheMemoryLimitNamesItsSettingLast) {
  const InputError e(Setting::MaxMemory, "a 64x64 image", "needs about 9 MiB, more than the memory limit of 4 MiB");
  EXPECT_STREQ(e.what(), "a 64x64 image needs about 9 MiB, more than the memory limit of 4 MiB");
  EXPECT_EQ(e.worded("--max-memory"), "a 64x64 image needs about 9 MiB, more than the memory limit of 4 MiB (--max-memory)");
}

TEST(KeyedError, APlainErrorIsItsMessageUnderAnyName) {
  const InputError e("scene.obj:3: bad vertex");
  EXPECT_EQ(e.setting(), Setting::None);
  EXPECT_EQ(e.subject(), "");
  EXPECT_EQ(e.detail(), "");
  EXPECT_EQ(e.worded("--size"), "scene.obj:3: bad vertex");
}

// The library's own checks throw keyed errors worded in no front end's terms.
TEST(KeyedError, TheLibrarysChecksKeyTheirErrors) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera camera = resolveCamera(*scene.camera, 32, 24, scene.bounds());
  struct Case {
    std::function<void()> f;
    Setting setting;
    std::string subject, what;
  };
  TiledSwitches switches;
  ShadowOptions shadows;
  shadows.mapSize = 8;
  RenderOptions unknown;
  unknown.algorithm = "nope";
  RenderOptions badParam;
  badParam.params["raster"] = "fast";
  RenderOptions depthOnly;
  depthOnly.outputs = FrameOutputs::DepthOnly;
  depthOnly.verify = true;
  Camera tooWide = camera;
  tooWide.width = 0;
  const std::vector<Case> cases{
      {[] { DepthFormat::parse("u17"); }, Setting::DepthFormat, "", "depth format: unknown storage 'u17' (u16, u24, u32, f32)"},
      {[] { DepthFormat::parse("u16:w"); }, Setting::DepthFormat, "", "depth format: unknown mapping 'w' (z, reversed, inv, linear)"},
      {[&] { switchOff(switches, "warp"); }, Setting::SwitchOff, "warp", ""},
      {[&] { checkShadowOptions(shadows); }, Setting::ShadowMapSize, "8", ""},
      {[&] { render(scene, camera, unknown); }, Setting::Algorithm, "", ""},
      {[&] { render(scene, camera, badParam); }, Setting::Param, "raster=fast", ""},
      {[&] { render(scene, camera, depthOnly); }, Setting::Verify, "", ""},
      {[&] { render(scene, tooWide, RenderOptions{}); }, Setting::Size, "0x24", ""},
  };
  for (const Case& c : cases) {
    const InputError e = thrown(c.f);
    EXPECT_EQ(e.setting(), c.setting) << e.what();
    EXPECT_EQ(e.subject(), c.subject) << e.what();
    if (!c.what.empty()) EXPECT_EQ(e.what(), c.what);
    EXPECT_EQ(std::string(e.what()).find("--"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hsr

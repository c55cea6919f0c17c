// renderViews and the per-pixel attributes of include/hsr/views.hpp: many views equal the same
// views rendered one by one, errors reach the caller, barycentrics and instance ids are right.
#include <hsr/views.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>

#include "test_scenes.hpp"

namespace hsr {
namespace {

std::vector<Camera> orbit(const Scene& scene, int count, int width, int height) {
  std::vector<Camera> cameras;
  const Bounds3 b = scene.bounds();
  for (int i = 0; i < count; ++i) {
    CameraSpec spec;
    const double a = 6.283185307179586 * i / count;
    spec.target = b.center();
    spec.eye = b.center() + dvec3(6 * std::cos(a), 2.0 + 0.1 * i, 6 * std::sin(a));
    cameras.push_back(resolveCamera(spec, width, height, b));
  }
  return cameras;
}

TEST(RenderViews, EveryViewHasTheBitsOfRenderingItAlone) {
  const Scene scene = test::boxesScene();
  const std::vector<Camera> cameras = orbit(scene, 7, 96, 72);
  for (int threads : {1, 2, 3, 8}) {
    RenderOptions options;
    options.threads = threads;
    std::vector<int> delivered(cameras.size(), 0);
    renderViews(scene, cameras, options, [&](size_t i, const Frame& frame, int) {
      const Frame alone = render(scene, cameras[i], options);
      EXPECT_EQ(test::firstDifference(frame.depth, alone.depth), -1) << "view " << i << ", threads " << threads;
      EXPECT_EQ(test::firstDifference(frame.faceId, alone.faceId), -1);
      EXPECT_EQ(test::firstDifference(frame.color, alone.color), -1);
      ++delivered[i];  // each view once, on one thread: no race on its own counter
    });
    for (int n : delivered) EXPECT_EQ(n, 1);
  }
}

TEST(RenderViews, FramesKeptByTheCallerGiveTheSameBits) {
  const Scene scene = test::boxesScene();
  const std::vector<Camera> cameras = orbit(scene, 5, 64, 48);
  std::vector<Frame> frames;
  for (int threads : {2, 1, 8, 2}) {  // frames of another size and count from the call before
    RenderOptions options;
    options.threads = threads;
    options.outputs = FrameOutputs::FaceIds;
    renderViews(
        scene, cameras, options,
        [&](size_t i, const Frame& frame, int) {
          const Frame alone = render(scene, cameras[i], options);
          EXPECT_EQ(test::firstDifference(frame.depth, alone.depth), -1) << "view " << i << ", threads " << threads;
          EXPECT_EQ(test::firstDifference(frame.faceId, alone.faceId), -1);
          EXPECT_TRUE(frame.triangleId.empty() && frame.color.empty());
        },
        frames);
    EXPECT_EQ(frames.size(), size_t(threads) > cameras.size() ? 1u : size_t(threads));
  }
}

// A frame lent memory of the caller's (ViewTarget, lentBuffer) is rendered straight into it, with
// the bits of rendering the view alone, on every algorithm the views run.
TEST(RenderViews, ViewsRenderStraightIntoLentMemory) {
  const Scene scene = test::boxesScene();
  const std::vector<Camera> cameras = orbit(scene, 5, 64, 48);
  const size_t pixels = 64 * 48;
  for (const char* algorithm : {"zbuffer", "painter", "reverse-painter", "raycast"})
    for (int threads : {1, 2}) {
      RenderOptions options;
      options.threads = threads;
      options.algorithm = algorithm;
      FrameBuffer<float> depth(cameras.size() * pixels, -1.0f);  // (cache-line aligned, as views' slices)
      FrameBuffer<Rgba8> color(cameras.size() * pixels);
      std::vector<Frame> frames;
      renderViews(
          scene, cameras, options,
          [&](size_t i, const Frame& frame, int) {
            EXPECT_EQ(frame.depth.data(), depth.data() + i * pixels) << algorithm;
            EXPECT_EQ(frame.color.data(), color.data() + i * pixels) << algorithm;
          },
          frames,
          [&](size_t i, Frame& frame) {
            frame.depth = lentBuffer(depth.data() + i * pixels, pixels);
            frame.color = lentBuffer(color.data() + i * pixels, pixels);
          });
      for (size_t i = 0; i < cameras.size(); ++i) {
        const Frame alone = render(scene, cameras[i], options);
        EXPECT_TRUE(std::equal(alone.depth.begin(), alone.depth.end(), depth.begin() + ptrdiff_t(i * pixels)))
            << algorithm << " view " << i;
        EXPECT_TRUE(std::equal(alone.color.begin(), alone.color.end(), color.begin() + ptrdiff_t(i * pixels)))
            << algorithm << " view " << i;
      }
    }
}

// A lent buffer keeps the memory's contents, never frees it, moves to memory of its own when it
// grows past it, and its copies own their memory.
TEST(RenderViews, LentBuffersBorrowAndNeverFree) {
  std::vector<int32_t> memory(32, 7);
  FrameBuffer<int32_t> lent = lentBuffer(memory.data(), 16);
  EXPECT_EQ(lent.data(), memory.data());
  EXPECT_EQ(lent.size(), 16u);
  EXPECT_EQ(lent[15], 7);  // not zeroed
  const FrameBuffer<int32_t> copy = lent;
  EXPECT_NE(copy.data(), memory.data());
  EXPECT_EQ(copy.get_allocator().lent(), nullptr);
  lent.resize(8);
  lent.resize(16);
  EXPECT_EQ(lent.data(), memory.data());
  lent[0] = 3;
  EXPECT_EQ(memory[0], 3);
  lent.resize(17);  // past the memory: its own now, the elements carried over
  EXPECT_NE(lent.data(), memory.data());
  EXPECT_EQ(lent[0], 3);
  EXPECT_EQ(lent[16], 0);  // (its own memory: new elements are zeroed)
  FrameBuffer<int32_t> own(4);
  EXPECT_EQ(own[3], 0);
}

TEST(RenderViews, TheFirstErrorReachesTheCaller) {
  const Scene scene = test::boxesScene();
  const std::vector<Camera> cameras = orbit(scene, 6, 32, 24);
  RenderOptions options;
  options.threads = 2;
  std::atomic<int> calls{0};
  EXPECT_THROW(renderViews(scene, cameras, options,
                           [&](size_t i, const Frame&, int) {
                             ++calls;
                             if (i == 1) throw InputError("view 1 failed");
                           }),
               InputError);
  EXPECT_LE(calls.load(), 6);
  options.algorithm = "nope";
  EXPECT_THROW(renderViews(scene, cameras, options, [](size_t, const Frame&, int) {}), InputError);
}

TEST(Attributes, BarycentricsPutThePixelCentreOnTheTriangle) {
  const Scene scene = test::boxesScene();
  const Camera camera = orbit(scene, 3, 80, 60)[1];
  const Frame frame = render(scene, camera, RenderOptions{});
  std::vector<float> b(3 * frame.depth.size());
  resolveBarycentrics(scene, camera, frame, b.data(), 2);
  int checked = 0;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const size_t i = frame.index(x, y);
      if (frame.triangleId[i] < 0) {
        EXPECT_EQ(b[3 * i] + b[3 * i + 1] + b[3 * i + 2], 0.0f);
        continue;
      }
      const Triangle& t = scene.triangles[size_t(frame.triangleId[i])];
      const dvec3 p = double(b[3 * i]) * scene.positions[t.v[0]] + double(b[3 * i + 1]) * scene.positions[t.v[1]] +
                      double(b[3 * i + 2]) * scene.positions[t.v[2]];
      const dvec4 h = camera.toPixelH(p);
      EXPECT_NEAR(h.x / h.w, x + 0.5, 1e-3);
      EXPECT_NEAR(h.y / h.w, y + 0.5, 1e-3);
      EXPECT_NEAR(h.z, frame.depth[i], 1e-5 * frame.depth[i]);
      ++checked;
    }
  EXPECT_GT(checked, 500);
}

TEST(Attributes, FaceValuesFollowTheMeshOfEachFace) {
  const Scene scene = test::boxesScene();
  const std::vector<int32_t> mesh = faceMeshIndices(scene);
  ASSERT_EQ(mesh.size(), scene.faceCount());
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    for (uint32_t f = scene.meshes[m].firstFace; f < scene.meshes[m].firstFace + scene.meshes[m].faceCount; ++f)
      EXPECT_EQ(mesh[f], int32_t(m));
  std::vector<int32_t> value(scene.faceCount());
  for (size_t f = 0; f < value.size(); ++f) value[f] = int32_t(100 + f);
  const Frame frame = render(scene, orbit(scene, 2, 64, 48)[0], RenderOptions{});
  std::vector<int32_t> out(frame.faceId.size());
  resolveFaceValues(frame, value, -7, out.data(), 2);
  for (size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i], frame.faceId[i] < 0 ? -7 : 100 + frame.faceId[i]);
}

}  // namespace
}  // namespace hsr

// The per-pixel state of a z-buffer that an algorithm drives itself, fragment by fragment or block
// by block, instead of through the drawing service's loop (hzb.cpp, midpoint.cpp): the stored
// depth values, and per pixel the set-up triangle that wrote last; then resolved into the frame's
// face ids, exact eye depths and colours. The same depth test, the same stored bits and the same
// resolve as the drawing service's DepthTest rule (draw.cpp), so such an algorithm differs from
// the textbook z-buffer only in which fragments it tests.
#pragma once
#include <hsr/options.hpp>

#include <span>
#include <vector>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "core/depth_map.hpp"
#include "scene/shading.hpp"
#include "frontend/frontend.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr::algo {

template <DepthStorage S, DepthMapping M>
class ZBufferPixels {
 public:
  using T = DepthT<S>;

  ZBufferPixels(const Camera& camera, const RenderOptions& options, Frame& frame)
      : camera_(camera), options_(options), frame_(frame), clear_(quantizeDepth<S>(options.depthFormat.clearValue())),
        depth_(size_t(camera.width) * size_t(camera.height), clear_),
        winner_(depth_.size(), 0) {}

  /// "a is strictly nearer than b" in stored values (the depth test's comparison, uncounted).
  static bool nearer(T a, T b) { return storedNearer<M>(double(a), double(b)); }
  /// The nearer / farther of two stored values.
  static T nearest(T a, T b) { return nearer(a, b) ? a : b; }
  static T farthest(T a, T b) { return nearer(a, b) ? b : a; }

  T clearValue() const { return clear_; }
  T at(size_t idx) const { return depth_[idx]; }
  DepthSetup depthSetup() const { return {options_.depthFormat, camera_.near, camera_.far, camera_.orthographic}; }

  /// The mapped depth planes of triangle t, for fragment().
  MappedPlanes planes(const SetupTriangle& t) const {
    return mapPlanes<M>(t.depthNum, t.depthDen, camera_.near, camera_.far, camera_.orthographic);
  }
  /// The value triangle t's fragment at pixel (x, y) stores (the drawing service's bits).
  static T fragment(const MappedPlanes& m, int x, int y) {
    return T(fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5)));
  }

  /// The depth test of triangle i's fragment z at pixel idx (draw.hpp's depthTest): written when
  /// strictly nearer.
  bool test(size_t idx, T z, uint32_t i, DrawCounters& n) {
    if (!depthTest<M>(z, depth_[idx], n)) return false;
    claim(idx, i, n);
    return true;
  }
  /// Triangle i's fragment z written at pixel idx without a test.
  void write(size_t idx, T z, uint32_t i, DrawCounters& n) {
    storeDepth(z, depth_[idx], n);
    claim(idx, i, n);
  }

  /// Face ids, eye depths and colours of every pixel from the last fragment written: the drawing
  /// service's resolve (resolvePixels).
  void resolve(std::span<const SetupTriangle> tris, const TriangleShader& shade, DrawCounters& n) {
    const bool color = has(options_.outputs, FrameOutputs::Color);
    const PixelRect image{0, 0, camera_.width - 1, camera_.height - 1, size_t(camera_.width)};
    resolvePixels(
        image, winner_, tris, options_.outputs, nullptr,
        [&](uint32_t w, size_t idx) {
          if (color) frame_.color[idx] = triangleColor(tris[w], shade);
        },
        frame_, n);
  }

  /// Per pixel, 1 + the index of the triangle that wrote it last; 0 where none did.
  std::span<const uint32_t> winners() const { return winner_; }

  void addMemory(Stats& st) const {
    st.addMemory("depth_buffer", depth_.size() * sizeof(T));
    st.addMemory("winner_ids", winner_.size() * sizeof(uint32_t));
  }

 private:
  // The fragment of triangle i that wrote pixel idx: the winner, counted.
  void claim(size_t idx, uint32_t i, DrawCounters& n) {
    winner_[idx] = i + 1;
    countWritten(idx, frame_, n);
  }

  const Camera& camera_;
  const RenderOptions& options_;
  Frame& frame_;
  const T clear_;
  std::vector<T> depth_;          // the stored values
  std::vector<uint32_t> winner_;  // 1 + the index of the last triangle written, 0 = none
};

}  // namespace hsr::algo

// The per-pixel state of a z-buffer that an algorithm drives itself, fragment by fragment or block
// by block, instead of through the drawing service's loop (hzb.cpp, midpoint.cpp): the stored
// depth values, and per pixel the set-up triangle that wrote last; then resolved into the frame's
// face ids, exact eye depths and colours. The same depth test, the same stored bits and the same
// resolve as the drawing service's DepthTest rule (draw.cpp), so such an algorithm differs from
// the textbook z-buffer only in which fragments it tests.
#pragma once
#include <hsr/render.hpp>

#include <span>
#include <vector>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "core/depth_map.hpp"
#include "core/shading.hpp"
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
        winner_(options.outputs != FrameOutputs::DepthOnly ? depth_.size() : 0, 0) {}

  /// "a is strictly nearer than b" in stored values: the depth test.
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

  /// The depth test of triangle i's fragment z at pixel idx: written when strictly nearer.
  bool test(size_t idx, T z, uint32_t i, DrawCounters& n) {
    ++n.depthTests;
    if (!nearer(z, depth_[idx])) return false;
    write(idx, z, i, n);
    return true;
  }
  /// Triangle i's fragment z written at pixel idx without a test.
  void write(size_t idx, T z, uint32_t i, DrawCounters& n) {
    depth_[idx] = z;
    ++n.depthWrites;
    ++n.written;
    if (!winner_.empty()) winner_[idx] = i + 1;
    if (!frame_.color.empty()) ++n.colorWrites;
    if (!frame_.writes.empty()) ++frame_.writes[idx];
  }

  /// Face ids, eye depths and colours of every pixel from the last fragment written (depth only:
  /// the eye depth of the stored value), as the drawing service resolves; counts covered pixels.
  void resolve(std::span<const SetupTriangle> tris, const TriangleShader& shade, DrawCounters& n) {
    const bool faceIds = has(options_.outputs, FrameOutputs::FaceIds);
    const bool triangleIds = has(options_.outputs, FrameOutputs::TriangleIds);
    const bool color = has(options_.outputs, FrameOutputs::Color);
    for (int y = 0; y < camera_.height; ++y)
      for (int x = 0; x < camera_.width; ++x) {
        const size_t idx = frame_.index(x, y);
        if (winner_.empty()) {
          if (depth_[idx] == clear_) continue;
          frame_.depth[idx] =
              float(eyeDepthOfStored<S, M>(double(depth_[idx]), camera_.near, camera_.far, camera_.orthographic));
        } else {
          if (!winner_[idx]) continue;
          const SetupTriangle& t = tris[winner_[idx] - 1];
          if (faceIds) frame_.faceId[idx] = int32_t(t.face);
          if (triangleIds) frame_.triangleId[idx] = int32_t(t.triangle);
          frame_.depth[idx] = float(t.eyeDepth(x + 0.5, y + 0.5));
          if (color) frame_.color[idx] = triangleColor(t, shade);
        }
        ++n.covered;
      }
  }

  void addMemory(Stats& st) const {
    st.addMemory("depth_buffer", depth_.size() * sizeof(T));
    st.addMemory("winner_ids", winner_.size() * sizeof(uint32_t));
  }

 private:
  const Camera& camera_;
  const RenderOptions& options_;
  Frame& frame_;
  const T clear_;
  std::vector<T> depth_;          // the stored values
  std::vector<uint32_t> winner_;  // 1 + the index of the last triangle written, 0 = none (not kept for depth only)
};

/// The statistics every z-buffer of this kind reports, as drawScene fills them: front-end counts,
/// the counters, the memory of the set-up triangles, the front end's and the frame's (the
/// algorithm adds its own buffers'), the depth format.
inline void recordZBufferStats(Stats& st, const FrontEndCounters& fe, uint64_t frontEndBytes,
                               const std::vector<SetupTriangle>& triangles, const DrawCounters& n,
                               const RenderOptions& options, const Frame& frame) {
  st.depth_format = options.depthFormat.name();
  st.triangles_clipped = fe.clipped;
  st.triangles_degenerate = fe.degenerate;
  st.culled_backface = fe.culledBackface;
  st.culled_frustum = fe.culledFrustum;
  st.depth_tests = n.depthTests;
  st.depth_writes = n.depthWrites;
  st.color_writes = n.colorWrites;
  st.covered_pixels = n.covered;
  st.addMemory("setup_triangles", triangles.capacity() * sizeof(SetupTriangle));
  st.addMemory("front_end", frontEndBytes);
  addFrameMemory(st, frame);
}

}  // namespace hsr::algo

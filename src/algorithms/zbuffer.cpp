// The z-buffer (documents 000, 001, 003, 004) — the textbook reference every fast path is
// checked against. A depth buffer and a frame buffer of the image's size: depth cleared to
// "far", colour to the background; every fragment of every triangle, in submission order, is
// compared with the stored depth and, when strictly nearer, overwrites depth, colour and the
// triangle id. A resolve pass then turns triangle ids into face ids and exact eye depths.
#include <cmath>
#include <limits>

#include "algorithms/algorithms.hpp"
#include "core/depth_map.hpp"
#include "core/timer.hpp"
#include "frontend/frontend.hpp"
#include "raster/halfspace.hpp"
#include "raster/scanline.hpp"

namespace hsr::algo {
namespace {

// Stored depth type per storage: u24 lives in 32 bits.
template <DepthStorage S>
using DepthT = std::conditional_t<S == DepthStorage::U16, uint16_t, std::conditional_t<S == DepthStorage::F32, float, uint32_t>>;

template <DepthStorage S>
DepthT<S> quantize(double v) {
  if constexpr (S == DepthStorage::F32) {
    return float(v);
  } else {
    constexpr double scale = S == DepthStorage::U16 ? 65535.0 : S == DepthStorage::U24 ? 16777215.0 : 4294967295.0;
    return DepthT<S>(v * scale + 0.5);
  }
}

struct Counters {
  uint64_t tests = 0, writes = 0;
};

// One frame of the z-buffer for depth storage S and mapping M.
template <DepthStorage S, DepthMapping M>
void drawAll(const std::vector<SetupTriangle>& tris, const Camera& cam, const RenderOptions& opt,
             std::vector<uint32_t>& triOf, Frame& frame, Counters& n, uint64_t& depthBytes) {
  using T = DepthT<S>;
  const DepthFormat fmt = opt.depthFormat;
  constexpr bool greater = M == DepthMapping::Reversed || M == DepthMapping::Inv;
  const double n0 = cam.near, f0 = cam.far;
  const bool ortho = cam.orthographic;
  std::vector<T> zbuf(size_t(cam.width) * cam.height, quantize<S>(fmt.clearValue()));
  depthBytes = zbuf.size() * sizeof(T);
  for (uint32_t i = 0; i < tris.size(); ++i) {
    const SetupTriangle& t = tris[i];
    auto fragment = [&](int x, int y, double eyeDepth) {
      const T z = quantize<S>(mapDepth<M>(eyeDepth, n0, f0, ortho));
      const size_t idx = size_t(y) * size_t(cam.width) + size_t(x);
      ++n.tests;
      if (greater ? z > zbuf[idx] : z < zbuf[idx]) {  // strictly nearer: ties keep the first
        zbuf[idx] = z;
        triOf[idx] = i + 1;
        frame.color[idx] = t.color;
        ++n.writes;
      }
    };
    if (opt.raster == RasterKind::Scanline) rasterizeScanline(t, fragment);
    else rasterizeHalfSpace(t, fragment);
  }
}

template <DepthStorage S>
void drawForMapping(DepthMapping m, const std::vector<SetupTriangle>& tris, const Camera& cam,
                    const RenderOptions& opt, std::vector<uint32_t>& triOf, Frame& frame, Counters& n,
                    uint64_t& bytes) {
  switch (m) {
    case DepthMapping::Z: return drawAll<S, DepthMapping::Z>(tris, cam, opt, triOf, frame, n, bytes);
    case DepthMapping::Reversed: return drawAll<S, DepthMapping::Reversed>(tris, cam, opt, triOf, frame, n, bytes);
    case DepthMapping::Inv: return drawAll<S, DepthMapping::Inv>(tris, cam, opt, triOf, frame, n, bytes);
    case DepthMapping::Linear: return drawAll<S, DepthMapping::Linear>(tris, cam, opt, triOf, frame, n, bytes);
  }
}

// Instantiates the frame loop for the format: every storage x mapping is its own compiled loop.
void drawForFormat(DepthFormat fmt, const std::vector<SetupTriangle>& tris, const Camera& cam,
                   const RenderOptions& opt, std::vector<uint32_t>& triOf, Frame& frame, Counters& n,
                   uint64_t& bytes) {
  switch (fmt.storage) {
    case DepthStorage::U16: return drawForMapping<DepthStorage::U16>(fmt.mapping, tris, cam, opt, triOf, frame, n, bytes);
    case DepthStorage::U24: return drawForMapping<DepthStorage::U24>(fmt.mapping, tris, cam, opt, triOf, frame, n, bytes);
    case DepthStorage::U32: return drawForMapping<DepthStorage::U32>(fmt.mapping, tris, cam, opt, triOf, frame, n, bytes);
    case DepthStorage::F32: return drawForMapping<DepthStorage::F32>(fmt.mapping, tris, cam, opt, triOf, frame, n, bytes);
  }
}

}  // namespace

void zbuffer(const Scene& scene, const Camera& cam, const RenderOptions& opt, Frame& frame) {
  Timer timer, total;
  Stats& st = frame.stats;
  FrontEndOutput fe;
  runFrontEnd(scene, cam, opt, fe);
  st.addTime("frontend", timer.lap());

  // 0 = nothing drawn, else index + 1 into fe.triangles.
  std::vector<uint32_t> triOf(size_t(cam.width) * cam.height, 0);
  Counters n;
  uint64_t depthBytes = 0;
  drawForFormat(opt.depthFormat, fe.triangles, cam, opt, triOf, frame, n, depthBytes);
  st.addTime("raster", timer.lap());

  // Resolve: face id and exact eye depth (from the winning triangle's plane) per pixel.
  uint64_t covered = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const size_t idx = frame.index(x, y);
      if (!triOf[idx]) continue;
      const SetupTriangle& t = fe.triangles[triOf[idx] - 1];
      frame.faceId[idx] = int32_t(t.face);
      frame.triangleId[idx] = int32_t(t.triangle);
      frame.depth[idx] = float(t.eyeDepth(x + 0.5, y + 0.5));
      ++covered;
    }
  st.addTime("resolve", timer.lap());

  st.algorithm = "zbuffer";
  st.depth_format = opt.depthFormat.name();
  st.triangles_clipped = fe.clipped;
  st.triangles_degenerate = fe.degenerate;
  st.culled_backface = fe.culledBackface;
  st.culled_frustum = fe.culledFrustum;
  st.depth_tests = n.tests;
  st.depth_writes = n.writes;
  st.color_writes = n.writes;
  st.covered_pixels = covered;
  const uint64_t pixels = uint64_t(cam.width) * cam.height;
  st.memory_bytes = depthBytes + pixels * sizeof(uint32_t) /* triangle ids */ +
                    pixels * (sizeof(Rgba8) + 2 * sizeof(int32_t) + sizeof(float)) /* frame */ +
                    fe.memoryBytes();
}

}  // namespace hsr::algo

// An occlusion buffer: a CPU depth rasterizer to embed (occlusion culling, visibility queries),
// exact. Occluders are rasterized by the tiled z-buffer's kernel (depth only) into 64x64 screen
// tiles that keep their depth in tile form and are not turned into an image unless asked: a tile
// that one triangle covers in front of all it held is stored as that triangle's depth plane in
// O(1) (the Ukrainian paper's lossless z-buffer compression), and each tile and 8x8 block keeps bounds
// of its stored depth, so queries and later triangles skip whole tiles and blocks.
//
// Exact: the stored values are those the z-buffer stores (raster/fragment_depth.hpp), for every
// depth format and thread count; rectVisible() is answered from those values, not from
// approximations, and depthImage() maps them back to eye depth.
//
//   hsr::OcclusionBuffer buffer;
//   buffer.render(occluders, camera);                       // replaces what it held
//   if (buffer.boxVisible(object.bounds)) draw(object);        // or rectVisible(pixels, depth)
#pragma once
#include <hsr/camera.hpp>
#include <hsr/depth_format.hpp>
#include <hsr/frame.hpp>
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>
#include <hsr/scene.hpp>

#include <memory>

namespace hsr {

class OcclusionBuffer;
namespace algo {
struct MeshCulling;
// Internal (src/algorithms/occlusion.cpp): render()'s frames with ids use a buffer's mesh culling.
const MeshCulling& cullMeshes(OcclusionBuffer& buffer, const Scene& scene, const Camera& camera,
                              const RenderOptions& options);
}  // namespace algo

struct OcclusionOptions {
  DepthFormat depthFormat;  // default f32:reversed
  Cull cull = Cull::None;   // occluders are two-sided unless back/front
  int threads = 0;          // 0: all cores
  TiledSwitches tiled;      // the tiled rasterizer's optimisations, all on (render.hpp)
};

/// Queries (rectVisible, boxVisible, storedAt, depthImage) only read the buffer: several threads
/// may query it at once, as long as no render() runs meanwhile.
class OcclusionBuffer {
 public:
  OcclusionBuffer();
  ~OcclusionBuffer();
  OcclusionBuffer(OcclusionBuffer&&) noexcept;
  OcclusionBuffer& operator=(OcclusionBuffer&&) noexcept;

  /// Rasterizes the triangles of `scene` (finalized) seen by `camera` into the buffer, which is
  /// sized to the camera's image and cleared first. The scene need not outlive the call. Returns
  /// the frame's statistics (docs/conventions.md keys; covered_pixels is counted by depthImage()).
  /// Throws InputError for bad options, like render(). Buffers are reused from call to call.
  const Stats& render(const Scene& scene, const Camera& camera, const OcclusionOptions& options = {});

  int width() const;
  int height() const;

  /// Would a fragment at eye depth `eyeDepth` win the depth test at some pixel of the rectangle
  /// [x0, x1] x [y0, y1] (inclusive pixel coordinates, clipped to the image)? True when at some
  /// pixel the buffer holds a value farther than the one that depth stores (the depth format's
  /// mapping and rounding; nothing drawn counts as the clear value). An object whose nearest
  /// point is at `eyeDepth` and whose image lies in the rectangle is hidden when this is false
  /// (up to the few ulps by which a rasterized fragment's value may differ from the mapping of
  /// its eye depth: pass a slightly nearer depth for a strictly conservative test). A rectangle
  /// outside the image, or empty (x1 < x0 or y1 < y0), is not visible. Throws InputError for a
  /// NaN depth, or before the first render().
  bool rectVisible(int x0, int y0, int x1, int y1, double eyeDepth) const;

  /// Could any part of the world-space box show, drawn after the occluders? Conservative: false
  /// only when no fragment of the box's faces could pass the depth test — the box projected to
  /// the pixel rectangle around its corners, its nearest corner's eye depth tested as
  /// rectVisible does, one storage step nearer (room for a fragment's rounding). A box reaching
  /// the near plane (or behind the eye) is visible; one wholly beyond the far plane is not.
  /// Throws InputError before the first render() or for a box with NaN corners.
  bool boxVisible(const Bounds3& box) const;

  /// The value stored at pixel (x, y): the format's integer code or float, as a double (the
  /// clear value where nothing was drawn). Throws InputError outside the image.
  double storedAt(int x, int y) const;

  /// The eye depth of every pixel's stored value (within the format's rounding of render()'s
  /// exact depth), +inf where nothing was drawn, into frame.depth (faceId, triangleId and color emptied). Sets
  /// frame.stats to render()'s statistics with covered_pixels counted.
  void depthImage(Frame& frame) const;

 private:
  friend const algo::MeshCulling& algo::cullMeshes(OcclusionBuffer&, const Scene&, const Camera&, const RenderOptions&);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hsr

// Testing a mesh whole for occlusion: a pixel box and a nearest stored depth for all of a mesh's
// triangles (MeshBound), several meshes at once with SIMD (mesh_bounds.cpp). Asked for by the
// mesh culling of the occlusion buffer (algorithms/occlusion.cpp) and of hzb, on their workers,
// with a MeshView made once per frame (meshView, clusters.cpp).
#pragma once
#include <hsr/camera.hpp>
#include <hsr/scene.hpp>

#include <cstddef>
#include <cstdint>

#include "setup/fragment_depth.hpp"

namespace hsr {

/// Testing a mesh whole for occlusion (the occlusion buffer's mesh culling): a pixel box in the
/// image holding every pixel centre its triangles may cover, a stored value of the depth setup
/// that none of their fragments is nearer than, and the least eye depth of its box (conservative).
struct MeshBound {
  int16_t minX, minY, maxX, maxY;
  double nearest, zMin;
};
/// What meshBound needs from a camera and depth setup, once per frame.
struct MeshView {
  bool enabled = false;  // a perspective camera of the kind resolveCamera makes (ClusterView)
  dvec3 eye{0.0};
  double eyeLength = 0, gradient = 0;  // |eye|; ClusterView::gradient()
  dmat4 pixelFromWorld{1.0};
  // Its columns' positive and negative parts and magnitudes (the intervals of meshBound).
  dvec4 positive[4], negative[4], magnitude[4];
  const Camera* camera = nullptr;
  DepthSetup depth;
};
MeshView meshView(const Camera& cam, const DepthSetup& depth);
/// What meshBound found: no bound (None); none of the mesh's triangles covers a pixel centre of
/// the image (Outside: it draws nothing); or a MeshBound.
enum class MeshTest : uint8_t { None, Outside, Bounded };
/// Mesh `mesh` of `scene` bounded so (MeshBound, in `out`), when the camera is a perspective one
/// (view.enabled), the mesh has its planes (MeshRange::planeCount), its box lies inside the clip
/// volume (none of its triangles is clipped) and it is not seen too nearly edge on (see
/// frontend/mesh_bounds.cpp). meshBounds: the same for meshes [first, last) into tests[0,
/// last - first) and bounds[0, last - first), several at once with SIMD (a mesh's result does
/// not depend on the others).
MeshTest meshBound(const Scene& scene, size_t mesh, const MeshView& view, MeshBound& out);
void meshBounds(const Scene& scene, size_t first, size_t last, const MeshView& view, MeshTest* tests,
                MeshBound* bounds);

}  // namespace hsr

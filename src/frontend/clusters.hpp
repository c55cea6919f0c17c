// Clusters of scene triangles (Scene::clusters) taken whole: culled when every triangle is a back
// face, or deferred with a pixel box and a nearest depth bound (DeferredCluster) for the tiled
// rasterizer to set up only where they may show. Decided by the front end's set-up workers
// (frontend.cpp) from a ClusterView made once per frame; defined, with the proofs, in clusters.cpp.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/scene.hpp>

#include <cmath>

#include "frontend/chunks.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr {

/// What deciding about clusters needs from a camera, once per frame (deferCluster).
struct ClusterView {
  bool enabled = false;  // a perspective camera of the kind resolveCamera makes (no cluster is deferred otherwise)
  dvec3 eye{0.0};        // the centre of projection, in world space
  double fx = 0, fy = 0, skew = 0, cx = 0, cy = 0;  // the intrinsics (pixelFromCamera)
  /// 1/fx + |skew|/(fx fy) + 1/fy: see deferCluster.
  double gradient() const { return 1 / fx + std::abs(skew) / (fx * fy) + 1 / fy; }
};
ClusterView clusterView(const Camera& cam);

/// With Cull::Back: whether every triangle of `cluster` is a back face for setupTriangle (its
/// snapped signed area is > 0) and inside the clip volume, so runFrontEnd culls the cluster whole
/// (counted as kClusterTriangles back faces) without looking at its triangles (see clusters.cpp).
bool cullCluster(const TriangleCluster& cluster, const ClusterView& view, const Camera& cam,
                 const dmat4& pixelFromWorld);

/// Whether runFrontEnd(.deferBackFaces = true) defers cluster `cluster` of a scene (see
/// DeferredCluster), and if so its box and nearest bound in `out` (out.cluster is left to the
/// caller). Every triangle of a deferred cluster lies inside the clip volume (none is clipped)
/// and draws only inside the box, and no fragment it draws in `depth` is nearer than
/// out.nearest (see clusters.cpp for why). `pixelFromWorld`: cam.pixelFromCamera *
/// cam.cameraFromWorld.
bool deferCluster(const TriangleCluster& cluster, const ClusterView& view, const Camera& cam,
                  const dmat4& pixelFromWorld, const DepthSetup& depth, DeferredCluster& out);

/// Eye depth d (perspective) as a stored value of `depth` that no fragment whose eye depth is
/// at least d stores nearer: mapped, moved 1e-9 of itself nearer, clamped and rounded to storage
/// (all monotone; the room is for the rounding of the planes, deferCluster's step 4). Also the
/// bound of a whole mesh (frontend/mesh_bounds.hpp).
double storedNearest(double d, const DepthSetup& depth);

}  // namespace hsr

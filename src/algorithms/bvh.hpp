// Exact ray queries against a scene in camera space: the scene's triangles transformed once to
// camera space (double), a bounding volume hierarchy over them (binned SAH) and a watertight
// ray-triangle test. Built and queried by the raycast reference (raycast.cpp) and --verify
// (verify.cpp); queries are const and safe from many threads at once.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>
#include <limits>
#include <vector>

namespace hsr::algo {

/// A ray prepared for the watertight ray-triangle test of Woop, Benthin and Wald (JCGT 2013):
/// the axis kz along which the direction is largest becomes "forward", and every vertex is
/// sheared so that the ray becomes the kz axis through the origin. Each vertex is transformed the
/// same way whichever triangle it belongs to, and the 2D edge functions are exactly
/// antisymmetric in their two vertices, so a ray through a shared edge or vertex hits at least
/// one of the triangles sharing it: nothing falls through a closed mesh.
class WatertightRay {
 public:
  WatertightRay(const dvec3& origin, const dvec3& dir);

  /// Parameter t of the hit (point = origin + t * dir), or NaN on a miss. A triangle whose
  /// projection along the ray has zero area is never hit. Culling: a front face is
  /// counter-clockwise as seen, i.e. its normal (v1 - v0) x (v2 - v0) points against the ray.
  double intersect(const dvec3& v0, const dvec3& v1, const dvec3& v2, Cull cull) const;

  const dvec3& origin() const { return org_; }
  const dvec3& dir() const { return dir_; }

 private:
  dvec3 org_, dir_;
  int kx_, ky_, kz_;     // permuted axes
  double sx_, sy_, sz_;  // shear and scale: x' = v[kx] - sx v[kz], y' likewise, z' = sz v[kz]
};

/// Nearest hit of a ray: parameter t (the eye depth for camera rays) and triangle index.
struct RayHit {
  double t = std::numeric_limits<double>::infinity();
  int32_t triangle = -1;
  bool found() const { return triangle >= 0; }
};

/// Work counters of ray queries: ray-triangle tests and accepted (nearer) hits.
struct TraceCounters {
  uint64_t tests = 0, hits = 0;
};

/// The scene in camera space with a BVH over its non-degenerate triangles. Keeps references to
/// the scene and the camera, which must outlive it.
class CameraSpaceBvh {
 public:
  /// Transforms every vertex with camera.toCamera (double, so models far from the origin keep
  /// their precision) and builds the hierarchy on the calling thread.
  CameraSpaceBvh(const Scene& scene, const Camera& camera);

  /// Nearest hit with tMin <= t <= tMax among triangles not culled; on equal t the lower
  /// triangle index wins (as the z-buffer keeps the first drawn).
  RayHit closestHit(const WatertightRay& ray, double tMin, double tMax, Cull cull,
                    TraceCounters& counters) const;

  /// The camera ray through pixel position (px, py), traced within [near, far].
  RayHit tracePixel(double px, double py, Cull cull, TraceCounters& counters) const;

  /// Every hit of the camera ray through pixel position (px, py) within [near, far] among
  /// triangles not culled, appended to `hits` in no particular order (the A-buffer's fragments).
  void allPixelHits(double px, double py, Cull cull, std::vector<RayHit>& hits, TraceCounters& counters) const;

  /// Triangles with zero world-space area (or sent to infinity by the camera transform): left
  /// out of the hierarchy, never hit.
  uint64_t degenerateTriangles() const { return degenerate_; }
  /// Bytes held: camera-space vertices, nodes and the triangle order.
  uint64_t memoryBytes() const;

 private:
  // Children of an inner node are adjacent: first and first + 1. A leaf (count > 0) holds
  // order_[first .. first + count).
  struct Node {
    dvec3 lo, hi;
    uint32_t first = 0, count = 0;
  };

  void build(const std::vector<uint32_t>& candidates);
  // Whether the ray meets the box within [tMin, tMax] (widened by rounding margins); tEntry is
  // where it enters.
  static bool boxEntry(const Node& node, const dvec3& origin, const dvec3& invDir, double tMin, double tMax,
                       double& tEntry);

  const Scene& scene_;
  const Camera& camera_;
  std::vector<dvec3> vertices_;   // camera space, indexed like Scene::positions
  std::vector<Node> nodes_;       // nodes_[0] is the root (absent when there is no triangle)
  std::vector<uint32_t> order_;   // triangle indices in leaf order
  uint64_t degenerate_ = 0;
};

}  // namespace hsr::algo

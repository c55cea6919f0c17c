// Convex polygons cut by planes, in double precision: the classification and splitting that a
// BSP tree (bsp.cpp) and Newell's algorithm share. Polygons are vertex lists in world space;
// a plane is n . x = d. Pure functions, any thread.
#pragma once
#include <hsr/common.hpp>

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace hsr {
struct Scene;
}

namespace hsr::algo {

struct SplitPlane {
  dvec3 n{0.0};  // unit normal
  double d = 0;  // n . x = d on the plane
  double distance(const dvec3& x) const { return glm::dot(n, x) - d; }
};

/// Where a polygon lies against a plane: a vertex within `epsilon` of it counts as on it.
enum class PolygonSide : uint8_t {
  Coplanar,  // every vertex on the plane
  Front,     // some vertex in front, none behind
  Back,      // some vertex behind, none in front
  Spanning,  // vertices on both sides: the plane cuts it
};

/// The plane of a polygon from its vertices: Newell's normal (robust for any planar polygon,
/// and the best-fit direction for a slightly non-planar one) through the vertices' centroid.
/// Returns false for a polygon of no area (normal of length 0).
bool planeOfPolygon(std::span<const dvec3> polygon, SplitPlane& plane);

PolygonSide classifyPolygon(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon);

/// Cuts a convex polygon by the plane into the part in front and the part behind (each convex;
/// vertices on the plane go to both; a part of fewer than 3 vertices is returned empty). A cut
/// edge's new vertex is computed from the edge's ends in a fixed order (lexicographic), so two
/// polygons sharing the edge get the same point, bit for bit: no crack opens between them.
void splitPolygon(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon, std::vector<dvec3>& front,
                  std::vector<dvec3>& back);

/// Whether a polygon is planar within `epsilon` of its plane and convex (no reflex corner), so
/// that splitPolygon's pieces cover exactly it.
bool isPlanarConvex(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon);

/// "On the plane" for a scene: 1e-9 of its size (the larger of its bounding box's diagonal and its
/// largest coordinate), far above double rounding of a plane distance, far below any feature.
double sceneEpsilon(const Scene& scene);

/// The scene's faces as convex planar polygons, in face order: a face that is convex and planar
/// within `epsilon` as itself, any other as its triangles; faces of no area left out. `visit`
/// gets the vertices, the plane, the face and a triangle of it.
using PolygonVisitor =
    std::function<void(std::span<const dvec3> vertices, const SplitPlane& plane, uint32_t face, uint32_t triangle)>;
void forEachConvexPolygon(const Scene& scene, double epsilon, const PolygonVisitor& visit);

/// A polygon whose vertices are pool[first, first + count), part of scene face `face`.
struct PolygonRef {
  uint32_t first = 0, count = 0;
  uint32_t face = 0;
};

/// Pieces of one face meet along its cuts, and a later cut of one piece puts a vertex on the
/// shared edge that its neighbour lacks (a T-junction): snapped to the pixel grid, the two would
/// leave cracks at a few pixel centres. So every polygon's edges get, in order, the vertices of
/// its face's other polygons that lie on them (within epsilon); a polygon that gains vertices
/// gets new storage at the end of `pool`.
void closeTJunctions(std::vector<dvec3>& pool, std::span<PolygonRef> polygons, double epsilon);

}  // namespace hsr::algo

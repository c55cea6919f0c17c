// Convex polygons cut by planes, in double precision: the classification and splitting that a
// BSP tree (bsp.cpp) and Newell's algorithm share. Polygons are vertex lists in world space;
// a plane is n . x = d. Pure functions, any thread.
#pragma once
#include <hsr/common.hpp>

#include <cstdint>
#include <span>
#include <vector>

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

}  // namespace hsr::algo

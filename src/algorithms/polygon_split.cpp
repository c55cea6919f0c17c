// Convex polygons cut by planes (polygon_split.hpp).
#include "algorithms/polygon_split.hpp"

#include <cmath>

namespace hsr::algo {
namespace {

bool lexLess(const dvec3& a, const dvec3& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

// The point where the plane crosses edge (a, b), whose ends are strictly on opposite sides.
dvec3 crossing(const dvec3& a, const dvec3& b, const SplitPlane& plane) {
  const dvec3& p = lexLess(a, b) ? a : b;
  const dvec3& q = lexLess(a, b) ? b : a;
  const double sp = plane.distance(p), sq = plane.distance(q);
  return p + (sp / (sp - sq)) * (q - p);
}

}  // namespace

bool planeOfPolygon(std::span<const dvec3> polygon, SplitPlane& plane) {
  dvec3 n(0.0), centroid(0.0);
  for (size_t i = 0, k = polygon.size(); i < k; ++i) {
    const dvec3& a = polygon[i];
    const dvec3& b = polygon[(i + 1) % k];
    n += dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
    centroid += a;
  }
  const double length = glm::length(n);
  if (!(length > 0) || polygon.size() < 3) return false;
  plane.n = n / length;
  plane.d = glm::dot(plane.n, centroid / double(polygon.size()));
  return true;
}

PolygonSide classifyPolygon(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon) {
  bool front = false, back = false;
  for (const dvec3& v : polygon) {
    const double s = plane.distance(v);
    front |= s > epsilon;
    back |= s < -epsilon;
  }
  if (front && back) return PolygonSide::Spanning;
  if (front) return PolygonSide::Front;
  if (back) return PolygonSide::Back;
  return PolygonSide::Coplanar;
}

void splitPolygon(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon, std::vector<dvec3>& front,
                  std::vector<dvec3>& back) {
  front.clear();
  back.clear();
  const size_t k = polygon.size();
  auto side = [&](const dvec3& v) {
    const double s = plane.distance(v);
    return s > epsilon ? 1 : s < -epsilon ? -1 : 0;
  };
  for (size_t i = 0; i < k; ++i) {
    const dvec3& a = polygon[i];
    const dvec3& b = polygon[(i + 1) % k];
    const int sa = side(a), sb = side(b);
    if (sa >= 0) front.push_back(a);
    if (sa <= 0) back.push_back(a);
    if (sa * sb < 0) {  // the edge crosses the plane strictly: both parts get the crossing
      const dvec3 x = crossing(a, b, plane);
      front.push_back(x);
      back.push_back(x);
    }
  }
  if (front.size() < 3) front.clear();
  if (back.size() < 3) back.clear();
}

bool isPlanarConvex(std::span<const dvec3> polygon, const SplitPlane& plane, double epsilon) {
  const size_t k = polygon.size();
  if (k < 3) return false;
  for (const dvec3& v : polygon)
    if (std::abs(plane.distance(v)) > epsilon) return false;
  for (size_t i = 0; i < k; ++i) {
    const dvec3 e1 = polygon[(i + 1) % k] - polygon[i];
    const dvec3 e2 = polygon[(i + 2) % k] - polygon[(i + 1) % k];
    // A reflex corner turns against the normal (collinear corners are allowed).
    if (glm::dot(glm::cross(e1, e2), plane.n) < -epsilon * (glm::length(e1) + glm::length(e2))) return false;
  }
  return true;
}

}  // namespace hsr::algo

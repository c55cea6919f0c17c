// Convex polygons cut by planes (polygon_split.hpp).
#include "algorithms/polygon_split.hpp"

#include <hsr/scene.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

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

double sceneEpsilon(const Scene& scene) {
  constexpr double kRelEpsilon = 1e-9;
  const Bounds3 b = scene.bounds();
  const double size = b.empty() ? 1.0
                               : std::max(glm::length(b.hi - b.lo),
                                          std::max(glm::length(glm::abs(b.lo)), glm::length(glm::abs(b.hi))));
  return kRelEpsilon * (std::isfinite(size) && size > 0 ? size : 1.0);
}

void forEachConvexPolygon(const Scene& scene, double epsilon, const PolygonVisitor& visit) {
  std::vector<uint32_t> firstTriangle(scene.faceCount() + 1, 0), triangleCount(scene.faceCount(), 0);
  for (size_t t = scene.triangles.size(); t-- > 0;) {
    firstTriangle[scene.triangles[t].face] = uint32_t(t);
    ++triangleCount[scene.triangles[t].face];
  }
  std::vector<dvec3> vertices;
  for (uint32_t f = 0; f < scene.faceCount(); ++f) {
    if (triangleCount[f] == 0) continue;  // no area: finalize() drew nothing of it
    vertices.clear();
    for (uint32_t v : scene.face(f)) vertices.push_back(scene.positions[v]);
    SplitPlane plane;
    if (planeOfPolygon(vertices, plane) && triangleCount[f] + 2 == vertices.size() &&
        isPlanarConvex(vertices, plane, epsilon)) {
      visit(vertices, plane, f, firstTriangle[f]);
      continue;
    }
    for (uint32_t t = firstTriangle[f], e = t + triangleCount[f]; t < e; ++t) {
      const Triangle& tri = scene.triangles[t];
      const dvec3 corners[3] = {scene.positions[tri.v[0]], scene.positions[tri.v[1]], scene.positions[tri.v[2]]};
      if (planeOfPolygon(corners, plane)) visit(corners, plane, f, t);
    }
  }
}

namespace {

// The vertices of `points` (sorted lexicographically) strictly inside edge (u, v), within
// epsilon of it, in order along it.
void verticesOnEdge(const std::vector<dvec3>& points, const dvec3& u, const dvec3& v, double epsilon,
                    std::vector<std::pair<double, dvec3>>& onEdge) {
  onEdge.clear();
  const dvec3 lo = glm::min(u, v) - epsilon, hi = glm::max(u, v) + epsilon, edge = v - u;
  const double length2 = glm::dot(edge, edge);
  if (!(length2 > 0)) return;
  auto it = std::lower_bound(points.begin(), points.end(), dvec3(lo.x, -INFINITY, -INFINITY), lexLess);
  for (; it != points.end() && it->x <= hi.x; ++it) {
    const dvec3& x = *it;
    if (x == u || x == v || x.y < lo.y || x.y > hi.y || x.z < lo.z || x.z > hi.z) continue;
    const double t = glm::dot(x - u, edge) / length2;
    if (t > 0 && t < 1 && glm::length(u + t * edge - x) <= epsilon) onEdge.emplace_back(t, x);
  }
  std::sort(onEdge.begin(), onEdge.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
}

}  // namespace

void closeTJunctions(std::vector<dvec3>& pool, std::span<PolygonRef> polygons, double epsilon) {
  std::vector<uint32_t> byFace(polygons.size());
  for (uint32_t i = 0; i < byFace.size(); ++i) byFace[i] = i;
  std::stable_sort(byFace.begin(), byFace.end(),
                   [&](uint32_t a, uint32_t b) { return polygons[a].face < polygons[b].face; });
  std::vector<dvec3> points, out;
  std::vector<std::pair<double, dvec3>> onEdge;
  for (size_t i = 0; i < byFace.size();) {
    size_t e = i;
    while (e < byFace.size() && polygons[byFace[e]].face == polygons[byFace[i]].face) ++e;
    if (e - i >= 2) {
      points.clear();
      for (size_t k = i; k < e; ++k) {
        const PolygonRef& p = polygons[byFace[k]];
        points.insert(points.end(), pool.begin() + p.first, pool.begin() + p.first + p.count);
      }
      std::sort(points.begin(), points.end(), lexLess);
      points.erase(std::unique(points.begin(), points.end()), points.end());
      for (size_t k = i; k < e; ++k) {
        PolygonRef& p = polygons[byFace[k]];
        out.clear();
        for (uint32_t j = 0; j < p.count; ++j) {
          const dvec3 u = pool[p.first + j], v = pool[p.first + (j + 1) % p.count];
          out.push_back(u);
          verticesOnEdge(points, u, v, epsilon, onEdge);
          for (const auto& [t, x] : onEdge) out.push_back(x);
        }
        if (out.size() == p.count) continue;
        p.first = uint32_t(pool.size());
        p.count = uint32_t(out.size());
        pool.insert(pool.end(), out.begin(), out.end());
      }
    }
    i = e;
  }
}

}  // namespace hsr::algo

// The camera-space BVH and the watertight ray-triangle test (see bvh.hpp). Built once per frame
// on the calling thread; queried concurrently by the raycast rows and by --verify.
#include "algorithms/bvh.hpp"

#include <algorithm>
#include <cmath>

// Watertightness rests on every vertex being sheared by the same rounded operations and on the
// edge functions being exactly antisymmetric: a compiler fusing some a*b - c*d into an fma (as
// GCC does by default when FMA instructions are enabled) would break both. Keep this file free
// of floating-point contractions.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace hsr::algo {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr int kBins = 16;              // SAH candidate planes per axis: kBins - 1
constexpr uint32_t kMaxLeaf = 8;       // a node this small may stay a leaf when SAH says so
constexpr double kTraversalCost = 1;   // one node visit, in units of one ray-triangle test
constexpr int kMaxSahDepth = 64;       // deeper, object-median splits bound the depth by 64 + 32
constexpr int kStackSize = 128;        // > maximum depth, so the traversal stack cannot overflow
// Slab distances and triangle distances are rounded differently (by a few ulps): widen every box
// interval by this relative margin so that a box never loses a hit that its triangle reports.
constexpr double kPad = 1e-12;

double widenUp(double t) { return t + std::abs(t) * kPad; }
double widenDown(double t) { return t - std::abs(t) * kPad; }

// a*b - c*d, the 2D edge function. Swapping (a, b) with (c, d) negates the result exactly
// (the products round the same either way), which is what makes the test watertight: the two
// triangles sharing an edge see the ray on opposite sides of it, or both exactly on it. (In
// double precision, the paper's fallback to a wider type for results of exactly zero only moves
// rays that pass within rounding of an edge from "on both" to "on one" side.)
double edgeFunction(double a, double b, double c, double d) { return a * b - c * d; }

// Half the surface area of a box; 0 for an empty one. (Only ratios matter to the SAH.)
double halfArea(const Bounds3& b) {
  if (b.empty()) return 0;
  const dvec3 e = b.hi - b.lo;
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

}  // namespace

// --- Watertight ray-triangle test ----------------------------------------------------------

WatertightRay::WatertightRay(const dvec3& origin, const dvec3& dir) : org_(origin), dir_(dir) {
  // Forward axis: the largest direction component, so that the shear below stays bounded.
  const dvec3 a = glm::abs(dir);
  kz_ = a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
  kx_ = (kz_ + 1) % 3;
  ky_ = (kx_ + 1) % 3;
  // Looking down the negative axis mirrors the projection: swap x and y to keep the winding.
  if (dir[kz_] < 0) std::swap(kx_, ky_);
  sx_ = dir[kx_] / dir[kz_];
  sy_ = dir[ky_] / dir[kz_];
  sz_ = 1.0 / dir[kz_];
}

double WatertightRay::intersect(const dvec3& v0, const dvec3& v1, const dvec3& v2, Cull cull) const {
  // Vertices relative to the ray origin, sheared so that the ray runs along the kz axis.
  const dvec3 a = v0 - org_, b = v1 - org_, c = v2 - org_;
  const double ax = a[kx_] - sx_ * a[kz_], ay = a[ky_] - sy_ * a[kz_];
  const double bx = b[kx_] - sx_ * b[kz_], by = b[ky_] - sy_ * b[kz_];
  const double cx = c[kx_] - sx_ * c[kz_], cy = c[ky_] - sy_ * c[kz_];

  // Scaled barycentrics: 2D edge functions of the ray (the origin) against each edge.
  const double u = edgeFunction(cx, by, cy, bx);
  const double v = edgeFunction(ax, cy, ay, cx);
  const double w = edgeFunction(bx, ay, by, ax);
  // Inside (or on an edge) when none has a sign opposite to another's.
  if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return kNaN;

  // det is twice the projected area: zero for a triangle seen edge-on or degenerate. Its sign
  // is the facing: det = -dot(n, dir) / |dir[kz]|, so det > 0 for a front face.
  const double det = u + v + w;
  if (det == 0) return kNaN;
  if ((cull == Cull::Back && det < 0) || (cull == Cull::Front && det > 0)) return kNaN;

  // Distance: the barycentric interpolation of the vertices' scaled kz coordinates.
  const double t = (u * a[kz_] + v * b[kz_] + w * c[kz_]) * sz_ / det;
  return t;
}

// --- BVH -----------------------------------------------------------------------------------

CameraSpaceBvh::CameraSpaceBvh(const Scene& scene, const Camera& camera) : scene_(scene), camera_(camera) {
  vertices_.resize(scene.positions.size());
  for (size_t i = 0; i < scene.positions.size(); ++i) vertices_[i] = camera.toCamera(scene.positions[i]);

  std::vector<uint32_t> candidates;
  candidates.reserve(scene.triangles.size());
  for (uint32_t i = 0; i < scene.triangles.size(); ++i) {
    const Triangle& tri = scene.triangles[i];
    const dvec3& p0 = scene.positions[tri.v[0]];
    const dvec3 n = glm::cross(scene.positions[tri.v[1]] - p0, scene.positions[tri.v[2]] - p0);
    bool finite = true;
    for (uint32_t v : tri.v)
      finite = finite && std::isfinite(vertices_[v].x) && std::isfinite(vertices_[v].y) && std::isfinite(vertices_[v].z);
    if (n == dvec3(0.0) || !finite) {
      ++degenerate_;
      continue;
    }
    candidates.push_back(i);
  }
  build(candidates);
}

void CameraSpaceBvh::build(const std::vector<uint32_t>& candidates) {
  const size_t n = candidates.size();
  if (n == 0) return;

  // The build works on references (bounds + triangle index) that it reorders in place, so every
  // pass over a node's triangles reads memory in order.
  struct Ref {
    Bounds3 box;
    uint32_t tri;
    dvec3 centre() const { return box.lo * 0.5 + box.hi * 0.5; }  // cannot overflow
  };
  std::vector<Ref> refs(n);
  for (size_t i = 0; i < n; ++i) {
    refs[i].tri = candidates[i];
    for (uint32_t v : scene_.triangles[candidates[i]].v) refs[i].box.add(vertices_[v]);
  }
  // Bounds of the triangles and of their centres over refs[begin, end).
  struct Extent {
    Bounds3 bounds, centres;
    void add(const Ref& r) {
      bounds.add(r.box);
      centres.add(r.centre());
    }
    void add(const Extent& e) {
      bounds.add(e.bounds);
      centres.add(e.centres);
    }
  };
  auto extentOf = [&](uint32_t begin, uint32_t end) {
    Extent e;
    for (uint32_t i = begin; i < end; ++i) e.add(refs[i]);
    return e;
  };

  nodes_.clear();
  nodes_.reserve(2 * n - 1);
  nodes_.emplace_back();
  // Each task knows its extent: the parent's binning gives it for free.
  struct Task {
    uint32_t node, begin, end;
    int depth;
    Extent extent;
  };
  std::vector<Task> tasks{{0, 0, uint32_t(n), 0, extentOf(0, uint32_t(n))}};
  struct Bin {
    Extent extent;
    uint32_t count = 0;
  };

  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    const auto first = refs.begin() + task.begin, last = refs.begin() + task.end;
    const uint32_t count = task.end - task.begin;
    const Bounds3& bounds = task.extent.bounds;
    const Bounds3& centres = task.extent.centres;
    Node& node = nodes_[task.node];
    node.lo = bounds.lo;
    node.hi = bounds.hi;
    if (count == 1) {
      node.first = task.begin;
      node.count = count;
      continue;
    }

    // Binned SAH along the widest axis of the centres: the cost of a split is left area * left
    // count + right area * right count (relative to this node's area, which the leaf cost
    // count * area shares).
    const dvec3 spread = centres.hi - centres.lo;
    const int axis = spread.x >= spread.y ? (spread.x >= spread.z ? 0 : 2) : (spread.y >= spread.z ? 1 : 2);
    const bool binnable = task.depth < kMaxSahDepth && spread[axis] > 0 && std::isfinite(spread[axis]);
    const double binScale = binnable ? kBins / spread[axis] : 0;
    auto binOf = [&](const Ref& r) {
      const double f = (r.centre()[axis] - centres.lo[axis]) * binScale;
      return f >= 0 ? (f < kBins ? int(f) : kBins - 1) : 0;  // also maps NaN to bin 0
    };
    Bin bins[kBins];
    double bestCost = kInf;
    int bestBin = 0;
    if (binnable) {
      for (auto r = first; r != last; ++r) {
        Bin& bin = bins[binOf(*r)];
        bin.extent.add(*r);
        ++bin.count;
      }
      // Sweep from the right to get the right-side costs, then from the left.
      double rightCost[kBins];
      Bounds3 acc;
      uint32_t accCount = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.add(bins[b].extent.bounds);
        accCount += bins[b].count;
        rightCost[b] = accCount ? halfArea(acc) * accCount : kInf;
      }
      acc = Bounds3();
      accCount = 0;
      for (int b = 1; b < kBins; ++b) {  // split between bins b - 1 and b
        acc.add(bins[b - 1].extent.bounds);
        accCount += bins[b - 1].count;
        if (!accCount) continue;
        const double cost = halfArea(acc) * accCount + rightCost[b];
        if (cost < bestCost) {
          bestCost = cost;
          bestBin = b;
        }
      }
    }

    const bool canSplit = bestCost < kInf;
    const double area = halfArea(bounds);
    const bool sahSplits = canSplit && kTraversalCost * area + bestCost < count * area;
    uint32_t mid;
    Extent left, right;
    if (canSplit && (sahSplits || count > kMaxLeaf)) {
      mid = uint32_t(std::partition(first, last, [&](const Ref& r) { return binOf(r) < bestBin; }) - refs.begin());
      for (int b = 0; b < kBins; ++b) (b < bestBin ? left : right).add(bins[b].extent);
    } else if (count <= kMaxLeaf) {
      node.first = task.begin;
      node.count = count;
      continue;
    } else {
      // No useful SAH split (coincident centres, or too deep): halve by the object median along
      // the widest axis of the centres, which always makes progress.
      mid = task.begin + count / 2;
      std::nth_element(first, refs.begin() + mid, last, [axis](const Ref& l, const Ref& r) {
        const double cl = l.centre()[axis], cr = r.centre()[axis];
        return cl < cr || (cl == cr && l.tri < r.tri);
      });
      left = extentOf(task.begin, mid);
      right = extentOf(mid, task.end);
    }

    const uint32_t child = uint32_t(nodes_.size());
    node.first = child;
    node.count = 0;
    nodes_.emplace_back();  // within the reserved capacity: no reallocation
    nodes_.emplace_back();
    tasks.push_back({child + 1, mid, task.end, task.depth + 1, right});
    tasks.push_back({child, task.begin, mid, task.depth + 1, left});
  }

  order_.resize(n);
  for (size_t i = 0; i < n; ++i) order_[i] = refs[i].tri;
}

inline bool CameraSpaceBvh::boxEntry(const Node& node, const dvec3& origin, const dvec3& invDir, double tMin,
                                     double tMax, double& tEntry) {
  double tNear = -kInf, tFar = kInf;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(invDir[a])) {
      // The ray is parallel to this slab: it is inside for every t or for none (closed box).
      if (origin[a] < node.lo[a] || origin[a] > node.hi[a]) return false;
      continue;
    }
    double t0 = (node.lo[a] - origin[a]) * invDir[a];
    double t1 = (node.hi[a] - origin[a]) * invDir[a];
    if (t0 > t1) std::swap(t0, t1);
    tNear = std::max(tNear, t0);
    tFar = std::min(tFar, t1);
  }
  tEntry = std::max(widenDown(tNear), tMin);
  return tEntry <= std::min(widenUp(tFar), widenUp(tMax));
}

RayHit CameraSpaceBvh::closestHit(const WatertightRay& ray, double tMin, double tMax, Cull cull,
                                  TraceCounters& counters) const {
  RayHit best;
  if (nodes_.empty()) return best;
  const dvec3& origin = ray.origin();
  const dvec3 invDir = 1.0 / ray.dir();
  double limit = tMax;  // hits beyond the best so far cannot win (equal ones still can)

  struct Entry {
    uint32_t node;
    double t;
  };
  Entry stack[kStackSize];
  int size = 0;
  double t0, t1;
  if (!boxEntry(nodes_[0], origin, invDir, tMin, limit, t0)) return best;
  stack[size++] = {0, t0};

  while (size > 0) {
    const Entry entry = stack[--size];
    if (entry.t > widenUp(limit)) continue;  // a nearer hit was found since it was pushed
    const Node& node = nodes_[entry.node];
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const uint32_t tri = order_[i];
        const Triangle& tr = scene_.triangles[tri];
        const double t = ray.intersect(vertices_[tr.v[0]], vertices_[tr.v[1]], vertices_[tr.v[2]], cull);
        ++counters.tests;
        if (t >= tMin && t <= limit && (t < best.t || (t == best.t && int32_t(tri) < best.triangle))) {
          best = {t, int32_t(tri)};
          limit = t;
          ++counters.hits;
        }
      }
      continue;
    }
    // Visit the nearer child first: push it last.
    const bool hitL = boxEntry(nodes_[node.first], origin, invDir, tMin, limit, t0);
    const bool hitR = boxEntry(nodes_[node.first + 1], origin, invDir, tMin, limit, t1);
    if (hitL && hitR) {
      if (t1 < t0) {
        stack[size++] = {node.first, t0};
        stack[size++] = {node.first + 1, t1};
      } else {
        stack[size++] = {node.first + 1, t1};
        stack[size++] = {node.first, t0};
      }
    } else if (hitL) {
      stack[size++] = {node.first, t0};
    } else if (hitR) {
      stack[size++] = {node.first + 1, t1};
    }
  }
  return best;
}

RayHit CameraSpaceBvh::tracePixel(double px, double py, Cull cull, TraceCounters& counters) const {
  dvec3 origin, dir;
  camera_.cameraRay(px, py, origin, dir);
  return closestHit(WatertightRay(origin, dir), camera_.near, camera_.far, cull, counters);
}

void CameraSpaceBvh::allPixelHits(double px, double py, Cull cull, std::vector<RayHit>& hits,
                                  TraceCounters& counters) const {
  if (nodes_.empty()) return;
  dvec3 origin, dir;
  camera_.cameraRay(px, py, origin, dir);
  const WatertightRay ray(origin, dir);
  const dvec3 invDir = 1.0 / ray.dir();
  const double tMin = camera_.near, tMax = camera_.far;
  uint32_t stack[kStackSize];
  int size = 0;
  double t0, t1;
  if (!boxEntry(nodes_[0], origin, invDir, tMin, tMax, t0)) return;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = nodes_[stack[--size]];
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const uint32_t tri = order_[i];
        const Triangle& tr = scene_.triangles[tri];
        const double t = ray.intersect(vertices_[tr.v[0]], vertices_[tr.v[1]], vertices_[tr.v[2]], cull);
        ++counters.tests;
        if (t >= tMin && t <= tMax) {
          hits.push_back({t, int32_t(tri)});
          ++counters.hits;
        }
      }
      continue;
    }
    if (boxEntry(nodes_[node.first], origin, invDir, tMin, tMax, t0)) stack[size++] = node.first;
    if (boxEntry(nodes_[node.first + 1], origin, invDir, tMin, tMax, t1)) stack[size++] = node.first + 1;
  }
}

uint64_t CameraSpaceBvh::memoryBytes() const {
  return vertices_.capacity() * sizeof(dvec3) + nodes_.capacity() * sizeof(Node) +
         order_.capacity() * sizeof(uint32_t);
}

}  // namespace hsr::algo

// Newell, Newell and Sancha's depth sort [KTH report]: the polygons seen from the
// eye are ordered by their farthest depth; the farthest, P, is painted only once no polygon Q that
// overlaps it in depth could be hidden by it, by the classic tests in order of cost (depth extents,
// screen x and y extents, P wholly behind Q's plane, Q wholly in front of P's plane, projections
// disjoint). A Q that must come first is moved to the front of the list; a polygon that would be
// moved twice closes a cycle, and a pair no test separates interpenetrates: then one is split by
// the other's plane (polygon_split.hpp), its pieces keeping the face. The order is computed in
// object space each frame, and the pieces are drawn back to front through the drawing service
// (Overwrite, no depth buffer) as a derived scene. Runs on the caller's thread.
#include <hsr/limits.hpp>
#include <hsr/scene.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/polygon_split.hpp"
#include "core/timer.hpp"

namespace hsr::algo {
namespace {

// Which test decided that P may be painted before Q, and what happened when none did.
struct NewellCounts {
  uint64_t polygons = 0;     // polygons in view entering the sort
  uint64_t clippedNear = 0;  // of those, cut by the plane at half the near distance (perspective)
  uint64_t pairs = 0;        // (P, Q) pairs tested
  uint64_t byDepth = 0, byX = 0, byY = 0, byBehind = 0, byInFront = 0, byDisjoint = 0;
  uint64_t reorders = 0;     // a Q moved to the front of the list
  uint64_t cycles = 0;       // a Q that would have been moved a second time
  uint64_t splits = 0;       // polygons cut in two (by the other's plane, or by a plane through the eye)
  uint64_t eyeSplits = 0;    // of those, cut by a plane through the eye (a cycle neither plane cuts)
};

// Screen distance below which two projections count as touching, not overlapping (rounding of
// the pixel coordinates; far below the 1/128 pixel --verify calls an edge).
constexpr double kTouchPixels = 1e-7;

// Bytes the sorter holds per polygon (the polygon, its world and pixel vertices, list entries),
// an upper estimate from the peak resident size of sorts of random triangles.
constexpr double kBytesPerPolygon = 384;

class DepthSorter {
 public:
  DepthSorter(const Scene& scene, const Camera& camera, uint64_t maxPolygons);
  void addInputs();
  void sort();
  /// The polygons in painting order (back to front), their T-junctions closed (`gained`: those
  /// that gained vertices on their edges).
  void result(std::vector<dvec3>& pool, std::vector<PolygonRef>& polygons, std::vector<uint32_t>& triangles,
              std::vector<bool>& gained);
  double epsilon() const { return epsilon_; }
  NewellCounts counts;

 private:
  struct Poly {
    uint32_t first = 0, count = 0;  // vertices in pool_ (world) and pixel_ (projected), same positions
    uint32_t face = 0, triangle = 0, plane = 0;
    double zmin = 0, zmax = 0;      // eye depth extent
    dvec2 lo{0.0}, hi{0.0};         // projected bounding box, pixels
    bool marked = false;            // moved to the front since the last polygon was painted
  };
  enum class Verdict : uint8_t { Clear, QFirst, Entangled };
  // A polygon of the sorted rest as its scan reads it: farthest depth and screen box (rounded
  // outwards to float: a box test that separates them in float separates them exactly), packed
  // so that the scan over the list runs through memory in order.
  struct RestEntry {
    double zmax;
    float lox, hix, loy, hiy;
    uint32_t id, face;
  };
  RestEntry entryOf(uint32_t id) const;

  std::span<const dvec3> world(const Poly& p) const { return {pool_.data() + p.first, p.count}; }
  std::span<const dvec2> screen(const Poly& p) const { return {pixel_.data() + p.first, p.count}; }
  uint32_t addPlane(const SplitPlane& plane);
  void addPolygon(std::span<const dvec3> vertices, uint32_t plane, uint32_t face, uint32_t triangle, bool input);
  bool wholly(const Poly& x, uint32_t plane, int side) const;
  bool projectionsOverlap(const Poly& p, const Poly& q) const;
  Verdict decide(const Poly& p, const Poly& q);
  void step();
  void act(uint32_t p, uint32_t q, Verdict verdict);
  void takeOut();
  void insertSorted(uint32_t id);
  void split(uint32_t id, const SplitPlane& plane);
  SplitPlane planeThroughEye(const Poly& p) const;
  static bool sortedBefore(const RestEntry& a, const RestEntry& b) {
    return a.zmax != b.zmax ? a.zmax < b.zmax : a.face < b.face;
  }

  const Scene& scene_;
  const Camera& camera_;
  uint64_t maxPolygons_;
  double memoryPolygons_;  // polygons that fit in the memory limit
  double epsilon_;
  dmat4 pixelFromWorld_;
  dvec4 eye_;  // homogeneous: (position, 1), or (direction towards the eye, 0) when orthographic
  std::vector<dvec3> pool_;
  std::vector<dvec2> pixel_;
  std::vector<SplitPlane> planes_;
  std::vector<int8_t> eyeSide_;   // per plane: the side the eye is on (+1, -1; 0: the eye is in it)
  std::vector<Poly> polys_;
  std::vector<RestEntry> rest_;   // not yet painted nor moved: by farthest depth, farthest last
  std::vector<uint32_t> stack_;   // the front of the list: the polygon being tested last
  size_t at_ = 0;                 // where in stack_ (below the top) or rest_ the Q that stopped the scan is
  bool atStack_ = false;
  std::vector<uint32_t> out_;     // painted, back to front
  std::vector<dvec3> front_, back_;
};

DepthSorter::DepthSorter(const Scene& scene, const Camera& camera, uint64_t maxPolygons)
    : scene_(scene), camera_(camera), maxPolygons_(maxPolygons),
      memoryPolygons_(double(memoryLimit()) / kBytesPerPolygon), epsilon_(sceneEpsilon(scene)) {
  pixelFromWorld_ = camera.pixelFromCamera * camera.cameraFromWorld;
  if (camera.orthographic) {
    const dvec3 forward = dvec3(glm::inverse(camera.cameraFromWorld) * dvec4(0, 0, 1, 0));
    eye_ = dvec4(-glm::normalize(forward), 0.0);
  } else {
    eye_ = dvec4(camera.eyeWorld(), 1.0);
  }
}

uint32_t DepthSorter::addPlane(const SplitPlane& plane) {
  const double s = glm::dot(plane.n, dvec3(eye_)) - plane.d * eye_.w;
  const double tolerance = eye_.w != 0 ? epsilon_ : 1e-12;
  planes_.push_back(plane);
  eyeSide_.push_back(int8_t(s > tolerance ? 1 : s < -tolerance ? -1 : 0));
  return uint32_t(planes_.size() - 1);
}

void DepthSorter::addPolygon(std::span<const dvec3> vertices, uint32_t plane, uint32_t face, uint32_t triangle,
                             bool input) {
  Poly p;
  p.first = uint32_t(pool_.size());
  p.count = uint32_t(vertices.size());
  p.face = face;
  p.triangle = triangle;
  p.plane = plane;
  p.zmin = INFINITY;
  p.zmax = -INFINITY;
  p.lo = dvec2(INFINITY);
  p.hi = dvec2(-INFINITY);
  for (const dvec3& v : vertices) {
    const dvec4 h = pixelFromWorld_ * dvec4(v, 1.0);
    const dvec2 xy = dvec2(h.x, h.y) / h.w;
    p.zmin = std::min(p.zmin, h.z);
    p.zmax = std::max(p.zmax, h.z);
    p.lo = glm::min(p.lo, xy);
    p.hi = glm::max(p.hi, xy);
    pixel_.push_back(xy);
  }
  // An input wholly outside the image draws nothing: left out of the sort.
  if (input && (p.hi.x <= 0 || p.hi.y <= 0 || p.lo.x >= camera_.width || p.lo.y >= camera_.height)) {
    pixel_.resize(p.first);
    return;
  }
  pool_.insert(pool_.end(), vertices.begin(), vertices.end());
  if (polys_.size() >= maxPolygons_)
    throw InputError("newell: the depth sort of " + scene_.source + " would hold more than max-fragments=" +
                     std::to_string(maxPolygons_) + " polygons; raise the parameter max-fragments");
  if (double(polys_.size()) >= memoryPolygons_)
    checkMemory(double(polys_.size() + 1) * kBytesPerPolygon,
                "newell: the depth sort of " + scene_.source + " (" + std::to_string(polys_.size() + 1) + " polygons so far)");
  polys_.push_back(p);
  if (input) ++counts.polygons;
}

// The scene's convex polygons; seen in perspective, each cut by the plane at half the near
// distance, keeping the part in front (the front end clips at the near plane itself), so that
// every vertex projects from a positive depth.
void DepthSorter::addInputs() {
  SplitPlane nearCut;
  if (!camera_.orthographic) {
    const dmat4& m = camera_.cameraFromWorld;
    const dvec3 r(m[0][2], m[1][2], m[2][2]);  // camera z = r . x + t
    const double t = m[3][2], length = glm::length(r);
    nearCut.n = r / length;
    nearCut.d = (0.5 * camera_.near - t) / length;
  }
  forEachConvexPolygon(scene_, epsilon_, [&](std::span<const dvec3> vertices, const SplitPlane& plane, uint32_t face,
                                             uint32_t triangle) {
    if (camera_.orthographic) return addPolygon(vertices, addPlane(plane), face, triangle, true);
    switch (classifyPolygon(vertices, nearCut, epsilon_)) {
      case PolygonSide::Front: return addPolygon(vertices, addPlane(plane), face, triangle, true);
      case PolygonSide::Spanning:
        splitPolygon(vertices, nearCut, epsilon_, front_, back_);
        if (front_.empty()) return;
        ++counts.clippedNear;
        return addPolygon(front_, addPlane(plane), face, triangle, true);
      default: return;  // behind the eye, or in the plane at half the near distance: never drawn
    }
  });
}

// Whether every vertex of x is on the eye's side of the plane (side +1) or on the far side
// (side -1), vertices within epsilon of the plane counting for either. A plane through the eye
// (seen edge on) hides nothing: every polygon counts as on either side of it.
bool DepthSorter::wholly(const Poly& x, uint32_t plane, int side) const {
  const SplitPlane& pl = planes_[plane];
  const double s = double(side * eyeSide_[plane]);
  for (const dvec3& v : world(x))
    if (s * pl.distance(v) < -epsilon_) return false;
  return true;
}

// The exact test of two convex projections: they overlap unless an edge direction of one of
// them separates them (separating axis theorem). Touching counts as disjoint.
bool DepthSorter::projectionsOverlap(const Poly& p, const Poly& q) const {
  auto separatedByEdgeOf = [](std::span<const dvec2> a, std::span<const dvec2> b) {
    for (size_t i = 0, k = a.size(); i < k; ++i) {
      const dvec2 e = a[(i + 1) % k] - a[i];
      const dvec2 axis(-e.y, e.x);
      const double length = glm::length(axis);
      if (!(length > 0)) continue;
      double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
      for (const dvec2& v : a) {
        const double s = glm::dot(axis, v);
        amin = std::min(amin, s);
        amax = std::max(amax, s);
      }
      for (const dvec2& v : b) {
        const double s = glm::dot(axis, v);
        bmin = std::min(bmin, s);
        bmax = std::max(bmax, s);
      }
      const double touch = kTouchPixels * length;
      if (amax <= bmin + touch || bmax <= amin + touch) return true;
    }
    return false;
  };
  return !separatedByEdgeOf(screen(p), screen(q)) && !separatedByEdgeOf(screen(q), screen(p));
}

// The classic tests, cheapest first: Clear when P cannot hide any part of Q; otherwise whether Q
// may be painted before P (QFirst) or neither order is right (Entangled: P crosses Q's plane).
DepthSorter::Verdict DepthSorter::decide(const Poly& p, const Poly& q) {
  ++counts.pairs;
  if (p.zmin >= q.zmax) return ++counts.byDepth, Verdict::Clear;
  if (p.hi.x <= q.lo.x || q.hi.x <= p.lo.x) return ++counts.byX, Verdict::Clear;
  if (p.hi.y <= q.lo.y || q.hi.y <= p.lo.y) return ++counts.byY, Verdict::Clear;
  if (wholly(p, q.plane, -1)) return ++counts.byBehind, Verdict::Clear;
  if (wholly(q, p.plane, +1)) return ++counts.byInFront, Verdict::Clear;
  if (!projectionsOverlap(p, q)) return ++counts.byDisjoint, Verdict::Clear;
  if (wholly(q, p.plane, -1) || wholly(p, q.plane, +1)) return Verdict::QFirst;
  return Verdict::Entangled;
}

// The polygon at the front of the list against every other that overlaps it in depth: the
// polygons moved before it, then the sorted rest down to the first entirely nearer than it.
void DepthSorter::step() {
  const uint32_t p = stack_.back();
  const Poly& pp = polys_[p];
  for (size_t i = stack_.size() - 1; i-- > 0;) {
    const Verdict v = decide(pp, polys_[stack_[i]]);
    if (v == Verdict::Clear) continue;
    at_ = i;
    atStack_ = true;
    return act(p, stack_[i], v);
  }
  // The rest: the first three tests on the packed entries, the others on the polygons.
  const float lox = std::nextafter(float(pp.lo.x), -INFINITY), hix = std::nextafter(float(pp.hi.x), INFINITY);
  const float loy = std::nextafter(float(pp.lo.y), -INFINITY), hiy = std::nextafter(float(pp.hi.y), INFINITY);
  const RestEntry* rest = rest_.data();
  uint64_t byX = 0, byY = 0, pairs = 0;
  for (size_t i = rest_.size(); i-- > 0;) {
    const RestEntry& e = rest[i];
    ++pairs;
    if (e.zmax <= pp.zmin) {  // this one and all before it are nearer than P
      ++counts.byDepth;
      break;
    }
    if (hix <= e.lox || e.hix <= lox) {
      ++byX;
      continue;
    }
    if (hiy <= e.loy || e.hiy <= loy) {
      ++byY;
      continue;
    }
    --pairs;  // decide() counts it
    const Verdict v = decide(pp, polys_[e.id]);
    if (v == Verdict::Clear) continue;
    counts.pairs += pairs, counts.byX += byX, counts.byY += byY;
    at_ = i;
    atStack_ = false;
    return act(p, e.id, v);
  }
  counts.pairs += pairs, counts.byX += byX, counts.byY += byY;
  out_.push_back(p);
  stack_.pop_back();
  for (uint32_t s : stack_) polys_[s].marked = false;
}

// Takes the Q that stopped the scan out of the list.
void DepthSorter::takeOut() {
  if (atStack_)
    stack_.erase(stack_.begin() + ptrdiff_t(at_));
  else
    rest_.erase(rest_.begin() + ptrdiff_t(at_));
}

void DepthSorter::act(uint32_t p, uint32_t q, Verdict verdict) {
  if (verdict == Verdict::QFirst && !polys_[q].marked) {
    ++counts.reorders;
    takeOut();
    stack_.push_back(q);
    polys_[q].marked = true;
    return;
  }
  auto spans = [&](uint32_t x, uint32_t plane) {
    return classifyPolygon(world(polys_[x]), planes_[plane], epsilon_) == PolygonSide::Spanning;
  };
  const uint32_t pPlane = polys_[p].plane, qPlane = polys_[q].plane;
  if (verdict == Verdict::QFirst) ++counts.cycles;
  if (verdict == Verdict::QFirst && spans(q, pPlane)) {
    takeOut();
    return split(q, planes_[pPlane]);
  }
  stack_.pop_back();  // P, split by Q's plane or, when it does not cross it, by a plane through the eye
  if (spans(p, qPlane)) return split(p, planes_[qPlane]);
  ++counts.eyeSplits;
  return split(p, planeThroughEye(polys_[p]));
}

DepthSorter::RestEntry DepthSorter::entryOf(uint32_t id) const {
  const Poly& p = polys_[id];
  return {p.zmax,
          std::nextafter(float(p.lo.x), -INFINITY),
          std::nextafter(float(p.hi.x), INFINITY),
          std::nextafter(float(p.lo.y), -INFINITY),
          std::nextafter(float(p.hi.y), INFINITY),
          id,
          p.face};
}

void DepthSorter::insertSorted(uint32_t id) {
  const RestEntry e = entryOf(id);
  rest_.insert(std::upper_bound(rest_.begin(), rest_.end(), e, sortedBefore), e);
}

// Replaces polygon `id` (taken out of the list) by its two pieces, back in the sorted rest.
void DepthSorter::split(uint32_t id, const SplitPlane& plane) {
  ++counts.splits;
  const Poly from = polys_[id];
  splitPolygon(world(from), plane, epsilon_, front_, back_);
  for (const std::vector<dvec3>* piece : {&front_, &back_}) {
    if (piece->empty()) continue;
    addPolygon(*piece, from.plane, from.face, from.triangle, false);
    insertSorted(uint32_t(polys_.size() - 1));
  }
}

// The plane through the eye and the screen line across the middle of P's longer extent: it cuts
// P's projection in two, and the pieces overlap fewer polygons of the cycle.
SplitPlane DepthSorter::planeThroughEye(const Poly& p) const {
  const bool alongX = p.hi.x - p.lo.x >= p.hi.y - p.lo.y;
  const double c = alongX ? 0.5 * (p.lo.x + p.hi.x) : 0.5 * (p.lo.y + p.hi.y);
  const int row = alongX ? 0 : 1;
  auto rowOf = [&](int r) {
    return dvec4(pixelFromWorld_[0][r], pixelFromWorld_[1][r], pixelFromWorld_[2][r], pixelFromWorld_[3][r]);
  };
  const dvec4 h = rowOf(row) - c * rowOf(3);  // h . (x, 1) = 0: pixel coordinate c
  const double length = glm::length(dvec3(h));
  SplitPlane plane;
  plane.n = dvec3(h) / length;
  plane.d = -h.w / length;
  return plane;
}

void DepthSorter::sort() {
  rest_.resize(polys_.size());
  for (uint32_t i = 0; i < rest_.size(); ++i) rest_[i] = entryOf(i);
  std::sort(rest_.begin(), rest_.end(), sortedBefore);
  while (!stack_.empty() || !rest_.empty()) {
    if (stack_.empty()) {
      stack_.push_back(rest_.back().id);
      rest_.pop_back();
    }
    step();
  }
}

void DepthSorter::result(std::vector<dvec3>& pool, std::vector<PolygonRef>& polygons,
                         std::vector<uint32_t>& triangles, std::vector<bool>& gained) {
  polygons.clear();
  triangles.clear();
  for (uint32_t id : out_) {
    polygons.push_back({polys_[id].first, polys_[id].count, polys_[id].face});
    triangles.push_back(polys_[id].triangle);
  }
  pool = pool_;
  closeTJunctions(pool, polygons, epsilon_);
  gained.resize(polygons.size());
  for (size_t i = 0; i < polygons.size(); ++i) gained[i] = polygons[i].count != polys_[out_[i]].count;
}

// The painting order as a scene the drawing service draws, one triangle a face, in painting
// order: a polygon that gained vertices on its edges (closeTJunctions) as a fan around its centre,
// so that such a vertex stays a corner of real triangles; any other as a fan from its first vertex.
struct DerivedPolygons {
  Scene scene;
  DerivedScene derived;
};

void derivePolygons(const Scene& original, const std::vector<dvec3>& pool, const std::vector<PolygonRef>& polygons,
                    const std::vector<uint32_t>& triangles, const std::vector<bool>& gained, DerivedPolygons& out) {
  constexpr size_t kPolygonsPerMesh = 1024;
  Scene& s = out.scene;
  s.source = original.source + " (newell polygons)";
  std::vector<uint32_t> polygonOf;
  for (size_t i = 0; i < polygons.size(); ++i) {
    const PolygonRef& p = polygons[i];
    if (i % kPolygonsPerMesh == 0) s.beginMesh("newell");
    const uint32_t base = uint32_t(s.positions.size());
    s.positions.insert(s.positions.end(), pool.begin() + p.first, pool.begin() + p.first + p.count);
    const Rgba8 color = original.faceColors[p.face];
    if (!gained[i]) {
      for (uint32_t k = 1; k + 1 < p.count; ++k) {
        s.addFace({base, base + k, base + k + 1}, color);
        polygonOf.push_back(uint32_t(i));
      }
      continue;
    }
    dvec3 centre{0.0};
    for (uint32_t k = 0; k < p.count; ++k) centre += pool[p.first + k];
    const uint32_t c = uint32_t(s.positions.size());
    s.positions.push_back(centre / double(p.count));
    for (uint32_t k = 0; k < p.count; ++k) {
      s.addFace({c, base + k, base + (k + 1) % p.count}, color);
      polygonOf.push_back(uint32_t(i));
    }
  }
  s.finalize();
  out.derived.scene = &s;
  out.derived.face.clear();
  out.derived.triangle.clear();
  for (uint32_t i : polygonOf) out.derived.face.push_back(polygons[i].face);
  for (const Triangle& t : s.triangles) out.derived.triangle.push_back(triangles[polygonOf[t.face]]);
}

void setCounts(Stats& st, const NewellCounts& c, uint64_t fragments) {
  st.setDetail("polygons", c.polygons);
  st.setDetail("clipped_near", c.clippedNear);
  st.setDetail("pairs", c.pairs);
  st.setDetail("by_depth", c.byDepth);
  st.setDetail("by_x", c.byX);
  st.setDetail("by_y", c.byY);
  st.setDetail("by_behind", c.byBehind);
  st.setDetail("by_in_front", c.byInFront);
  st.setDetail("by_disjoint", c.byDisjoint);
  st.setDetail("reorders", c.reorders);
  st.setDetail("cycles", c.cycles);
  st.setDetail("splits", c.splits);
  st.setDetail("eye_splits", c.eyeSplits);
  st.setDetail("fragments", fragments);
}

// The sort is view-dependent: each frame sorts (and splits) anew; the object keeps nothing.
class Newell final : public SceneAlgorithm, public PaintsInOrder {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override;
  void paintedPolygons(const Camera& camera, PaintedPolygons& out) override;
};

void Newell::render(const Camera& camera, const RenderOptions& options, Frame& frame) {
  const Scene& scene = scene_;
  const AlgorithmParams& params = params_;
  Timer timer;
  DepthSorter sorter(scene, camera, uint64_t(params.integer("max-fragments")));
  sorter.addInputs();
  sorter.sort();
  std::vector<dvec3> pool;
  std::vector<PolygonRef> polygons;
  std::vector<uint32_t> triangles;
  std::vector<bool> gained;
  sorter.result(pool, polygons, triangles, gained);
  const double sortMs = timer.lap();
  DerivedPolygons derived;
  derivePolygons(scene, pool, polygons, triangles, gained, derived);
  const double deriveMs = timer.lap();

  // The derived scene's faces are in painting order; the front end keeps submission order, and
  // the sort below only restores it should it not.
  const OrderFn inPaintingOrder = [](std::vector<SetupTriangle>& tris) {
    auto byFace = [](const SetupTriangle& a, const SetupTriangle& b) { return a.face < b.face; };
    if (!std::is_sorted(tris.begin(), tris.end(), byFace)) std::stable_sort(tris.begin(), tris.end(), byFace);
  };
  drawScene(scene, camera, options, hasTransparency(scene) ? WriteRule::Blend : WriteRule::Overwrite,
            drawRasterOf(params), inPaintingOrder, buffers_, frame, &derived.derived);
  Stats& st = frame.stats;
  st.addTime("depth_sort", sortMs);
  st.addTime("fragments", deriveMs);
  setCounts(st, sorter.counts, polygons.size());
  st.setDetail("object_ms", sortMs + deriveMs);
  st.addMemory("newell_polygons", pool.capacity() * sizeof(dvec3) + polygons.capacity() * sizeof(PolygonRef));
  st.addMemory("newell_fragments",
               derived.scene.positions.capacity() * sizeof(dvec3) + derived.scene.triangles.capacity() * sizeof(Triangle));
}

void Newell::paintedPolygons(const Camera& camera, PaintedPolygons& out) {
  DepthSorter sorter(scene_, camera, uint64_t(params_.integer("max-fragments")));
  sorter.addInputs();
  sorter.sort();
  std::vector<bool> gained;
  sorter.result(out.vertices, out.polygons, out.triangles, gained);
}

}  // namespace

AlgorithmInfo newellAlgorithm() {
  AlgorithmInfo a;
  a.name = "newell";
  a.summary = "Newell-Newell-Sancha depth sort: polygons by farthest depth, reordered by the classic tests, "
              "split on cycles and interpenetration, painted back to front";
  a.source = "KTH report";
  a.params = {
      {"max-fragments", ParamType::Int, "4000000", {}, 1, 1e9,
       "the most polygons the sort may hold (inputs and pieces): a sort that would make more stops with an error"},
      drawRasterParam("binned", /*kernel=*/true),
  };
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.capability = Capability::PaintsInOrder;
  a.create = factoryOf<Newell>();
  return a;
}

}  // namespace hsr::algo

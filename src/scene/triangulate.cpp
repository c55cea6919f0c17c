// Polygon triangulation (see triangulate.hpp): Newell plane, planarity and convexity tests, fan
// or ear clipping. Produces Scene::triangles for Scene::finalize(); runs on the caller's thread.
#include "scene/triangulate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hsr {
namespace {

// Areas (as |cross product|, i.e. twice the area) at or below this fraction of the squared size
// count as zero: well above double rounding of the cross products, far below any sliver a model
// means to draw. A polygon's size is its bounding box's diagonal; a triangle's (or a turn's) its
// longest side, so that the small, well-shaped pieces of a polygon of many vertices count.
constexpr double kZeroAreaRel = 1e-12;
// A vertex farther than this fraction of the polygon's size from its Newell plane makes the
// polygon non-planar.
constexpr double kPlanarRel = 1e-6;
// Ear clipping's budget, in vertex visits, grid cells scanned and blocker tests: 256 n sqrt(n)
// (long fan triangles of big polygons scan about sqrt(n) cells each), at most 2^34 (some
// seconds). Simple polygons tried stay below it (a comb of 200k vertices, the worst shape found,
// uses 150 n sqrt(n)); a pathological one that runs out is finished without containment tests
// rather than taking hours.
constexpr uint64_t kWorkPerVertex = 256;
constexpr uint64_t kBaseWork = uint64_t(1) << 20;
constexpr uint64_t kMaxWork = uint64_t(1) << 34;
// Once a lap found no ear (the polygon self-intersects), a convex vertex is cut after this many
// fruitless visits instead of another whole lap, so tangled polygons cost linear time.
constexpr uint32_t kTangledMisses = 8;

double cross2(const dvec2& a, const dvec2& b) { return a.x * b.y - a.y * b.x; }
double length2(const dvec3& v) { return glm::dot(v, v); }

/// Why a zero-area polygon has no area, for the note.
const char* degenerateReason(const std::vector<dvec3>& pts) {
  // Fewer than 3 distinct points: every point equals one of the first two distinct ones.
  const dvec3& first = pts[0];
  const dvec3* second = nullptr;
  for (const dvec3& p : pts) {
    if (p == first || (second && p == *second)) continue;
    if (second) return "zero area";
    second = &p;
  }
  return "fewer than 3 distinct vertices";
}

}  // namespace

PolygonReport Triangulator::run(const std::vector<dvec3>& positions, std::span<const uint32_t> poly,
                                uint32_t face, std::vector<Triangle>& out) {
  PolygonReport report;
  const size_t n = poly.size();
  if (n < 3) {
    report.degenerate = true;
    report.degenerateReason = "fewer than 3 vertices";
    return report;
  }

  // Triangles, the common case, take a short path: one cross product.
  if (n == 3) {
    const dvec3& a = positions[poly[0]];
    dvec3 ab = positions[poly[1]] - a, ac = positions[poly[2]] - a, bc = ac - ab;
    double size2 = std::max({length2(ab), length2(ac), length2(bc)});
    if (!(glm::length(glm::cross(ab, ac)) > kZeroAreaRel * size2)) {
      report.degenerate = true;
      local_.assign({a, positions[poly[1]], positions[poly[2]]});
      report.degenerateReason = degenerateReason(local_);
      return report;
    }
    out.push_back({{poly[0], poly[1], poly[2]}, face});
    return report;
  }

  // Vertices relative to the first one: keeps full precision for models far from the origin.
  local_.resize(n);
  const dvec3 origin = positions[poly[0]];
  dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  dvec3 sum(0.0);
  for (size_t i = 0; i < n; ++i) {
    local_[i] = positions[poly[i]] - origin;
    lo = glm::min(lo, local_[i]);
    hi = glm::max(hi, local_[i]);
    sum += local_[i];
  }
  size2_ = length2(hi - lo);

  // Newell normal: the sum of edge cross products, twice the polygon's vector area. Its plane
  // through the centroid is the best-fit plane of a (nearly) planar polygon.
  dvec3 normal(0.0);
  for (size_t i = 0; i < n; ++i) normal += glm::cross(local_[i], local_[(i + 1) % n]);
  const double normalLength = glm::length(normal);
  if (!(normalLength > kZeroAreaRel * size2_)) {
    report.degenerate = true;
    report.degenerateReason = degenerateReason(local_);
    return report;
  }
  const dvec3 unitNormal = normal / normalLength;
  const dvec3 centroid = sum / double(n);
  for (const dvec3& p : local_)
    report.planeDistance = std::max(report.planeDistance, std::abs(glm::dot(unitNormal, p - centroid)));
  report.nonPlanar = report.planeDistance > kPlanarRel * std::sqrt(size2_);
  if (!report.nonPlanar) report.planeDistance = 0;

  // Project onto the coordinate plane the normal is most aligned with, choosing the axis order
  // that makes the projected polygon counter-clockwise (positive signed area).
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(normal[k]) > std::abs(normal[axis])) axis = k;
  int u = (axis + 1) % 3, v = (axis + 2) % 3;
  if (normal[axis] < 0) std::swap(u, v);
  flat_.resize(n);
  for (size_t i = 0; i < n; ++i) flat_[i] = {local_[i][u], local_[i][v]};

  // Convex: no reflex turn, and the edge directions sweep around only once — the signs of the
  // edges' x and y components each change exactly twice around the loop. (The second test
  // rejects self-intersecting polygons like a pentagram, whose turns all have the same sign.)
  // A straight vertex (no turn) would give the fan a zero-area triangle and leave that vertex
  // as a T-junction on a neighbouring triangle's edge, so such polygons are ear clipped too.
  bool convex = true, straight = false;
  int xChanges = 0, yChanges = 0, firstX = 0, firstY = 0, lastX = 0, lastY = 0;
  auto countChange = [](double component, int& first, int& last, int& changes) {
    int sign = (component > 0) - (component < 0);
    if (sign == 0) return;
    if (first == 0) first = sign;
    if (last != 0 && sign != last) ++changes;
    last = sign;
  };
  for (size_t i = 0; i < n && convex; ++i) {
    dvec2 edgeIn = flat_[i] - flat_[(i + n - 1) % n], edgeOut = flat_[(i + 1) % n] - flat_[i];
    double turn = cross2(edgeIn, edgeOut);
    const double tolerance = flatTolerance(uint32_t((i + n - 1) % n), uint32_t(i), uint32_t((i + 1) % n));
    if (turn < -tolerance) convex = false;
    straight = straight || turn <= tolerance;
    countChange(edgeOut.x, firstX, lastX, xChanges);
    countChange(edgeOut.y, firstY, lastY, yChanges);
  }
  xChanges += lastX != firstX;  // the change from the last edge back to the first
  yChanges += lastY != firstY;
  convex = convex && xChanges <= 2 && yChanges <= 2;

  size_t before = out.size();
  if (convex && !straight) {
    fan(poly, face, out);
  } else {
    report.concave = !convex;
    earClip(poly, face, out);
    report.approximate = tangled_ || workLeft_ == 0;
  }
  if (out.size() == before) {  // every piece was a sliver (possible for non-planar input)
    report.degenerate = true;
    report.degenerateReason = "zero area";
    report.concave = report.nonPlanar = false;
  }
  return report;
}

void Triangulator::emit(std::span<const uint32_t> poly, uint32_t a, uint32_t b, uint32_t c,
                        uint32_t face, std::vector<Triangle>& out) const {
  // Zero-area pieces (collinear or repeated vertices) are dropped; the test is in 3D, because
  // that is the triangle every algorithm will draw.
  const dvec3 ab = local_[b] - local_[a], ac = local_[c] - local_[a], bc = ac - ab;
  if (glm::length(glm::cross(ab, ac)) > kZeroAreaRel * std::max({length2(ab), length2(ac), length2(bc)}))
    out.push_back({{poly[a], poly[b], poly[c]}, face});
}

void Triangulator::fan(std::span<const uint32_t> poly, uint32_t face, std::vector<Triangle>& out) {
  for (uint32_t i = 1; i + 1 < poly.size(); ++i) emit(poly, 0, i, i + 1, face, out);
}

double Triangulator::orient(uint32_t a, uint32_t b, uint32_t c) const {
  return cross2(flat_[b] - flat_[a], flat_[c] - flat_[a]);
}

double Triangulator::flatTolerance(uint32_t a, uint32_t b, uint32_t c) const {
  const dvec2 ab = flat_[b] - flat_[a], bc = flat_[c] - flat_[b], ca = flat_[a] - flat_[c];
  return kZeroAreaRel * std::max({glm::dot(ab, ab), glm::dot(bc, bc), glm::dot(ca, ca)});
}

// Ear clipping: repeatedly cut off a convex vertex whose triangle with its two neighbours
// contains no other remaining vertex, not even on its boundary. For a simple polygon only
// vertices that are not strictly convex (reflex or straight: the "blockers") can lie there, so
// only they are tested, through a uniform grid. Straight vertices are kept until they turn
// convex, so none is left as a T-junction. Each polygon of n vertices costs O(n) ear tests in
// practice. A polygon that self-intersects may have no valid ear: then the first convex vertex
// of a fruitless lap is cut anyway (so the loop always ends), and from then on the polygon is
// "tangled" and a convex vertex is cut after a few fruitless visits.
void Triangulator::earClip(std::span<const uint32_t> poly, uint32_t face, std::vector<Triangle>& out) {
  const uint32_t n = uint32_t(poly.size());
  // A strictly convex turn at k (not straight, not reflex).
  auto convexAt = [&](uint32_t k) { return orient(prev_[k], k, next_[k]) > flatTolerance(prev_[k], k, next_[k]); };
  prev_.resize(n);
  next_.resize(n);
  alive_.assign(n, 1);
  blocker_.resize(n);
  lateBlockers_.clear();
  for (uint32_t i = 0; i < n; ++i) {
    prev_[i] = (i + n - 1) % n;
    next_[i] = (i + 1) % n;
  }
  for (uint32_t i = 0; i < n; ++i) blocker_[i] = !convexAt(i);
  buildBlockerGrid();

  auto unlink = [&](uint32_t i) {
    uint32_t a = prev_[i], c = next_[i];
    next_[a] = c;
    prev_[c] = a;
    alive_[i] = 0;
    // Cutting an ear makes its neighbours more convex, but cutting a zero-width spike can
    // make one reflex: such vertices join the ear tests through lateBlockers_.
    for (uint32_t k : {a, c}) {
      bool nowBlocker = !convexAt(k);
      if (nowBlocker && !blocker_[k]) lateBlockers_.push_back(k);
      blocker_[k] = nowBlocker;
    }
  };

  uint32_t remaining = n, i = 0, misses = 0;
  uint32_t firstConvexMiss = n;  // first strictly convex non-ear of the current lap (fallback)
  // After a cut both neighbours may have become ears: the search goes on at the previous vertex
  // and, if that is no ear, jumps to the next one. Checking only one side would leave a strip
  // being "zipped" from its end to be found again only after a walk around the whole polygon.
  uint32_t otherNeighbour = n;
  // Removes vertex v (emitting its triangle when asked) and goes on with its neighbours.
  auto cut = [&](uint32_t v, bool emitTriangle) {
    if (emitTriangle) emit(poly, prev_[v], v, next_[v], face, out);
    i = prev_[v];
    otherNeighbour = next_[v];
    unlink(v);
    --remaining;
    misses = 0;
    firstConvexMiss = n;
  };
  workLeft_ = std::min(kWorkPerVertex * n * (1 + uint64_t(std::sqrt(double(n)))), kMaxWork) + kBaseWork;
  tangled_ = false;
  while (remaining > 3) {
    if (workLeft_ > 0) --workLeft_;
    const uint32_t a = prev_[i], c = next_[i];
    const double o = orient(a, i, c);
    if (std::abs(o) <= flatTolerance(a, i, c)) {
      // A repeated vertex or the tip of a zero-width spike adds no area: drop it. A straight
      // vertex is no ear; it waits until a neighbour's ear makes it convex.
      if (glm::dot(flat_[i] - flat_[a], flat_[c] - flat_[i]) <= 0) {
        cut(i, false);
        continue;
      }
    } else if (o > 0) {
      if (isEar(a, i, c)) {
        cut(i, true);
        continue;
      }
      if (firstConvexMiss == n) firstConvexMiss = i;
    }
    if (++misses > (tangled_ ? kTangledMisses : remaining)) {
      // A whole lap without an ear: the polygon self-intersects. Cut a convex vertex anyway
      // (or, if none is left, the current one) so that the loop makes progress.
      tangled_ = true;
      uint32_t v = firstConvexMiss != n ? firstConvexMiss : i;
      cut(v, convexAt(v));
      continue;
    }
    if (otherNeighbour != n && alive_[otherNeighbour]) {
      i = otherNeighbour;
    } else {
      i = c;
    }
    otherNeighbour = n;
  }
  if (convexAt(i)) emit(poly, prev_[i], i, next_[i], face, out);
}

void Triangulator::buildBlockerGrid() {
  const uint32_t n = uint32_t(flat_.size());
  uint32_t blockerCount = 0;
  dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (uint32_t i = 0; i < n; ++i) {
    blockerCount += blocker_[i];
    lo = glm::min(lo, flat_[i]);
    hi = glm::max(hi, flat_[i]);
  }
  // About one blocker per cell.
  gridSide_ = std::clamp(int(std::ceil(std::sqrt(double(blockerCount)))), 1, 512);
  gridLo_ = lo;
  dvec2 extent = hi - lo;
  gridScale_ = {extent.x > 0 ? gridSide_ / extent.x : 0.0, extent.y > 0 ? gridSide_ / extent.y : 0.0};
  auto cellOf = [&](const dvec2& p) {
    glm::ivec2 c = cell(p);
    return uint32_t(c.y * gridSide_ + c.x);
  };
  const uint32_t cells = uint32_t(gridSide_ * gridSide_);
  cellStart_.assign(cells + 1, 0);
  for (uint32_t i = 0; i < n; ++i)
    if (blocker_[i]) ++cellStart_[cellOf(flat_[i]) + 1];
  for (uint32_t k = 0; k < cells; ++k) cellStart_[k + 1] += cellStart_[k];
  cellItems_.resize(blockerCount);
  cellCursor_.assign(cellStart_.begin(), cellStart_.end() - 1);
  for (uint32_t i = 0; i < n; ++i)
    if (blocker_[i]) cellItems_[cellCursor_[cellOf(flat_[i])]++] = i;
}

glm::ivec2 Triangulator::cell(const dvec2& p) const {
  return {std::clamp(int((p.x - gridLo_.x) * gridScale_.x), 0, gridSide_ - 1),
          std::clamp(int((p.y - gridLo_.y) * gridScale_.y), 0, gridSide_ - 1)};
}

bool Triangulator::blocksEar(uint32_t r, uint32_t a, uint32_t b, uint32_t c) const {
  if (!alive_[r] || !blocker_[r] || r == a || r == b || r == c) return false;
  const dvec2& p = flat_[r];
  // A vertex at the same place as a corner (polygons joined along a bridge) does not block.
  if (p == flat_[a] || p == flat_[b] || p == flat_[c]) return false;
  // Inside or on the boundary of the counter-clockwise triangle a, b, c.
  return cross2(flat_[b] - flat_[a], p - flat_[a]) >= 0 && cross2(flat_[c] - flat_[b], p - flat_[b]) >= 0 &&
         cross2(flat_[a] - flat_[c], p - flat_[c]) >= 0;
}

bool Triangulator::isEar(uint32_t a, uint32_t b, uint32_t c) {
  if (workLeft_ == 0) return true;  // out of budget: every convex vertex counts as an ear
  uint64_t work = 1;
  auto blocked = [&](uint32_t first, uint32_t end, const uint32_t* items) {
    work += end - first;
    for (uint32_t k = first; k < end; ++k)
      if (blocksEar(items[k], a, b, c)) return true;
    return false;
  };
  bool ear = !blocked(0, uint32_t(lateBlockers_.size()), lateBlockers_.data());

  // Scan the blockers of the grid cells the triangle overlaps: row by row, the columns its
  // part within that row's band spans. (Its bounding box would do, but a long thin triangle,
  // common in fans, overlaps few of the cells of its box.) Margins keep the scan conservative
  // against rounding at cell borders.
  const dvec2 p[3] = {flat_[a], flat_[b], flat_[c]};
  const dvec2 lo = glm::min(p[0], glm::min(p[1], p[2])), hi = glm::max(p[0], glm::max(p[1], p[2]));
  const dvec2 margin = (hi - lo) * 1e-9;
  const glm::ivec2 loCell = cell(lo - margin), hiCell = cell(hi + margin);
  for (int y = loCell.y; y <= hiCell.y && ear; ++y) {
    // The band of row y, within the triangle's extent (the outer rows reach beyond the grid).
    const double y0 = std::max(lo.y, gridLo_.y + y / gridScale_.y) - margin.y;
    const double y1 = std::min(hi.y, gridLo_.y + (y + 1) / gridScale_.y) + margin.y;
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
    for (int k = 0; k < 3; ++k) {
      const dvec2 &from = p[k], &to = p[(k + 1) % 3];
      if (from.y >= y0 && from.y <= y1) {
        x0 = std::min(x0, from.x);
        x1 = std::max(x1, from.x);
      }
      for (double band : {y0, y1})
        if ((from.y - band) * (to.y - band) < 0) {
          double x = from.x + (band - from.y) * (to.x - from.x) / (to.y - from.y);
          x0 = std::min(x0, x);
          x1 = std::max(x1, x);
        }
    }
    if (x0 > x1) continue;
    const uint32_t row = uint32_t(y * gridSide_);
    const uint32_t c0 = row + uint32_t(cell({x0 - margin.x, y0}).x), c1 = row + uint32_t(cell({x1 + margin.x, y0}).x);
    ear = !blocked(cellStart_[c0], cellStart_[c1 + 1], cellItems_.data());
    work += c1 - c0;
  }
  workLeft_ -= std::min(work, workLeft_);
  return ear;
}

}  // namespace hsr

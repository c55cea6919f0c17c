// Vector output (include/hsr/svg.hpp): a list-priority algorithm's polygons, back to front,
// clipped in world space to the near and far planes, projected to pixels, clipped to the image
// rectangle, gathered in paint groups (the pieces of a face as one shape), written as SVG polygons
// and paths with the shading of the raster image.
#include <hsr/io.hpp>
#include <hsr/svg.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
#include <queue>
#include <span>
#include <stdexcept>

#include "algorithms/algorithms.hpp"
#include "scene/shading.hpp"

namespace hsr {
namespace {

using algo::PaintedPolygons;
using algo::SplitPlane;

// Appends v to 1/1000 pixel, without trailing zeros ("12.5", "3", "-0.125").
void appendCoordinate(std::string& out, double v) {
  long long m = std::llround(v * 1000.0);
  if (m < 0) {
    out += '-';
    m = -m;
  }
  char digits[24];
  auto [end, ec] = std::to_chars(digits, digits + sizeof digits, m / 1000);
  out.append(digits, end);
  int frac = int(m % 1000);
  if (frac == 0) return;
  char f[4] = {char('0' + frac / 100), char('0' + frac / 10 % 10), char('0' + frac % 10), 0};
  int n = 3;
  while (f[n - 1] == '0') --n;
  out += '.';
  out.append(f, size_t(n));
}

void appendColor(std::string& out, Rgba8 c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  out += buf;
}

void appendOpacity(std::string& out, uint8_t alpha) {
  if (alpha == 255) return;
  char buf[32];
  std::snprintf(buf, sizeof buf, " fill-opacity=\"%.4g\"", alpha / 255.0);
  out += buf;
}

// The planes camera z = near and camera z = far as SplitPlanes whose front is the kept side.
void depthPlanes(const Camera& camera, SplitPlane& nearPlane, SplitPlane& farPlane) {
  const dmat4& m = camera.cameraFromWorld;
  const dvec3 r(m[0][2], m[1][2], m[2][2]);  // camera z = r . x + t
  const double t = m[3][2], length = glm::length(r);
  nearPlane.n = r / length;
  nearPlane.d = (camera.near - t) / length;
  farPlane.n = -r / length;
  farPlane.d = -(camera.far - t) / length;
}

// Sutherland-Hodgman against a half-plane: keeps where n . p >= c. Crossings on a line of constant
// x or y (an image side) get that coordinate exactly.
void clipHalfPlane(std::vector<dvec2>& poly, std::vector<dvec2>& scratch, dvec2 n, double c) {
  scratch.clear();
  for (size_t i = 0, k = poly.size(); i < k; ++i) {
    const dvec2 a = poly[i], b = poly[(i + 1) % k];
    const double da = glm::dot(n, a) - c, db = glm::dot(n, b) - c;
    if (da >= 0) scratch.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
      const double s = da / (da - db);
      dvec2 x = a + s * (b - a);
      if (n.y == 0) x.x = c / n.x;
      if (n.x == 0) x.y = c / n.y;
      scratch.push_back(x);
    }
  }
  poly.swap(scratch);
}

// Twice the signed area (pixels, y down: negative is counter-clockwise as seen, a front face).
double signedArea(std::span<const dvec2> poly) {
  double a = 0;
  for (size_t i = 0, k = poly.size(); i < k; ++i) {
    const dvec2 p = poly[i], q = poly[(i + 1) % k];
    a += p.x * q.y - p.y * q.x;
  }
  return a;
}

// The names of the algorithms that declare Capability::PaintsInOrder, for messages.
std::string paintingAlgorithms() {
  std::string names;
  for (const AlgorithmInfo& a : algorithms())
    if (a.capability == Capability::PaintsInOrder) names += (names.empty() ? "" : ", ") + a.name;
  return names;
}

// The order from the algorithm's object, made for this scene (the capability's interface).
void paintingOrder(const Scene& scene, const Camera& camera, const RenderOptions& options, PaintedPolygons& out) {
  const AlgorithmInfo* algorithm = findAlgorithm(options.algorithm);
  if (!algorithm || algorithm->capability != Capability::PaintsInOrder)
    throw InputError(Setting::Svg, "",
                     options.algorithm + " paints no polygons (vector output needs " + paintingAlgorithms() + ")");
  const std::unique_ptr<Algorithm> object = algorithm->create(scene, resolveParams(*algorithm, options.params));
  auto* painter = dynamic_cast<algo::PaintsInOrder*>(object.get());
  if (!painter) throw std::logic_error(options.algorithm + " declares PaintsInOrder but does not implement it");
  painter->paintedPolygons(camera, out);
}


// The painted polygons as projected and clipped, in the algorithm's order, before grouping.
struct Piece {
  uint32_t first, count, face;
  Rgba8 color;
  dvec2 lo, hi;  // bounding box
  bool convex;
};

// Whether no corner turns against the others; a corner within 1e-6 pixel of straight (a piece's
// vertex on an edge of its face, computed by a split and rounded) turns neither way.
bool isConvex(const dvec2* p, uint32_t n) {
  double sign = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const dvec2 a = p[i], b = p[(i + 1) % n], c = p[(i + 2) % n];
    const double cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
    if (std::abs(cross) <= 1e-6 * glm::length(c - a)) continue;  // b within 1e-6 pixel of the line a c
    if (sign == 0) sign = cross;
    if ((cross > 0) != (sign > 0)) return false;
  }
  return true;
}

// Whether some edge normal of `a` separates the two convex polygons (touching counts as separate:
// a shared edge has no area in common, to within 1e-6 pixel).
bool separatedByEdgeOf(const dvec2* a, uint32_t na, const dvec2* b, uint32_t nb) {
  constexpr double kTouch = 1e-6;
  for (uint32_t i = 0; i < na; ++i) {
    const dvec2 e = a[(i + 1) % na] - a[i];
    const dvec2 normal(-e.y, e.x);  // projections scaled by |e|: so is the tolerance
    double loA = INFINITY, hiA = -INFINITY, loB = INFINITY, hiB = -INFINITY;
    for (uint32_t k = 0; k < na; ++k) {
      const double d = glm::dot(a[k], normal);
      loA = std::min(loA, d);
      hiA = std::max(hiA, d);
    }
    for (uint32_t k = 0; k < nb; ++k) {
      const double d = glm::dot(b[k], normal);
      loB = std::min(loB, d);
      hiB = std::max(hiB, d);
    }
    const double touch = kTouch * glm::length(e);
    if (touch > 0 && (hiA <= loB + touch || hiB <= loA + touch)) return true;
  }
  return false;
}

// Whether two pieces may cover a common point of the image: their boxes overlap and, when both are
// convex, no edge separates them (a non-convex piece is taken to overlap whatever its box meets).
bool mayOverlap(const Piece& a, const Piece& b, const std::vector<dvec2>& points) {
  if (a.hi.x <= b.lo.x || b.hi.x <= a.lo.x || a.hi.y <= b.lo.y || b.hi.y <= a.lo.y) return false;
  if (!a.convex || !b.convex) return true;
  const dvec2 *pa = &points[a.first], *pb = &points[b.first];
  return !separatedByEdgeOf(pa, a.count, pb, b.count) && !separatedByEdgeOf(pb, b.count, pa, a.count);
}

// Appends to `out` convex polygons covering the part of the convex polygon `p` outside the convex
// polygon `x` (one piece per edge of x that cuts p; slivers of no area left out).
void subtractConvex(const std::vector<dvec2>& p, const dvec2* x, uint32_t nx, std::vector<std::vector<dvec2>>& out) {
  const double orientation = signedArea({x, nx}) > 0 ? 1.0 : -1.0;
  std::vector<dvec2> rest = p, outside, scratch;
  for (uint32_t i = 0; i < nx && rest.size() >= 3; ++i) {
    const dvec2 a = x[i], e = x[(i + 1) % nx] - a;
    // An edge of less than 1e-7 pixel (a vertex repeated up to rounding) has no direction to trust.
    if (glm::length(e) < 1e-7) continue;
    const dvec2 n = orientation * dvec2(-e.y, e.x);  // n . q > n . a inside x
    outside = rest;
    clipHalfPlane(outside, scratch, -n, -glm::dot(n, a));
    if (outside.size() >= 3 && std::abs(signedArea(outside)) > 1e-9) out.push_back(outside);
    clipHalfPlane(rest, scratch, n, glm::dot(n, a));
  }
}

// Groups the pieces (in painting order) as ScreenPolygons describes. Two pieces that may overlap
// on the image keep their order; any order that keeps those gives the same picture. Among those
// orders this takes one that paints the pieces of a face together: a topological sort of the
// "paints before" graph that, when it starts a group, prefers a face whose pieces are all ready
// (every piece overlapping them and painted before them already painted), taking all of them
// at once, and otherwise the earliest ready piece with its face's other ready pieces. The graph's
// edges come from a grid of cells over the image listing the pieces whose boxes meet each cell.
void groupPieces(const std::vector<Piece>& pieces, const std::vector<dvec2>& points, size_t faceCount, int width,
                 int height, ScreenPolygons& out) {
  const uint32_t n = uint32_t(pieces.size());
  const int cell = std::clamp(int(2 * std::sqrt(double(width) * height / std::max(1u, n))), 8, 64);
  const int columns = std::max(1, (width + cell - 1) / cell), rows = std::max(1, (height + cell - 1) / cell);
  std::vector<std::vector<uint32_t>> grid(size_t(columns) * size_t(rows));
  std::vector<std::pair<uint32_t, uint32_t>> edges;  // (earlier, later)
  std::vector<uint32_t> seen(n, ~0u);
  for (uint32_t i = 0; i < n; ++i) {
    const Piece& p = pieces[i];
    const int x0 = std::clamp(int(p.lo.x) / cell, 0, columns - 1), x1 = std::clamp(int(p.hi.x) / cell, 0, columns - 1);
    const int y0 = std::clamp(int(p.lo.y) / cell, 0, rows - 1), y1 = std::clamp(int(p.hi.y) / cell, 0, rows - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        std::vector<uint32_t>& here = grid[size_t(y) * size_t(columns) + size_t(x)];
        for (uint32_t j : here)
          if (seen[j] != i) {
            seen[j] = i;
            if (mayOverlap(pieces[j], p, points)) edges.emplace_back(j, i);
          }
        here.push_back(i);
      }
  }
  grid = {};
  // Successors in compressed rows; how many predecessors each piece still waits for.
  std::vector<uint32_t> start(n + 1, 0), successors(edges.size()), waiting(n, 0);
  for (const auto& [a, b] : edges) ++start[a + 1], ++waiting[b];
  for (uint32_t i = 0; i < n; ++i) start[i + 1] += start[i];
  {
    std::vector<uint32_t> at(start.begin(), start.end() - 1);
    for (const auto& [a, b] : edges) successors[at[a]++] = b;
  }
  edges = {};

  // Per face: pieces not yet painted, and the ready ones.
  std::vector<uint32_t> remaining(faceCount, 0);
  std::vector<std::vector<uint32_t>> ready(faceCount);
  for (const Piece& p : pieces) ++remaining[p.face];
  using Queue = std::priority_queue<uint32_t, std::vector<uint32_t>, std::greater<>>;
  Queue readyPieces, completeFaces;  // completeFaces holds a ready piece of each face whose pieces are all ready
  auto becomeReady = [&](uint32_t i) {
    const uint32_t face = pieces[i].face;
    ready[face].push_back(i);
    readyPieces.push(i);
    if (ready[face].size() == remaining[face]) completeFaces.push(ready[face].front());
  };
  for (uint32_t i = 0; i < n; ++i)
    if (waiting[i] == 0) becomeReady(i);

  std::vector<std::vector<uint32_t>> groups;  // in painting order
  std::vector<uint32_t> members;
  std::vector<bool> painted(n, false);
  while (true) {
    uint32_t head = ~0u;
    while (!completeFaces.empty() && head == ~0u) {
      const uint32_t i = completeFaces.top();
      completeFaces.pop();
      if (!painted[i]) head = i;
    }
    while (!readyPieces.empty() && head == ~0u) {
      const uint32_t i = readyPieces.top();
      readyPieces.pop();
      if (!painted[i]) head = i;
    }
    if (head == ~0u) break;
    const uint32_t face = pieces[head].face;
    members.clear();
    members.swap(ready[face]);
    // None of these waits for another (they are all ready), so none overlaps another: one group.
    std::sort(members.begin(), members.end());
    for (uint32_t i : members) painted[i] = true;
    remaining[face] -= uint32_t(members.size());
    groups.push_back(members);
    for (uint32_t i : members)
      for (uint32_t k = start[i]; k < start[i + 1]; ++k)
        if (--waiting[successors[k]] == 0) becomeReady(successors[k]);
  }

  // Repaints: a group of an opaque face that has earlier groups paints again, in its shape, the
  // parts of those groups' pieces within a pixel of its box that are still on top (each piece
  // less the pieces painted over it since), so that where the face's groups meet the later shape
  // holds both sides and shows no seam. A non-convex piece, one under a non-convex piece, or one
  // cut into too many parts is not repainted.
  std::vector<uint32_t> groupOf(n);
  for (uint32_t g = 0; g < groups.size(); ++g)
    for (uint32_t i : groups[g]) groupOf[i] = g;
  std::vector<std::vector<uint32_t>> groupsOf(faceCount);
  for (uint32_t g = 0; g < groups.size(); ++g) groupsOf[pieces[groups[g][0]].face].push_back(g);
  auto boxesMeet = [](dvec2 lo, dvec2 hi, const Piece& b) {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y;
  };
  constexpr size_t kMostParts = 64;  // a piece cut into more is not repainted (bounds the work)
  std::vector<std::vector<std::vector<dvec2>>> repaints(groups.size());
  std::vector<std::vector<dvec2>> parts, cut;
  std::vector<dvec2> scratch;
  for (const std::vector<uint32_t>& of : groupsOf) {
    if (of.size() < 2 || pieces[groups[of[0]][0]].color.a != 255) continue;
    for (size_t k = 1; k < of.size(); ++k) {
      // The parts of earlier pieces within a pixel of this group's box: where a seam could be.
      dvec2 lo = pieces[groups[of[k]][0]].lo, hi = pieces[groups[of[k]][0]].hi;
      for (uint32_t i : groups[of[k]]) {
        lo = glm::min(lo, pieces[i].lo);
        hi = glm::max(hi, pieces[i].hi);
      }
      lo -= 1.0;
      hi += 1.0;
      for (size_t j = 0; j < k; ++j)
        for (uint32_t m : groups[of[j]]) {
          const Piece& piece = pieces[m];
          if (!piece.convex || !boxesMeet(lo, hi, piece) ||
              std::none_of(groups[of[k]].begin(), groups[of[k]].end(),
                           [&](uint32_t i) { return boxesMeet(pieces[i].lo - 1.0, pieces[i].hi + 1.0, piece); }))
            continue;
          parts.assign(1, std::vector<dvec2>(&points[piece.first], &points[piece.first] + piece.count));
          clipHalfPlane(parts[0], scratch, {1, 0}, lo.x);
          clipHalfPlane(parts[0], scratch, {-1, 0}, -hi.x);
          clipHalfPlane(parts[0], scratch, {0, 1}, lo.y);
          clipHalfPlane(parts[0], scratch, {0, -1}, -hi.y);
          if (parts[0].size() < 3) continue;
          bool ok = true;
          for (uint32_t e = start[m]; e < start[m + 1] && ok && !parts.empty(); ++e) {
            const Piece& over = pieces[successors[e]];
            if (groupOf[successors[e]] >= of[k] || !boxesMeet(lo, hi, over)) continue;
            ok = over.convex && parts.size() <= kMostParts;
            cut.clear();
            for (const std::vector<dvec2>& part : parts) subtractConvex(part, &points[over.first], over.count, cut);
            parts.swap(cut);
          }
          if (ok) repaints[of[k]].insert(repaints[of[k]].end(), parts.begin(), parts.end());
        }
    }
  }

  out.groups = uint32_t(groups.size());
  out.polygons.reserve(pieces.size());
  for (uint32_t g = 0; g < groups.size(); ++g) {
    for (uint32_t i : groups[g]) {
      const Piece& p = pieces[i];
      out.polygons.push_back({p.first, p.count, p.face, p.color, g, false});
    }
    const Piece& head = pieces[groups[g][0]];
    for (const std::vector<dvec2>& part : repaints[g]) {
      out.polygons.push_back({uint32_t(out.points.size()), uint32_t(part.size()), head.face, head.color, g, true});
      out.points.insert(out.points.end(), part.begin(), part.end());
    }
  }
}

}  // namespace

bool paintsPolygons(const std::string& algorithm) {
  const AlgorithmInfo* found = findAlgorithm(algorithm);
  return found && found->capability == Capability::PaintsInOrder;
}

ScreenPolygons screenPolygons(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  PaintedPolygons painted;
  paintingOrder(scene, camera, options, painted);
  const TriangleShader shade(scene, camera, options.shading);
  SplitPlane nearPlane, farPlane;
  depthPlanes(camera, nearPlane, farPlane);
  const dmat4 pixelFromWorld = camera.pixelFromCamera * camera.cameraFromWorld;
  const double w = camera.width, h = camera.height;

  ScreenPolygons out;
  std::vector<Piece> pieces;
  std::vector<dvec3> world, front, back;
  std::vector<dvec2> poly, scratch;
  for (size_t i = 0; i < painted.polygons.size(); ++i) {
    const algo::PolygonRef& p = painted.polygons[i];
    world.assign(painted.vertices.begin() + p.first, painted.vertices.begin() + p.first + p.count);
    for (const SplitPlane* plane : {&nearPlane, &farPlane}) {
      if (world.size() < 3) break;
      bool inside = true;
      for (const dvec3& v : world) inside &= plane->distance(v) >= 0;
      if (inside) continue;
      algo::splitPolygon(world, *plane, 0.0, front, back);
      world.swap(front);
    }
    if (world.size() < 3) continue;
    poly.clear();
    for (const dvec3& v : world) {
      const dvec4 q = pixelFromWorld * dvec4(v, 1.0);
      poly.emplace_back(q.x / q.w, q.y / q.w);
    }
    const double area = signedArea(poly);
    if (area == 0 || (options.cull == Cull::Back && area > 0) || (options.cull == Cull::Front && area < 0)) continue;
    clipHalfPlane(poly, scratch, {1, 0}, 0);
    clipHalfPlane(poly, scratch, {-1, 0}, -w);
    clipHalfPlane(poly, scratch, {0, 1}, 0);
    clipHalfPlane(poly, scratch, {0, -1}, -h);
    if (poly.size() < 3 || signedArea(poly) == 0) continue;
    Piece piece{uint32_t(out.points.size()), uint32_t(poly.size()), scene.triangles[painted.triangles[i]].face,
                shade(painted.triangles[i]), poly[0], poly[0], isConvex(poly.data(), uint32_t(poly.size()))};
    for (const dvec2& v : poly) {
      piece.lo = glm::min(piece.lo, v);
      piece.hi = glm::max(piece.hi, v);
    }
    pieces.push_back(piece);
    out.points.insert(out.points.end(), poly.begin(), poly.end());
  }
  groupPieces(pieces, out.points, scene.faceCount(), camera.width, camera.height, out);
  return out;
}

std::string renderSvg(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  const ScreenPolygons painted = screenPolygons(scene, camera, options);
  std::string out;
  out.reserve(96 + painted.polygons.size() * 64);
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"";
  out += std::to_string(camera.width) + "\" height=\"" + std::to_string(camera.height) + "\" viewBox=\"0 0 " +
         std::to_string(camera.width) + " " + std::to_string(camera.height) + "\">\n";

  auto appendPoints = [&](const ScreenPolygon& p) {
    for (uint32_t k = 0; k < p.count; ++k) {
      if (k) out += ' ';
      appendCoordinate(out, painted.points[p.first + k].x);
      out += ',';
      appendCoordinate(out, painted.points[p.first + k].y);
    }
  };
  for (size_t begin = 0, end; begin < painted.polygons.size(); begin = end) {
    end = begin + 1;
    while (end < painted.polygons.size() && painted.polygons[end].group == painted.polygons[begin].group) ++end;
    if (end - begin == 1) {
      out += "<polygon points=\"";
      appendPoints(painted.polygons[begin]);
    } else {
      out += "<path d=\"";
      for (size_t i = begin; i < end; ++i) {
        out += 'M';
        appendPoints(painted.polygons[i]);
        out += 'Z';
      }
    }
    const Rgba8 color = painted.polygons[begin].color;
    out += "\" fill=\"";
    appendColor(out, color);
    out += "\"";
    appendOpacity(out, color.a);
    out += "/>\n";
  }
  out += "</svg>\n";
  return out;
}

void checkSvgPath(const std::string& path) {
  const size_t dot = path.find_last_of('.'), slash = path.find_last_of('/');
  std::string ext = dot == std::string::npos || (slash != std::string::npos && dot < slash) ? "" : path.substr(dot);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".svg")
    throw InputError(path + ": " + (ext.empty() ? "no extension" : "unknown extension '" + ext + "'") +
                     " for vector output (use .svg)");
}

void writeSvg(const Scene& scene, const Camera& camera, const RenderOptions& options, const std::string& path) {
  checkSvgPath(path);
  writeTextFile(renderSvg(scene, camera, options), path);
}

}  // namespace hsr

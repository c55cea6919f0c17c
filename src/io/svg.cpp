// Vector output (include/hsr/svg.hpp): a list-priority algorithm's polygons, back to front,
// clipped in world space to the near and far planes, projected to pixels, clipped to the image
// rectangle, written as SVG polygons with the shading of the raster image.
#include <hsr/io.hpp>
#include <hsr/svg.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>
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

// Sutherland-Hodgman against one side of the image rectangle: keep where sign * (p[axis] - at) >= 0.
void clipSide(std::vector<dvec2>& poly, std::vector<dvec2>& scratch, int axis, double at, double sign) {
  scratch.clear();
  for (size_t i = 0, k = poly.size(); i < k; ++i) {
    const dvec2 a = poly[i], b = poly[(i + 1) % k];
    const double da = sign * (a[axis] - at), db = sign * (b[axis] - at);
    if (da >= 0) scratch.push_back(a);
    if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
      const double s = da / (da - db);
      dvec2 x = a + s * (b - a);
      x[axis] = at;
      scratch.push_back(x);
    }
  }
  poly.swap(scratch);
}

// Twice the signed area (pixels, y down: negative is counter-clockwise as seen, a front face).
double signedArea(const std::vector<dvec2>& poly) {
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

}  // namespace

bool paintsPolygons(const std::string& algorithm) {
  const AlgorithmInfo* found = findAlgorithm(algorithm);
  return found && found->capability == Capability::PaintsInOrder;
}

std::string renderSvg(const Scene& scene, const Camera& camera, const RenderOptions& options) {
  PaintedPolygons painted;
  paintingOrder(scene, camera, options, painted);
  const TriangleShader shade(scene, camera, options.shading);
  SplitPlane nearPlane, farPlane;
  depthPlanes(camera, nearPlane, farPlane);
  const dmat4 pixelFromWorld = camera.pixelFromCamera * camera.cameraFromWorld;
  const double w = camera.width, h = camera.height;

  std::string out;
  out.reserve(96 + painted.polygons.size() * 64);
  out += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"";
  out += std::to_string(camera.width) + "\" height=\"" + std::to_string(camera.height) + "\" viewBox=\"0 0 " +
         std::to_string(camera.width) + " " + std::to_string(camera.height) + "\">\n<rect width=\"" +
         std::to_string(camera.width) + "\" height=\"" + std::to_string(camera.height) + "\" fill=\"";
  appendColor(out, options.background);
  out += "\"";
  appendOpacity(out, options.background.a);
  out += "/>\n";

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
    clipSide(poly, scratch, 0, 0, 1);
    clipSide(poly, scratch, 0, w, -1);
    clipSide(poly, scratch, 1, 0, 1);
    clipSide(poly, scratch, 1, h, -1);
    if (poly.size() < 3 || signedArea(poly) == 0) continue;
    const Rgba8 color = shade(painted.triangles[i]);
    out += "<polygon points=\"";
    for (size_t k = 0; k < poly.size(); ++k) {
      if (k) out += ' ';
      appendCoordinate(out, poly[k].x);
      out += ',';
      appendCoordinate(out, poly[k].y);
    }
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

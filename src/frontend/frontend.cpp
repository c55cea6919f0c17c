// Geometry front end (see frontend.hpp): transform, clip, project, snap, cull, set up.
#include "frontend/frontend.hpp"

#include <cmath>

#include "core/shading.hpp"

namespace hsr {
namespace {

// The six clipping half-spaces, each "value >= 0": d >= near, d <= far, and the guard band.
constexpr int kPlanes = 6;
double planeDistance(const HVertex& v, int plane, const Camera& cam) {
  const double gx0 = -kGuardBandPixels, gx1 = cam.width + kGuardBandPixels;
  const double gy0 = -kGuardBandPixels, gy1 = cam.height + kGuardBandPixels;
  switch (plane) {
    case 0: return v.d - cam.near;
    case 1: return cam.far - v.d;
    case 2: return v.hx - gx0 * v.w;
    case 3: return gx1 * v.w - v.hx;
    case 4: return v.hy - gy0 * v.w;
    default: return gy1 * v.w - v.hy;
  }
}

uint32_t outcode(const HVertex& v, const Camera& cam) {
  uint32_t code = 0;
  for (int p = 0; p < kPlanes; ++p)
    if (planeDistance(v, p, cam) < 0) code |= 1u << p;
  return code;
}

// Sutherland–Hodgman in homogeneous coordinates: every coordinate is linear in the world point,
// so interpolating all four along an edge is exact.
int clipPolygon(HVertex* poly, int count, uint32_t planes, const Camera& cam, HVertex* scratch) {
  for (int p = 0; p < kPlanes && count > 0; ++p) {
    if (!(planes & (1u << p))) continue;
    int outCount = 0;
    for (int i = 0; i < count; ++i) {
      const HVertex& a = poly[i];
      const HVertex& b = poly[(i + 1) % count];
      double da = planeDistance(a, p, cam), db = planeDistance(b, p, cam);
      if (da >= 0) scratch[outCount++] = a;
      if ((da >= 0) != (db >= 0)) {
        double t = da / (da - db);
        scratch[outCount++] = {a.hx + (b.hx - a.hx) * t, a.hy + (b.hy - a.hy) * t, a.d + (b.d - a.d) * t,
                               a.w + (b.w - a.w) * t};
      }
    }
    for (int i = 0; i < outCount; ++i) poly[i] = scratch[i];
    count = outCount;
  }
  return count;
}

// Affine function through three (x, y, value) points.
Plane planeThrough(const double* x, const double* y, const double* v) {
  double x1 = x[1] - x[0], y1 = y[1] - y[0], x2 = x[2] - x[0], y2 = y[2] - y[0];
  double v1 = v[1] - v[0], v2 = v[2] - v[0];
  double det = x1 * y2 - x2 * y1;
  Plane p;
  p.a = (v1 * y2 - v2 * y1) / det;
  p.b = (x1 * v2 - x2 * v1) / det;
  p.c = v[0] - p.a * x[0] - p.b * y[0];
  return p;
}

int64_t floorDiv(int64_t a, int64_t b) {  // b > 0
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

}  // namespace

bool setupTriangle(const HVertex* v, uint32_t triIndex, uint32_t face, Rgba8 color, const Camera& cam,
                   Cull cull, FrontEndOutput& out, SetupTriangle& t) {
  double sx[3], sy[3];
  int64_t X[3], Y[3];
  for (int i = 0; i < 3; ++i) {
    sx[i] = v[i].hx / v[i].w;
    sy[i] = v[i].hy / v[i].w;
    // Round to the nearest 1/256 pixel (|coordinate| < 2^15 pixels after clipping).
    X[i] = int64_t(std::floor(sx[i] * kSubpixelOne + 0.5));
    Y[i] = int64_t(std::floor(sy[i] * kSubpixelOne + 0.5));
  }
  // Twice the signed area on the snapped grid, y down: negative = counter-clockwise as seen.
  int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
  if (area == 0) {
    ++out.degenerate;
    return false;
  }
  t.frontFacing = area < 0;
  if ((cull == Cull::Back && !t.frontFacing) || (cull == Cull::Front && t.frontFacing)) {
    ++out.culledBackface;
    return false;
  }
  int order[3] = {0, 1, 2};
  if (area < 0) std::swap(order[1], order[2]);  // make the edge functions positive inside
  double px[3], py[3], num[3], den[3];
  for (int i = 0; i < 3; ++i) {
    int k = order[i];
    t.x[i] = int32_t(X[k]);
    t.y[i] = int32_t(Y[k]);
    px[i] = double(X[k]) / kSubpixelOne;
    py[i] = double(Y[k]) / kSubpixelOne;
    num[i] = v[k].d / v[k].w;  // d/w and 1/w are affine in screen space
    den[i] = 1.0 / v[k].w;
  }
  // Pixels whose centres (x + 1/2) can lie in the box: x in [ceil(min - 1/2), floor(max - 1/2)].
  const int64_t half = kSubpixelOne / 2;
  int64_t minX = std::min({X[0], X[1], X[2]}), maxX = std::max({X[0], X[1], X[2]});
  int64_t minY = std::min({Y[0], Y[1], Y[2]}), maxY = std::max({Y[0], Y[1], Y[2]});
  t.minX = int(std::max<int64_t>(0, -floorDiv(-(minX - half), kSubpixelOne)));
  t.maxX = int(std::min<int64_t>(cam.width - 1, floorDiv(maxX - half, kSubpixelOne)));
  t.minY = int(std::max<int64_t>(0, -floorDiv(-(minY - half), kSubpixelOne)));
  t.maxY = int(std::min<int64_t>(cam.height - 1, floorDiv(maxY - half, kSubpixelOne)));
  if (t.minX > t.maxX || t.minY > t.maxY) {
    // Off screen (inside the guard band) or too small to contain a pixel centre.
    if (maxX < 0 || maxY < 0 || minX > int64_t(cam.width) * kSubpixelOne || minY > int64_t(cam.height) * kSubpixelOne)
      ++out.culledFrustum;
    return false;
  }
  // Depth planes through the unsnapped positions: snapping decides coverage only, so depth stays
  // exact for the true triangle. Fall back to the snapped positions when the unsnapped triangle is
  // (nearly) degenerate and its plane would be ill-conditioned.
  double ux[3], uy[3];
  for (int i = 0; i < 3; ++i) {
    ux[i] = sx[order[i]];
    uy[i] = sy[order[i]];
  }
  const double exactArea = (ux[1] - ux[0]) * (uy[2] - uy[0]) - (uy[1] - uy[0]) * (ux[2] - ux[0]);
  const bool useExact = exactArea > 0.5 * double(std::abs(area)) / double(kSubpixelOne * kSubpixelOne);
  t.depthNum = useExact ? planeThrough(ux, uy, num) : planeThrough(px, py, num);
  t.depthDen = useExact ? planeThrough(ux, uy, den) : planeThrough(px, py, den);
  t.triangle = triIndex;
  t.face = face;
  t.color = color;
  return true;
}

uint64_t FrontEndOutput::memoryBytes() const { return triangles.capacity() * sizeof(SetupTriangle); }

void runFrontEnd(const Scene& scene, const Camera& cam, const RenderOptions& options, FrontEndOutput& out) {
  out.triangles.clear();
  out.clipped = out.culledBackface = out.culledFrustum = out.degenerate = 0;

  // Object-level view culling: a mesh whose bounding box lies wholly outside one clipping plane
  // is skipped without touching its triangles.
  std::vector<uint8_t> faceVisible(scene.faceCount(), 1);
  for (const MeshRange& mesh : scene.meshes) {
    Bounds3 b;
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f)
      for (uint32_t vi : scene.face(f)) b.add(scene.positions[vi]);
    if (b.empty()) continue;
    uint32_t all = (1u << kPlanes) - 1;
    for (int c = 0; c < 8; ++c) {
      dvec3 p{c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z};
      dvec4 h = cam.toPixelH(p);
      all &= outcode({h.x, h.y, h.z, h.w}, cam);
    }
    if (all) std::fill(faceVisible.begin() + mesh.firstFace, faceVisible.begin() + mesh.firstFace + mesh.faceCount, 0);
  }

  // Transform every vertex once, in double, straight from world to homogeneous pixel coordinates.
  std::vector<HVertex> hv(scene.positions.size());
  const dmat4 pixelFromWorld = cam.pixelFromCamera * cam.cameraFromWorld;
  for (size_t i = 0; i < hv.size(); ++i) {
    dvec4 h = pixelFromWorld * dvec4(scene.positions[i], 1.0);
    hv[i] = {h.x, h.y, h.z, h.w};
  }

  const TriangleShader shade(scene, cam, options.shading);
  out.triangles.reserve(scene.triangles.size());
  HVertex poly[3 + kPlanes], scratch[3 + kPlanes];
  SetupTriangle st;
  for (uint32_t ti = 0; ti < scene.triangles.size(); ++ti) {
    const Triangle& tri = scene.triangles[ti];
    if (!faceVisible[tri.face]) {
      ++out.culledFrustum;
      continue;
    }
    HVertex v[3] = {hv[tri.v[0]], hv[tri.v[1]], hv[tri.v[2]]};
    uint32_t c0 = outcode(v[0], cam), c1 = outcode(v[1], cam), c2 = outcode(v[2], cam);
    if (c0 & c1 & c2) {
      ++out.culledFrustum;
      continue;
    }
    Rgba8 color = shade(ti);
    if ((c0 | c1 | c2) == 0) {
      if (setupTriangle(v, ti, tri.face, color, cam, options.cull, out, st)) out.triangles.push_back(st);
      continue;
    }
    ++out.clipped;
    poly[0] = v[0];
    poly[1] = v[1];
    poly[2] = v[2];
    int n = clipPolygon(poly, 3, c0 | c1 | c2, cam, scratch);
    // The clipped polygon is convex: fan it. Every piece keeps the triangle's and face's index.
    for (int i = 1; i + 1 < n; ++i) {
      HVertex piece[3] = {poly[0], poly[i], poly[i + 1]};
      if (setupTriangle(piece, ti, tri.face, color, cam, options.cull, out, st)) out.triangles.push_back(st);
    }
  }
}

}  // namespace hsr

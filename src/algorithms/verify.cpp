// --verify: compares a frame with the ray-cast reference and classifies every pixel whose face
// differs as ambiguous (explained by sub-pixel snapping or depth precision) or wrong. Called by
// render() when options.verify is set, and by the tests. The classification is documented in
// docs/reference.md.
#include <hsr/verify.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "algorithms/algorithms.hpp"
#include "algorithms/bvh.hpp"
#include "core/parallel.hpp"
#include "frontend/frontend.hpp"

namespace hsr {
namespace {

// Vertices snap to 1/256 pixel, each moving by at most 1/512 in x and in y, so an edge (made of
// convex combinations of its ends) moves by at most sqrt(2)/512 = 1/362 pixel. A ray offset by
// delta in x or in y crosses every edge closer than delta / sqrt(2) to the centre: with delta =
// 1/128, every edge within 1/181 pixel, twice the largest displacement.
constexpr double kEdgeOffset = 1.0 / 128;
constexpr double kSnapStep = 1.0 / 256;       // sub-pixel grid of the rasterizers
constexpr double kPlaneRelTolerance = 1e-9;   // "at the near/far plane", relative to the range

// The depth of one triangle's plane around a pixel centre, mapped by the depth format.
struct MappedDepth {
  bool finite = false;  // false: the plane is seen edge-on there (depth or gradient infinite)
  double eyeDepth = 0;
  double value = 0;     // DepthFormat::map of eyeDepth
  double snapTerm = 0;  // (|dv/dx| + |dv/dy|) / 256: twice what snapping can move the value
};

class PlaneDepths {
 public:
  PlaneDepths(const Scene& scene, const Camera& camera, const DepthFormat& format)
      : scene_(scene), camera_(camera), format_(format) {}

  MappedDepth at(uint32_t triangle, double px, double py) const {
    const Triangle& tri = scene_.triangles[triangle];
    const dvec3 v0 = camera_.toCamera(scene_.positions[tri.v[0]]);
    const dvec3 n = glm::cross(camera_.toCamera(scene_.positions[tri.v[1]]) - v0,
                               camera_.toCamera(scene_.positions[tri.v[2]]) - v0);
    MappedDepth m;
    m.eyeDepth = eyeDepth(n, v0, px, py);
    // Central differences over one snapping step: the mapped value is smooth in the pixel
    // position (affine in it for perspective z), so this is accurate.
    const double h = kSnapStep;
    const double gx = (mapped(n, v0, px + h, py) - mapped(n, v0, px - h, py)) / (2 * h);
    const double gy = (mapped(n, v0, px, py + h) - mapped(n, v0, px, py - h)) / (2 * h);
    m.value = format_.map(m.eyeDepth, camera_.near, camera_.far, camera_.orthographic);
    m.snapTerm = (std::abs(gx) + std::abs(gy)) * kSnapStep;
    m.finite = std::isfinite(m.eyeDepth) && std::isfinite(m.value) && std::isfinite(m.snapTerm);
    return m;
  }

  // Whether the depth lies at the near or far plane, where clipping may go either way.
  bool atClipPlane(double d) const {
    const double tol = kPlaneRelTolerance * std::max(std::abs(camera_.near), std::abs(camera_.far));
    return std::abs(d - camera_.near) <= tol || std::abs(d - camera_.far) <= tol;
  }

 private:
  // Eye depth where the camera ray through (px, py) meets the plane through v0 with normal n.
  double eyeDepth(const dvec3& n, const dvec3& v0, double px, double py) const {
    dvec3 origin, dir;
    camera_.cameraRay(px, py, origin, dir);
    const double t = glm::dot(n, v0 - origin) / glm::dot(n, dir);
    return origin.z + t * dir.z;
  }
  double mapped(const dvec3& n, const dvec3& v0, double px, double py) const {
    return format_.map(eyeDepth(n, v0, px, py), camera_.near, camera_.far, camera_.orthographic);
  }

  const Scene& scene_;
  const Camera& camera_;
  const DepthFormat& format_;
};

// Two mapped depths the format cannot separate once snapping is accounted for.
bool depthsClose(const DepthFormat& format, double v1, double v2, double snapTerms) {
  const double resolution = std::max(format.resolution(v1), format.resolution(v2));
  return std::abs(v1 - v2) <= 2 * resolution + snapTerms;
}

// Depth ambiguity of one differing pixel: the frame's and the reference's triangles (either may
// be -1, background) are closer in depth than the depth format separates.
bool depthAmbiguous(const PlaneDepths& planes, const Scene& scene, const DepthFormat& format, int32_t frameTri,
                    int32_t refTri, double px, double py) {
  auto valid = [&](int32_t t) { return t >= 0 && size_t(t) < scene.triangles.size(); };
  std::optional<MappedDepth> a, b;
  if (valid(frameTri)) a = planes.at(uint32_t(frameTri), px, py);
  if (valid(refTri)) b = planes.at(uint32_t(refTri), px, py);
  if ((a && !a->finite) || (b && !b->finite)) return true;  // seen edge-on: depth ill-conditioned
  if (a && b) return depthsClose(format, a->value, b->value, a->snapTerm + b->snapTerm);
  const std::optional<MappedDepth>& surface = a ? a : b;
  if (!surface) return false;  // the frame shows a face but names no triangle: unexplained
  // Surface against background: at the clear value the strict depth test fails, and at a
  // clipping plane clipping may go either way.
  return depthsClose(format, surface->value, format.clearValue(), surface->snapTerm) ||
         planes.atClipPlane(surface->eyeDepth);
}

// Edge ambiguity: rays kEdgeOffset to each side of the centre. The centre ray sees the
// reference's face and the frame's face differs from it, so "the five rays see more than one
// face, or see the frame's face" is the same as "an offset ray sees a face other than the
// reference's".
// With a CSG tree, the offset rays see the tree's result (csg: CsgRays).
bool edgeAmbiguous(const algo::CameraSpaceBvh& bvh, const algo::CsgRays* csg, const Scene& scene, Cull cull,
                   int32_t refFace, double px, double py) {
  static constexpr double offsets[4][2] = {
      {kEdgeOffset, 0}, {-kEdgeOffset, 0}, {0, kEdgeOffset}, {0, -kEdgeOffset}};
  algo::TraceCounters unused;
  algo::CsgRays::Scratch scratch;
  for (const auto& o : offsets) {
    const algo::RayHit hit = csg ? csg->tracePixel(px + o[0], py + o[1], scratch, unused)
                                 : bvh.tracePixel(px + o[0], py + o[1], cull, unused);
    const int32_t face = hit.found() ? int32_t(scene.triangles[size_t(hit.triangle)].face) : -1;
    if (face != refFace) return true;
  }
  return false;
}

// Edge ambiguity from the triangle itself: the centre lies within kEdgeOffset of an edge of
// triangle `tri` as projected (all its vertices in front of the eye). The offset rays above miss
// the narrow wedge near a sharp vertex, which snapping can move onto or off the centre.
bool nearTriangleEdge(const Scene& scene, const dmat4& pixelFromWorld, int32_t tri, double px, double py) {
  if (tri < 0 || size_t(tri) >= scene.triangles.size()) return false;
  const Triangle& t = scene.triangles[size_t(tri)];
  double sx[3], sy[3];
  for (int k = 0; k < 3; ++k) {
    const HVertex h = transformVertex(scene.positions[t.v[k]], pixelFromWorld);
    if (!(h.w > 0)) return false;
    sx[k] = h.hx / h.w;
    sy[k] = h.hy / h.w;
  }
  // Whether vertices a and b follow each other around the face: a diagonal of its triangulation
  // is shared by two of its own triangles, so crossing it never changes the face seen.
  const auto polygon = scene.face(t.face);
  auto boundary = [&](uint32_t a, uint32_t b) {
    for (size_t i = 0, n = polygon.size(); i < n; ++i) {
      const uint32_t p = polygon[i], q = polygon[(i + 1) % n];
      if ((p == a && q == b) || (p == b && q == a)) return true;
    }
    return false;
  };
  for (int k = 0; k < 3; ++k) {
    const int j = (k + 1) % 3;
    if (!boundary(t.v[k], t.v[j])) continue;
    const double ex = sx[j] - sx[k], ey = sy[j] - sy[k], rx = px - sx[k], ry = py - sy[k];
    const double length2 = ex * ex + ey * ey;
    const double u = length2 > 0 ? std::clamp((rx * ex + ry * ey) / length2, 0.0, 1.0) : 0.0;
    const double dx = rx - u * ex, dy = ry - u * ey;
    if (dx * dx + dy * dy <= kEdgeOffset * kEdgeOffset) return true;
  }
  return false;
}

}  // namespace

VerifyResult verifyAgainstReference(const Scene& scene, const Camera& camera, const RenderOptions& options,
                                    const Frame& frame, const Frame& reference) {
  std::vector<PixelVerdict> verdicts;
  return verifyPixels(scene, camera, options, frame, reference, verdicts);
}

VerifyResult verifyPixels(const Scene& scene, const Camera& camera, const RenderOptions& options, const Frame& frame,
                          const Frame& reference, std::vector<PixelVerdict>& verdicts) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  auto sized = [&](const Frame& f) {
    return f.width == camera.width && f.height == camera.height && f.faceId.size() == pixels &&
           f.triangleId.size() == pixels;
  };
  if (!sized(frame) || !sized(reference))
    throw InputError("verify: the frame (" + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                     ") and the reference (" + std::to_string(reference.width) + "x" +
                     std::to_string(reference.height) + ") must both match the camera's " +
                     std::to_string(camera.width) + "x" + std::to_string(camera.height));

  verdicts.assign(pixels, PixelVerdict::Same);
  std::vector<size_t> differing;
  for (size_t i = 0; i < pixels; ++i)
    if (frame.faceId[i] != reference.faceId[i]) differing.push_back(i);
  VerifyResult result;
  if (differing.empty()) return result;

  const algo::CameraSpaceBvh bvh(scene, camera);
  std::optional<algo::CsgRays> csg;
  if (!scene.csg.empty()) csg.emplace(scene, camera);
  const PlaneDepths planes(scene, camera, options.depthFormat);
  const dmat4 pixelFromWorld = camera.pixelFromCamera * camera.cameraFromWorld;
  std::vector<uint8_t> wrong(differing.size());
  parallelFor(0, differing.size(), resolveThreads(options.threads), [&](size_t k) {
    const size_t i = differing[k];
    const int x = int(i % size_t(camera.width)), y = int(i / size_t(camera.width));
    const double px = x + 0.5, py = y + 0.5;
    const bool ambiguous =
        depthAmbiguous(planes, scene, options.depthFormat, frame.triangleId[i], reference.triangleId[i], px, py) ||
        edgeAmbiguous(bvh, csg ? &*csg : nullptr, scene, options.cull, reference.faceId[i], px, py) ||
        nearTriangleEdge(scene, pixelFromWorld, frame.triangleId[i], px, py) ||
        nearTriangleEdge(scene, pixelFromWorld, reference.triangleId[i], px, py);
    wrong[k] = !ambiguous;
  });

  for (size_t k = 0; k < differing.size(); ++k) {
    verdicts[differing[k]] = wrong[k] ? PixelVerdict::Wrong : PixelVerdict::Ambiguous;
    if (!wrong[k]) {
      ++result.ambiguous_pixels;
      continue;
    }
    ++result.wrong_pixels;
    if (result.first_wrong.size() < 16)
      result.first_wrong.emplace_back(int(differing[k] % size_t(camera.width)),
                                     int(differing[k] / size_t(camera.width)));
  }
  return result;
}

namespace algo {

ColorError colorError(const Frame& frame, const Frame& reference, const std::vector<uint8_t>* nearEdge) {
  ColorError e;
  const size_t n = std::min(frame.color.size(), reference.color.size());
  uint64_t sum[3] = {0, 0, 0};
  const bool ids = frame.faceId.size() == n && reference.faceId.size() == n;
  for (size_t i = 0; i < n; ++i) {
    if (ids && frame.faceId[i] != reference.faceId[i]) continue;  // a wrong or ambiguous pixel: the id check's
    if (nearEdge && (*nearEdge)[i]) {
      ++e.nearEdge;
      continue;
    }
    ++e.pixels;
    const Rgba8 a = frame.color[i], b = reference.color[i];
    const int d[3] = {std::abs(int(a.r) - int(b.r)), std::abs(int(a.g) - int(b.g)), std::abs(int(a.b) - int(b.b))};
    bool beyond = false;
    for (int c = 0; c < 3; ++c) {
      e.max[c] = std::max(e.max[c], d[c]);
      sum[c] += uint64_t(d[c]);
      beyond |= d[c] > 1;
    }
    e.beyondStep += beyond;
  }
  for (int c = 0; c < 3; ++c) e.mean[c] = e.pixels ? double(sum[c]) / double(e.pixels) : 0.0;
  return e;
}

}  // namespace algo

}  // namespace hsr

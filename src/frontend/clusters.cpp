// Clusters and meshes taken whole (clusters.hpp, mesh_bounds.hpp): the per-frame camera views,
// the facing and in-view tests, and the proofs that a culled cluster holds only back faces and
// that a deferred cluster's nearest bound holds for every fragment. Run by the front end's set-up
// workers, one cluster at a time (the mesh bounds' SIMD part is mesh_bounds.cpp).
#include "frontend/clusters.hpp"

#include <algorithm>
#include <cmath>

#include "core/depth_map.hpp"
#include "frontend/mesh_bounds.hpp"
#include "frontend/vertices.hpp"
#include "setup/fixed_point.hpp"

namespace hsr {
ClusterView clusterView(const Camera& cam) {
  ClusterView view;
  const dmat4& P = cam.pixelFromCamera;  // [col][row]: hx = fx X + s Y + cx Z, hy = fy Y + cy Z, d = w = Z
  const bool pinhole = !cam.orthographic && P[0][0] > 0 && P[1][1] > 0 && P[0][1] == 0 && P[3][0] == 0 &&
                       P[3][1] == 0 && P[0][2] == 0 && P[1][2] == 0 && P[2][2] == 1 && P[3][2] == 0 &&
                       P[0][3] == 0 && P[1][3] == 0 && P[2][3] == 1 && P[3][3] == 0;
  const dmat3 R(cam.cameraFromWorld);
  const dmat3 RtR = glm::transpose(R) * R;
  bool rigid = true;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) rigid &= std::abs(RtR[c][r] - (c == r ? 1.0 : 0.0)) <= 1e-6;
  if (!pinhole || !rigid) return view;
  if (!(glm::determinant(R) > 0)) return view;  // (a reflection would turn the winding)
  view.eye = -(glm::transpose(R) * dvec3(cam.cameraFromWorld[3]));
  const double fx = P[0][0], skew = P[1][0], fy = P[1][1];
  view.fx = fx, view.fy = fy, view.skew = skew, view.cx = P[2][0], view.cy = P[2][1];
  view.enabled = std::isfinite(view.gradient()) && std::isfinite(view.eye.x) && std::isfinite(view.eye.y) &&
                 std::isfinite(view.eye.z);
  return view;
}

// Why out.nearest bounds every fragment of a deferred cluster (perspective camera, so a
// fragment's stored value is a monotone function of the plane D = 1/w at its pixel centre, the
// same for every mapping: nearer where D is larger).
// 1. Facing away: every point p of the cluster's bounding sphere (centre C, radius R) is seen
//    from the eye within angle gamma (sin gamma = R / |C - eye|) of the direction of C - eye,
//    which makes angle beta with the cone's axis, and every triangle's unit normal n lies within
//    alpha of the axis; so the angle between n and p - eye is at most beta + gamma + alpha, and
//    when that is below pi/2 with cosine >= kAway: |n . (p - eye)| >= kAway |p - eye|. The plane
//    of each triangle is therefore at distance c >= kAway (|C - eye| - R) from the eye.
// 2. On such a plane 1/z is affine in the pixel position with gradient (n . dr/du, n . dr/dv)
//    / c, r(u, v) = K^-1 (u, v, 1): its L1 norm is at most G = gradient / c (ClusterView).
// 3. A triangle's fragments lie in its snapped triangle, whose corners are within 1/512 pixel
//    of the projected vertices, so in the true triangle's image grown by 1/512 in x and y; there
//    the plane D exceeds its largest vertex value, 1 / (least z of the vertices), by at most
//    G / 512; the bound allows G / 128 (room for the vertices' own rounding). The least z over the
//    bounding box is at a corner (z is affine in the world point); the corners' z are computed
//    less 1e-12 of their terms' magnitudes, far above the rounding of a vertex's z.
// 4. The rasterizer's D differs from that geometric plane by rounding only: well-shaped
//    triangles (Scene::clusters) seen away from edge on are far from slivers, so their planes
//    are well conditioned (a tiny one is planed through its snapped corners, where the values
//    are its vertices' own), and its relative error is ~1e-13 where 1e-6 is allowed; the
//    mapped, stored value gets 1e-9 of itself towards near on top, then clamp and rounding to
//    storage are monotone. Half of kAway stands in for kAway against the rounding of step 1
//    (and a camera rotation orthonormal to 1e-6 only).
// Tiled.DeferredClusterBoundsEveryTriangle (tests/tiled_test.cpp) checks the bound against every
// triangle's own nearest bound.
namespace {

constexpr double kAway = 0.1;  // the facing margin (step 1 above)

// A box whose every corner lies inside the clip volume with room to spare (so no triangle
// inside it is clipped), with the least and greatest eye depth of its corners (conservative) and
// the extremes of their pixel positions. What deferCluster, cullCluster and meshBound share.
struct BoxInView {
  double zMin, zMax;
  double x0, y0, x1, y1;
};
bool boxInView(const Bounds3& box, const Camera& cam, const dmat4& M, BoxInView& out) {
  const double planeScale = 2 * kGuardBandPixels + cam.width + cam.height + 1;
  // The magnitudes of the corners' terms, bounded once for the box: |M[j][r] p_j| at the box's
  // largest |p_j| (at least every corner's own: the margins below only grow).
  const dvec3 most = glm::max(glm::abs(box.lo), glm::abs(box.hi));
  auto terms = [&](int r) {
    return std::abs(M[0][r] * most.x) + std::abs(M[1][r] * most.y) + std::abs(M[2][r] * most.z) + std::abs(M[3][r]);
  };
  const double wTerms = terms(3);
  const double magnitude = terms(0) + terms(1) + terms(2) + wTerms * planeScale + cam.near + cam.far;
  // The corners' homogeneous coordinates as transformVertex computes them, each inside every
  // clipping plane by the margin; their least and greatest eye depth, widened for rounding (one
  // division a corner, not two: the reciprocal's rounding, ~1e-16 relative, is far within the
  // room deferCluster leaves, ~1e-12), and pixel positions. (With SIMD, four or eight corners at
  // a time.)
  double extent[6];
  if (!boxCornersInView(box, M, cam, 1e-9 * magnitude, 1e-12 * wTerms, extent)) return false;
  out.zMin = extent[0], out.zMax = extent[1];
  out.x0 = extent[2], out.y0 = extent[3], out.x1 = extent[4], out.y1 = extent[5];
  return out.zMin > 0;
}

// What deferCluster and cullCluster share: the facing test (step 1) and the box in view.
struct ClusterInView : BoxInView {
  double dist, radius;  // from the eye to the bounding sphere's centre; its radius
};
bool clusterInView(const TriangleCluster& cl, const ClusterView& view, const Camera& cam, const dmat4& M,
                   ClusterInView& out) {
  if (!view.enabled || !cl.usable) return false;
  // 1. Facing away by a margin (cheapest test first: most clusters that fail, fail here).
  const dvec3 centre = cl.bounds.center();
  const double radius = 0.5 * glm::length(cl.bounds.hi - cl.bounds.lo) * (1 + 1e-12);
  const dvec3 toCentre = centre - view.eye;
  const double dist = glm::length(toCentre);
  if (!(dist > 1.001 * radius)) return false;
  const double cosB = glm::dot(cl.axis, toCentre) / dist;
  if (!(cosB > 0)) return false;
  const double sinB = std::sqrt(std::max(0.0, 1 - cosB * cosB));
  const double sinG = radius / dist, cosG = std::sqrt(1 - sinG * sinG);
  const double cosBG = cosB * cosG - sinB * sinG, sinBG = sinB * cosG + cosB * sinG;
  if (!(cosBG >= 0)) return false;  // beta + gamma <= pi/2 (both are in [0, pi/2))
  const double cosA = cl.cosCone, sinA = std::sqrt(std::max(0.0, 1 - cosA * cosA));  // alpha <= pi/3
  if (!(cosBG * cosA - sinBG * sinA >= kAway)) return false;
  out.dist = dist, out.radius = radius;
  return boxInView(cl.bounds, cam, M, out);
}

// Pixels whose centres a triangle inside a box in view may cover: centres x + 1/2 within 1/256
// of a pixel of [x0, x1] (snapping moves a vertex by 1/512; the rest is room for rounding, ~1e-12
// relative). (Rather than a whole pixel of margin each side: fewer triangles set up late.) False
// when no centre of the image is in it.
bool pixelBoxOf(const BoxInView& in, const Camera& cam, int16_t& minX, int16_t& minY, int16_t& maxX, int16_t& maxY) {
  constexpr double kRoom = 1.0 / 256;
  const double bx0 = std::max(0.0, std::ceil(in.x0 - 0.5 - kRoom));
  const double bx1 = std::min(double(cam.width - 1), std::floor(in.x1 - 0.5 + kRoom));
  const double by0 = std::max(0.0, std::ceil(in.y0 - 0.5 - kRoom));
  const double by1 = std::min(double(cam.height - 1), std::floor(in.y1 - 0.5 + kRoom));
  if (!(bx0 <= bx1 && by0 <= by1)) return false;
  minX = int16_t(bx0), maxX = int16_t(bx1), minY = int16_t(by0), maxY = int16_t(by1);
  return true;
}

}  // namespace

double storedNearest(double d, const DepthSetup& depth) {
  double out = 0;
  visitDepthFormat(depth.format, [&]<DepthStorage S, DepthMapping Map>() {
    double v = mapDepth<Map>(d, depth.near, depth.far, false);
    v = depth.format.greaterWins() ? v + std::abs(v) * 1e-9 : v - std::abs(v) * 1e-9;
    out = double(quantizeDepth<S>(std::clamp(v, 0.0, 1.0)));
  });
  return out;
}

bool deferCluster(const TriangleCluster& cl, const ClusterView& view, const Camera& cam, const dmat4& M,
                  const DepthSetup& depth, DeferredCluster& out) {
  ClusterInView in;
  if (depth.orthographic || !clusterInView(cl, view, cam, M, in)) return false;
  if (!pixelBoxOf(in, cam, out.minX, out.minY, out.maxX, out.maxY)) return false;
  // 2.-4. The largest D, as an eye depth, mapped and stored.
  const double gradient = view.gradient() / (0.5 * kAway * (in.dist - in.radius));
  const double largestD = (1 / in.zMin) * (1 + 1e-6) + 2 * gradient / double(kSubpixelOne);
  out.nearest = storedNearest((1 / largestD) * (1 - 1e-12), depth);
  return std::isfinite(out.nearest);
}

// Why every triangle of a cluster cullCluster accepts has a snapped signed area > 0, the back
// faces of setupTriangle: on a plane n . X = c (unit n = (v1 - v0) x (v2 - v0) normalized, camera
// space) the image's area element is fx fy c / z^3 times the triangle's (skew does not change
// the determinant), so its exact image has signed area of the sign of c — positive when it faces
// away — and at least fx fy c minArea / zMax^3, with c >= kAway/2 (dist - radius) (step 1). A
// triangle edge of length L at depth >= zMin moves u by at most (fx + |s| + |u - cx|) L / zMin and
// v by (fy + |v - cy|) L / zMin (du = (fx dX + s dY - (u - cx) dZ) / z), so its image's edges have
// L1 lengths at most E = (fx + |s| + fy + U + V) maxEdge / zMin. Snapping (and the projection's
// rounding) moves each corner by at most delta = 1/512 pixel in x and y, which changes twice the
// signed area by at most 4 delta E + 8 delta^2: less than twice the area, so the sign holds.
bool cullCluster(const TriangleCluster& cl, const ClusterView& view, const Camera& cam, const dmat4& M) {
  ClusterInView in;
  if (!clusterInView(cl, view, cam, M, in)) return false;
  const double c = 0.5 * kAway * (in.dist - in.radius);
  const double area = view.fx * view.fy * c * cl.minArea * (1 - 1e-9) / (in.zMax * in.zMax * in.zMax);
  const double U = std::max(std::abs(in.x0 - view.cx), std::abs(in.x1 - view.cx));
  const double V = std::max(std::abs(in.y0 - view.cy), std::abs(in.y1 - view.cy));
  const double edge = (view.fx + std::abs(view.skew) + view.fy + U + V) * cl.maxEdge * (1 + 1e-9) / in.zMin;
  const double delta = (1.0 / (2 * kSubpixelOne)) * (1 + 1e-6);
  return 2 * area > 4 * delta * edge + 8 * delta * delta;
}

MeshView meshView(const Camera& cam, const DepthSetup& depth) {
  MeshView mv;
  const ClusterView view = clusterView(cam);
  mv.enabled = view.enabled && !depth.orthographic;
  mv.eye = view.eye;
  mv.eyeLength = glm::length(view.eye);
  mv.gradient = view.gradient();
  mv.pixelFromWorld = cam.pixelFromCamera * cam.cameraFromWorld;
  const dmat4& M = mv.pixelFromWorld;
  for (int j = 0; j < 4; ++j) {
    mv.positive[j] = glm::max(M[j], dvec4(0.0));
    mv.negative[j] = glm::min(M[j], dvec4(0.0));
    mv.magnitude[j] = glm::abs(M[j]);
  }
  mv.camera = &cam;
  mv.depth = depth;
  return mv;
}

}  // namespace hsr

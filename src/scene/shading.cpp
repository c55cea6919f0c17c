// Flat shading per triangle (see shading.hpp).
#include "scene/shading.hpp"

#include <algorithm>
#include <cmath>

namespace hsr {

Rgba8 faceIdColor(uint32_t face) {
  // docs/conventions.md: face index + 1 as a 24-bit integer, R the high byte, B the low byte.
  const uint32_t v = face + 1;
  return Rgba8{uint8_t(v >> 16), uint8_t(v >> 8), uint8_t(v), 255};
}

TriangleShader::TriangleShader(const Scene& scene, const Camera& camera, Shading shading)
    : scene_(scene),
      shading_(shading),
      orthographic_(camera.orthographic),
      ownFaces_(scene.triangles.size() == scene.faceCount() && scene.polygonIndices.size() == 3 * scene.faceCount()) {
  dmat4 worldFromCamera = glm::inverse(camera.cameraFromWorld);
  eye_ = dvec3(worldFromCamera * dvec4(0, 0, 0, 1));
  forward_ = dvec3(worldFromCamera * dvec4(0, 0, 1, 0));
  if (ownFaces_ || orthographic_) return;
  for (size_t f = 0; f < scene.faceCount(); ++f) {
    const auto polygon = scene.face(f);
    if (polygon.size() <= kSmallFace) continue;
    dvec3 sum{0.0};
    for (uint32_t v : polygon) sum += scene.positions[v] - scene.positions[polygon[0]];
    largeFaces_.push_back({uint32_t(f), sum});
  }
}

// The ray from the eye to the triangle's face's centroid, scaled by the face's vertex count (the
// cosine ignores the scale, and this way it needs no division).
dvec3 TriangleShader::centroidRay(const Triangle& tri) const {
  const auto polygon = scene_.face(tri.face);
  if (polygon.size() > kSmallFace) {
    auto it = std::lower_bound(largeFaces_.begin(), largeFaces_.end(), tri.face,
                               [](const LargeFace& l, uint32_t face) { return l.face < face; });
    return (scene_.positions[polygon[0]] - eye_) * double(polygon.size()) + it->sum;
  }
  const dvec3& a = scene_.positions[tri.v[0]];
  dvec3 sum{0.0};
  for (uint32_t v : polygon) sum += scene_.positions[v] - a;
  return (a - eye_) * double(polygon.size()) + sum;
}

Rgba8 TriangleShader::operator()(uint32_t t) const {
  const Triangle& tri = scene_.triangles[t];
  if (shading_ == Shading::FaceId) return faceIdColor(tri.face);
  const Rgba8 base = scene_.faceColors[tri.face];
  if (shading_ == Shading::Flat) return base;
  return lambertColor(base, lambertFactor(t));
}

double TriangleShader::lambertFactor(uint32_t t) const {
  const Triangle& tri = scene_.triangles[t];
  // Headlight: light from the eye; two-sided, so |cos| of the angle between the face normal and
  // the view ray to the face's centroid. Per face, so a polygon's triangles shade alike.
  const dvec3& a = scene_.positions[tri.v[0]];
  const dvec3& b = scene_.positions[tri.v[1]];
  const dvec3& c = scene_.positions[tri.v[2]];
  dvec3 n = glm::cross(b - a, c - a);
  const dvec3 view = orthographic_ ? forward_ : centroidRay(tri);
  const double ln2 = glm::dot(n, n) * glm::dot(view, view);
  const double cosine = ln2 > 0 ? std::abs(glm::dot(n, view)) / std::sqrt(ln2) : 1.0;
  return 0.25 + 0.75 * cosine;
}

Rgba8 shadeTriangle(const Scene& scene, const Camera& camera, const RenderOptions& options, uint32_t t) {
  return TriangleShader(scene, camera, options.shading)(t);
}

}  // namespace hsr

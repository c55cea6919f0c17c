// Flat shading per triangle (see shading.hpp).
#include "core/shading.hpp"

#include <cmath>

namespace hsr {

Rgba8 faceIdColor(uint32_t face) {
  // A multiplicative hash spreads neighbouring ids over the colour cube; keep it bright.
  uint32_t h = (face + 1) * 2654435761u;
  h ^= h >> 15;
  return Rgba8{uint8_t(64 + (h & 0xBF)), uint8_t(64 + ((h >> 8) & 0xBF)), uint8_t(64 + ((h >> 16) & 0xBF)), 255};
}

Rgba8 shadeTriangle(const Scene& scene, const Camera& camera, const RenderOptions& options, uint32_t t) {
  const Triangle& tri = scene.triangles[t];
  if (options.shading == Shading::FaceId) return faceIdColor(tri.face);
  Rgba8 base = scene.faceColors[tri.face];
  if (options.shading == Shading::Flat) return base;
  // Headlight: light from the eye; two-sided, so |cos| of the angle between normal and view ray.
  dvec3 a = camera.toCamera(scene.positions[tri.v[0]]);
  dvec3 b = camera.toCamera(scene.positions[tri.v[1]]);
  dvec3 c = camera.toCamera(scene.positions[tri.v[2]]);
  dvec3 n = glm::cross(b - a, c - a);
  dvec3 view = camera.orthographic ? dvec3(0, 0, 1) : (a + b + c) / 3.0;
  double ln = glm::length(n) * glm::length(view);
  double cosine = ln > 0 ? std::abs(glm::dot(n, view)) / ln : 1.0;
  double k = 0.25 + 0.75 * cosine;
  auto scale = [k](uint8_t v) { return uint8_t(std::lround(v * k)); };
  return Rgba8{scale(base.r), scale(base.g), scale(base.b), base.a};
}

}  // namespace hsr

// Per-triangle flat shading shared by all algorithms, so every algorithm's colour image agrees:
// face colour, a two-sided headlight Lambert shade, or the face id as a colour.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <vector>

namespace hsr {

/// The colour Shading::FaceId gives face `face`: face + 1 as 24-bit RGB (R the high byte, B the low
/// byte; 0,0,0 is left for the background), as the face-id PNG; ids from 2^24 - 1 on wrap around.
Rgba8 faceIdColor(uint32_t face);

/// `base` scaled by the Lambert factor k (0.25 + 0.75 |cos|), alpha kept.
inline Rgba8 lambertColor(Rgba8 base, double k) {
  auto scale = [k](uint8_t v) { return uint8_t(v * k + 0.5); };
  return Rgba8{scale(base.r), scale(base.g), scale(base.b), base.a};
}

/// Shades scene triangles for one camera; construct once per frame.
class TriangleShader {
 public:
  TriangleShader(const Scene& scene, const Camera& camera, Shading shading);
  Rgba8 operator()(uint32_t triangleIndex) const;
  /// out[i] = (*this)(triangles[i]) for i < count, bit for bit; Lambert shades with SIMD
  /// (scene/shading_batch.cpp).
  void shadeMany(const uint32_t* triangles, size_t count, Rgba8* out) const;
  /// Shading::Lambert's factor for a triangle: 0.25 + 0.75 |cos|, the cosine between its face's
  /// normal and the view ray to the face's centroid (two-sided headlight).
  double lambertFactor(uint32_t triangleIndex) const;
  /// factor[i] = lambertFactor(triangles[i]) for i < count, bit for bit, with SIMD for the
  /// triangles that are their own face (the polygon's three vertices in the triangle's order).
  void lambertFactors(const uint32_t* triangles, size_t count, double* factor) const;

 private:
  const Scene& scene_;
  Shading shading_;
  bool orthographic_;
  dvec3 eye_;      // world position of the eye (perspective)
  dvec3 forward_;  // world view direction (orthographic)
  // Whether every triangle is its own face (three vertices, in the triangle's order: a face of
  // three vertices is one triangle, so when there are as many triangles as faces and three
  // indices a face, each face made its triangle).
  bool ownFaces_;
  // For each face of more than kSmallFace vertices, in face order: the sum of (p - p0) over its
  // vertices p (p0 its first), so the view ray to its centroid costs O(1) per triangle rather
  // than O(polygon). Empty when every face is a triangle or the camera is orthographic.
  static constexpr size_t kSmallFace = 16;
  struct LargeFace {
    uint32_t face;
    dvec3 sum;
  };
  std::vector<LargeFace> largeFaces_;
  dvec3 centroidRay(const Triangle& tri) const;
  bool ownFace(const Triangle& tri) const {
    const auto polygon = scene_.face(tri.face);
    return polygon.size() == 3 && polygon[0] == tri.v[0] && polygon[1] == tri.v[1] && polygon[2] == tri.v[2];
  }
};

/// Colour of one triangle (convenience; builds a TriangleShader, so prefer that in loops).
Rgba8 shadeTriangle(const Scene& scene, const Camera& camera, const RenderOptions& options, uint32_t triangleIndex);

}  // namespace hsr

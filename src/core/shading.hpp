// Per-triangle flat shading shared by all algorithms, so every algorithm's colour image agrees:
// face colour, a two-sided headlight Lambert shade, or a distinct colour per face id.
#pragma once
#include <hsr/render.hpp>

namespace hsr {

/// A distinct, deterministic colour for face `face` (used by Shading::FaceId).
Rgba8 faceIdColor(uint32_t face);

/// Shades scene triangles for one camera; construct once per frame.
class TriangleShader {
 public:
  TriangleShader(const Scene& scene, const Camera& camera, Shading shading);
  Rgba8 operator()(uint32_t triangleIndex) const;

 private:
  const Scene& scene_;
  Shading shading_;
  bool orthographic_;
  dvec3 eye_;      // world position of the eye (perspective)
  dvec3 forward_;  // world view direction (orthographic)
};

/// Colour of one triangle (convenience; builds a TriangleShader, so prefer that in loops).
Rgba8 shadeTriangle(const Scene& scene, const Camera& camera, const RenderOptions& options, uint32_t triangleIndex);

}  // namespace hsr

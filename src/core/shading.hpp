// Per-triangle flat shading shared by all algorithms, so every algorithm's colour image agrees:
// face colour, a two-sided headlight Lambert shade, or a distinct colour per face id.
#pragma once
#include <hsr/render.hpp>

namespace hsr {

/// Colour of scene triangle `triangleIndex` under options.shading.
Rgba8 shadeTriangle(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    uint32_t triangleIndex);
/// A distinct, deterministic colour for face `face` (used by Shading::FaceId).
Rgba8 faceIdColor(uint32_t face);

}  // namespace hsr

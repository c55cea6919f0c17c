// Pixel-by-pixel verification against the exact reference: what --verify counts, kept per pixel
// for error maps (hsr compare's report).
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>
#include <vector>

namespace hsr {

/// Result of comparing a frame with the exact reference.
struct VerifyResult {
  uint64_t wrong_pixels = 0;      // face id differs and the difference is not explained below
  uint64_t ambiguous_pixels = 0;  // face id differs, but the two surfaces are closer in depth
                                  // than the format separates there, or the pixel centre lies
                                  // within 1/128 pixel of an edge of either triangle
  std::vector<std::pair<int, int>> first_wrong;  // up to 16 wrong pixels (x, y), for messages
};
/// Compares `frame` (rendered with `options`) against `reference` (the raycast of the same
/// scene and camera) and classifies each differing pixel.
VerifyResult verifyAgainstReference(const Scene& scene, const Camera& camera,
                                    const RenderOptions& options, const Frame& frame,
                                    const Frame& reference);

/// How a pixel of a frame compares with the reference's.
enum class PixelVerdict : uint8_t {
  Same,       // the same face id
  Ambiguous,  // a different face, but the two are closer in depth than the format separates, or
              // the pixel centre is within 1/128 pixel of a triangle edge (VerifyResult)
  Wrong,      // a different face, and nothing explains it
};

/// verifyAgainstReference, also giving each pixel's verdict (row 0 = top) in `verdicts`.
VerifyResult verifyPixels(const Scene& scene, const Camera& camera, const RenderOptions& options, const Frame& frame,
                          const Frame& reference, std::vector<PixelVerdict>& verdicts);

}  // namespace hsr

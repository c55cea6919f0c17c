// Pixel-by-pixel verification against the exact reference: what --verify counts, kept per pixel
// for error maps (hsr compare's report).
#pragma once
#include <hsr/render.hpp>

#include <cstdint>
#include <vector>

namespace hsr {

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

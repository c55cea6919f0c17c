// Face-id agreement of two visibility buffers of the same scene and camera (hsr's and a peer
// renderer's): covered pixels, equal pixels, and mismatches away from face boundaries.
// Consumed by hsr_peer_llvmpipe (bench/peer/llvmpipe_peer.cpp); tested by tests/peer_test.cpp.
// Pure, header-only, no GL.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

namespace hsr::peer {

struct IdAgreement {
  uint64_t covered = 0;                           // pixels where either image shows a face
  uint64_t equal = 0;                             // covered pixels with the same face id in both images
  uint64_t edgeMismatches = 0;                    // differing pixels on a face boundary: fill-rule and snapping
                                                  // differences, expected between two rasterizers
  uint64_t nonEdgeMismatches = 0;                 // differing pixels inside faces: a convention or precision bug
  std::vector<std::pair<int, int>> firstNonEdge;  // up to kMaxListed of them (x, y), for messages

  static constexpr size_t kMaxListed = 16;
  double equalFraction() const { return covered ? double(equal) / double(covered) : 1.0; }
};

/// A pixel is an edge pixel when one of its 4-neighbours inside the image has a different id
/// from the pixel's own in `a` or in `b` (face ids, width x height, row 0 at the top): there two
/// rasterizers may legitimately disagree (snapping, fill rule, clipping), so only mismatches
/// elsewhere point at a bug. A wrong region therefore counts only its interior.
inline bool isEdgePixel(int width, int height, std::span<const int32_t> a, std::span<const int32_t> b, int x, int y) {
  const size_t w = size_t(width), i = size_t(y) * w + size_t(x);
  auto differsFromNeighbour = [&](std::span<const int32_t> ids) {
    return (x > 0 && ids[i - 1] != ids[i]) || (x + 1 < width && ids[i + 1] != ids[i]) ||
           (y > 0 && ids[i - w] != ids[i]) || (y + 1 < height && ids[i + w] != ids[i]);
  };
  return differsFromNeighbour(a) || differsFromNeighbour(b);
}

/// Compares face ids `a` and `b` (width x height, row 0 at the top, -1 = background).
inline IdAgreement compareFaceIds(int width, int height, std::span<const int32_t> a, std::span<const int32_t> b) {
  if (width < 0 || height < 0 || a.size() != size_t(width) * size_t(height) || b.size() != a.size())
    throw std::invalid_argument("compareFaceIds: buffers do not match the image size");
  IdAgreement result;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * size_t(width) + size_t(x);
      if (a[i] < 0 && b[i] < 0) continue;
      ++result.covered;
      if (a[i] == b[i]) {
        ++result.equal;
      } else if (isEdgePixel(width, height, a, b, x, y)) {
        ++result.edgeMismatches;
      } else {
        ++result.nonEdgeMismatches;
        if (result.firstNonEdge.size() < IdAgreement::kMaxListed) result.firstNonEdge.emplace_back(x, y);
      }
    }
  }
  return result;
}

}  // namespace hsr::peer

// The fixed-point pixel grid every set-up triangle lives on: 1/256 pixel, the guard band and the
// largest image, which together bound snapped coordinates so that edge functions fit int64; and
// the integer divisions that turn fixed-point positions into pixel ranges. Used by the front end
// (snapping), the edge functions (setup/edge.hpp) and the rasterizers, on any thread.
#pragma once
#include <cmath>
#include <cstdint>

namespace hsr {

/// Sub-pixel precision of snapped vertex positions: 8 bits, 1/256 pixel.
inline constexpr int kSubpixelBits = 8;
inline constexpr int64_t kSubpixelOne = int64_t(1) << kSubpixelBits;
/// Guard band: geometry is clipped to this many pixels beyond each image border, which bounds
/// snapped coordinates by 2^15 pixels (2^23 fixed point) so edge functions fit int64 with room.
inline constexpr double kGuardBandPixels = 8192;
inline constexpr int kMaxImageSize = 16384;

/// Integer division rounding towards minus / plus infinity (b > 0), for pixel ranges.
inline int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
inline int64_t ceilDiv(int64_t a, int64_t b) { return -floorDiv(-a, b); }

/// A pixel coordinate snapped to 1/256 pixel: rounded to the nearest (|s| < 2^15 pixels after
/// clipping, so the result is exact in int64 and in double).
inline int64_t snapCoordinate(double s) { return int64_t(std::floor(s * kSubpixelOne + 0.5)); }

}  // namespace hsr

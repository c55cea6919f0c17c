// OpenGL clip coordinates from an hsr camera, so that a GL renderer draws hsr's pixels and depth
// order: the projection of the llvmpipe peer (bench/peer/llvmpipe_peer.cpp), tested without GL
// by tests/peer_test.cpp. Pure, header-only.
#pragma once
#include <hsr/camera.hpp>

namespace hsr::peer {

// Clip coordinates from hsr camera space (OpenCV axes), for glClipControl(GL_LOWER_LEFT,
// GL_ZERO_TO_ONE) and a reversed-Z float depth buffer (clear 0, GL_GREATER) — hsr's default
// f32:reversed. With h = pixelFromCamera * p = (hx, hy, d, w) and z the camera-space z (= d):
//   x_clip = 2 hx / W - w   : GL window x = hsr pixel x
//   y_clip = w - 2 hy / H   : GL window y = H - hsr pixel y. The image stands upright in GL, so
//                             GL row r (counted bottom up) is hsr row H-1-r, and GL's fill rule,
//                             stated in y-up window coordinates, is hsr's top-left rule.
//   z_clip = s (far - z) / (far - near), s = near (perspective, w = z) or 1 (orthographic,
//            w = 1): window depth = 1 - OpenGL's standard depth, near -> 1, far -> 0, and GL
//            clips exactly at hsr's near and far planes (0 <= z_clip <= w_clip).
inline dmat4 clipFromCamera(const Camera& camera) {
  const dmat4& pix = camera.pixelFromCamera;  // [col][row]
  auto row = [&pix](int r) { return dvec4(pix[0][r], pix[1][r], pix[2][r], pix[3][r]); };
  const double s = camera.orthographic ? 1.0 : camera.near;
  const double range = camera.far - camera.near;
  const dvec4 rows[4] = {
      row(0) * (2.0 / camera.width) - row(3),
      row(3) - row(1) * (2.0 / camera.height),
      dvec4(0, 0, -s / range, s * camera.far / range),
      row(3),
  };
  dmat4 clip(0.0);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) clip[c][r] = rows[r][c];
  return clip;
}

// Eye depth from a window depth of clipFromCamera (inverts its z_clip / w_clip).
inline double eyeDepthFromWindow(const Camera& camera, double windowZ) {
  const double range = camera.far - camera.near;
  return camera.orthographic ? camera.far - windowZ * range
                             : camera.near * camera.far / (camera.near + windowZ * range);
}

}  // namespace hsr::peer

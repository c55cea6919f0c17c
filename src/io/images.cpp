// The PNG writers of io.hpp: shaded colour, face-id images (24-bit id + 1, or int32 .npy) and
// the grey depth picture, encoded in memory with stb_image_write and written atomically.
// Called by the `hsr` command line after a render; formats per docs/conventions.md "Output files".
#include "io/encode.hpp"

#include <stb/stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hsr {

namespace io {

Bytes encodePng(int width, int height, int channels, const uint8_t* pixels, const std::string& name) {
  // stb_image_write sizes its buffers with int arithmetic: (width * channels + 1) * height.
  if ((int64_t(width) * channels + 1) * height > std::numeric_limits<int>::max())
    throw std::runtime_error(name + ": image too large for the PNG encoder");
  Bytes png;
  auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<Bytes*>(context);
    const auto* bytes = static_cast<const uint8_t*>(data);
    out->insert(out->end(), bytes, bytes + size);
  };
  if (!stbi_write_png_to_func(append, &png, width, height, channels, pixels, width * channels))
    throw std::runtime_error(name + ": PNG encoding failed (out of memory?)");
  return png;
}

}  // namespace io

void writeColorPng(const Frame& frame, const std::string& path) {
  io::requirePng(path);
  io::requirePixels(frame, frame.color.size(), "colour", path);
  // RGB unless some pixel is translucent: the smaller file, and what other renderers' PNGs
  // are compared with.
  bool opaque = std::all_of(frame.color.begin(), frame.color.end(), [](Rgba8 c) { return c.a == 255; });
  int channels = opaque ? 3 : 4;
  std::vector<uint8_t> pixels;
  pixels.reserve(frame.color.size() * size_t(channels));
  for (Rgba8 c : frame.color) {
    pixels.insert(pixels.end(), {c.r, c.g, c.b});
    if (!opaque) pixels.push_back(c.a);
  }
  io::writeBytes(io::encodePng(frame.width, frame.height, channels, pixels.data(), path), path);
}

void writeFaceIds(const Frame& frame, const std::string& path) {
  io::IdFileFormat format = io::idFileFormat(path);
  io::requirePixels(frame, frame.faceId.size(), "face-id", path);
  if (format == io::IdFileFormat::Npy) {
    io::writeBytes(io::encodeNpy("<i4", frame.height, frame.width, frame.faceId.data()), path);
    return;
  }
  // PNG: face + 1 as a 24-bit integer, R the high byte; 0 is background. The largest value
  // 2^24 - 1 belongs to face 2^24 - 2.
  constexpr int32_t kMaxFace = (1 << 24) - 2;
  std::vector<uint8_t> pixels;
  pixels.reserve(frame.faceId.size() * 3);
  for (int32_t face : frame.faceId) {
    if (face < -1 || face > kMaxFace)
      throw std::runtime_error(path + ": face id " + std::to_string(face) +
                               " does not fit a 24-bit PNG (write .npy instead)");
    auto value = uint32_t(face + 1);
    pixels.insert(pixels.end(), {uint8_t(value >> 16), uint8_t(value >> 8), uint8_t(value)});
  }
  io::writeBytes(io::encodePng(frame.width, frame.height, 3, pixels.data(), path), path);
}

void writeDepthImage(const Frame& frame, const std::string& path) {
  io::requirePng(path);
  io::requirePixels(frame, frame.depth.size(), "depth", path);
  // Grey linear in eye depth over the visible range: 255 at the nearest surface, kFarGrey at
  // the farthest, so even the farthest surface stays distinct from the black background.
  constexpr double kFarGrey = 32;
  double dmin = std::numeric_limits<double>::infinity(), dmax = -dmin;
  for (float d : frame.depth) {
    if (!std::isfinite(d)) continue;
    dmin = std::min(dmin, double(d));
    dmax = std::max(dmax, double(d));
  }
  double scale = dmax > dmin ? (255.0 - kFarGrey) / (dmax - dmin) : 0.0;
  std::vector<uint8_t> pixels(frame.depth.size());
  std::transform(frame.depth.begin(), frame.depth.end(), pixels.begin(), [&](float d) {
    return std::isfinite(d) ? uint8_t(std::lround(255.0 - (double(d) - dmin) * scale)) : uint8_t(0);
  });
  io::writeBytes(io::encodePng(frame.width, frame.height, 1, pixels.data(), path), path);
}

void writeOverdrawImage(const Frame& frame, const std::string& path) {
  io::requirePng(path);
  io::requirePixels(frame, frame.writes.size(), "per-pixel write count", path);
  static constexpr uint8_t kScale[8][3] = {{0, 0, 0},     {40, 70, 200},  {40, 170, 80},  {230, 210, 40},
                                           {240, 140, 30}, {220, 40, 40}, {200, 60, 200}, {255, 255, 255}};
  std::vector<uint8_t> pixels(frame.writes.size() * 3);
  for (size_t i = 0; i < frame.writes.size(); ++i) {
    const uint8_t* c = kScale[std::min<WriteCount>(frame.writes[i], 7)];
    std::copy(c, c + 3, pixels.begin() + ptrdiff_t(3 * i));
  }
  io::writeBytes(io::encodePng(frame.width, frame.height, 3, pixels.data(), path), path);
}

}  // namespace hsr

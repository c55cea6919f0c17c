// Frame buffers and the statistics JSON (keys of CONVENTIONS.md). Consumed by the writers, the
// CLI (--stats, --json, bench) and the tests.
#include <hsr/frame.hpp>

#include <algorithm>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/parallel.hpp"

namespace hsr {

void Stats::addTime(const std::string& stage, double ms) {
  for (auto& [k, v] : time_ms)
    if (k == stage) {
      v += ms;
      return;
    }
  time_ms.emplace_back(stage, ms);
}

std::string Stats::toJson(int indent) const {
  nlohmann::ordered_json j;
  j["algorithm"] = algorithm;
  j["width"] = width;
  j["height"] = height;
  if (!depth_format.empty()) j["depth_format"] = depth_format;
  j["faces"] = faces;
  j["triangles"] = triangles;
  j["triangles_clipped"] = triangles_clipped;
  j["triangles_degenerate"] = triangles_degenerate;
  j["culled_backface"] = culled_backface;
  j["culled_frustum"] = culled_frustum;
  j["culled_occlusion"] = culled_occlusion;
  j["depth_tests"] = depth_tests;
  j["depth_writes"] = depth_writes;
  j["color_writes"] = color_writes;
  j["covered_pixels"] = covered_pixels;
  j["overdraw"] = overdraw();
  j["memory_bytes"] = memory_bytes;
  nlohmann::ordered_json t = nlohmann::ordered_json::object();
  for (auto& [k, v] : time_ms) t[k] = v;
  j["time_ms"] = t;
  if (wrong_pixels) j["wrong_pixels"] = *wrong_pixels;
  if (ambiguous_pixels) j["ambiguous_pixels"] = *ambiguous_pixels;
  return j.dump(indent);
}

void Frame::resize(int w, int h, Rgba8 background, int threads) {
  width = w;
  height = h;
  const size_t n = size_t(w) * size_t(h);
  faceId.resize(n);
  triangleId.resize(n);
  depth.resize(n);
  color.resize(n);
  // The clear is a pass over 16 bytes a pixel: worth splitting for large frames.
  const size_t chunk = 1 << 16;
  parallelFor(0, (n + chunk - 1) / chunk, threads, [&](size_t c) {
    const size_t b = c * chunk, e = std::min(n, b + chunk);
    std::fill(faceId.begin() + std::ptrdiff_t(b), faceId.begin() + std::ptrdiff_t(e), -1);
    std::fill(triangleId.begin() + std::ptrdiff_t(b), triangleId.begin() + std::ptrdiff_t(e), -1);
    std::fill(depth.begin() + std::ptrdiff_t(b), depth.begin() + std::ptrdiff_t(e), std::numeric_limits<float>::infinity());
    std::fill(color.begin() + std::ptrdiff_t(b), color.begin() + std::ptrdiff_t(e), background);
  });
}

}  // namespace hsr

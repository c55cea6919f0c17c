// Frame buffers and the statistics JSON (keys of docs/conventions.md). Consumed by the writers, the
// CLI (--stats, --json, bench) and the tests.
#include <hsr/frame.hpp>

#include <algorithm>
#include <cstring>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <nlohmann/json.hpp>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "core/parallel.hpp"
#include "core/stream_fill.hpp"

namespace hsr {

namespace detail {

void* allocateBuffer(size_t bytes) {
  if (bytes < kHugePageBytes) return ::operator new(bytes, std::align_val_t{64});
  const size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  if (rounded < bytes) throw std::bad_alloc();
  void* p = ::operator new(rounded, std::align_val_t{kHugePageBytes});
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  madvise(p, rounded, MADV_HUGEPAGE);  // advice: its failure (no THP here) leaves ordinary pages
#endif
  return p;
}

void freeBuffer(void* p, size_t bytes) noexcept {
  if (bytes < kHugePageBytes) ::operator delete(p, std::align_val_t{64});
  else ::operator delete(p, std::align_val_t{kHugePageBytes});
}

}  // namespace detail

void Stats::addTime(const std::string& stage, double ms) {
  for (auto& [k, v] : time_ms)
    if (k == stage) {
      v += ms;
      return;
    }
  time_ms.emplace_back(stage, ms);
}

StaticName StaticName::interned(std::string_view name) {
  static std::mutex mutex;
  static std::set<std::string, std::less<>> names;  // a set's elements never move
  std::lock_guard lock(mutex);
  auto it = names.find(name);
  if (it == names.end()) it = names.emplace(name).first;
  return StaticName(*it);
}

void Stats::addMemory(StaticName name, uint64_t bytes) {
  if (bytes == 0) return;
  memory_bytes += bytes;
  for (auto& [k, v] : memory)
    if (k == name) {
      v += bytes;
      return;
    }
  memory.emplace_back(name, bytes);
}

void Stats::addCounts(const Stats& part) {
  triangles_clipped += part.triangles_clipped;
  triangles_degenerate += part.triangles_degenerate;
  culled_backface += part.culled_backface;
  culled_frustum += part.culled_frustum;
  culled_occlusion += part.culled_occlusion;
  depth_tests += part.depth_tests;
  depth_writes += part.depth_writes;
  color_writes += part.color_writes;
  for (const auto& [stage, ms] : part.time_ms) addTime(stage, ms);
}

void Stats::setDetail(StaticName key, Detail value) {
  for (auto& [k, v] : details)
    if (k == key) {
      v = std::move(value);
      return;
    }
  details.emplace_back(key, std::move(value));
}

void Stats::addDetail(StaticName key, uint64_t count) {
  setDetail(key, detailCount(key).value_or(0) + count);
}

std::optional<uint64_t> Stats::detailCount(std::string_view key) const {
  for (const auto& [k, v] : details)
    if (k == key && std::holds_alternative<uint64_t>(v)) return std::get<uint64_t>(v);
  return std::nullopt;
}

std::string Stats::detailText(std::string_view key) const {
  for (const auto& [k, v] : details)
    if (k == key && std::holds_alternative<std::string>(v)) return std::get<std::string>(v);
  return {};
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
  nlohmann::ordered_json m = nlohmann::ordered_json::object();
  for (const auto& [k, v] : memory) m[std::string(k)] = v;
  j["memory"] = m;
  nlohmann::ordered_json t = nlohmann::ordered_json::object();
  for (auto& [k, v] : time_ms) t[k] = v;
  j["time_ms"] = t;
  nlohmann::ordered_json p = nlohmann::ordered_json::object();
  for (const auto& [k, v] : params) p[k] = v;
  j["params"] = p;
  if (!details.empty() && !algorithm.empty()) {
    nlohmann::ordered_json d = nlohmann::ordered_json::object();
    for (const auto& [k, v] : details) std::visit([&d, &k](const auto& value) { d[std::string(k)] = value; }, v);
    j[algorithm] = d;
  }
  if (wrong_pixels) j["wrong_pixels"] = *wrong_pixels;
  if (ambiguous_pixels) j["ambiguous_pixels"] = *ambiguous_pixels;
  return j.dump(indent);
}

void Frame::allocate(int w, int h, FrameOutputs outputs) {
  width = w;
  height = h;
  const size_t n = size_t(w) * size_t(h);
  depth.resize(n);
  faceId.resize(has(outputs, FrameOutputs::FaceIds) ? n : 0);
  triangleId.resize(has(outputs, FrameOutputs::TriangleIds) ? n : 0);
  color.resize(has(outputs, FrameOutputs::Color) ? n : 0);
}

namespace {
constexpr std::pair<const char*, FrameOutputs> kOutputWords[] = {
    {"face", FrameOutputs::FaceIds}, {"triangle", FrameOutputs::TriangleIds}, {"color", FrameOutputs::Color}};
}

FrameOutputs parseFrameOutputs(const std::string& list, const std::string& what) {
  FrameOutputs outputs = FrameOutputs::DepthOnly;
  size_t begin = 0;
  while (begin <= list.size()) {
    const size_t end = std::min(list.find(',', begin), list.size());
    const std::string word = list.substr(begin, end - begin);
    bool known = word == "depth";
    for (auto [name, flag] : kOutputWords)
      if (word == name) {
        outputs = outputs | flag;
        known = true;
      }
    if (!known)
      throw InputError(what + ": unknown output '" + word + "' in '" + list +
                       "' (a comma-separated list of depth, face, triangle, color)");
    begin = end + 1;
  }
  return outputs;
}

std::string frameOutputsName(FrameOutputs outputs) {
  std::string name = "depth";
  for (auto [word, flag] : kOutputWords)
    if (has(outputs, flag)) name += std::string(",") + word;
  return name;
}

void Frame::clear(Rgba8 background, int threads) {
  // The clear is a pass over up to 16 bytes a pixel: worth splitting for large frames, and written
  // with streaming stores (core/stream_fill.hpp; chunks of whole cache lines).
  const size_t n = depth.size(), chunk = 1 << 16;
  auto fill = [chunk](auto& buffer, size_t c, auto value) {
    static_assert(sizeof(value) == sizeof(uint32_t));
    const size_t b = std::min(buffer.size(), c * chunk), e = std::min(buffer.size(), b + chunk);
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    streamFill(reinterpret_cast<uint32_t*>(buffer.data() + b), bits, e - b);
  };
  parallelFor(0, (n + chunk - 1) / chunk, threads, [&](size_t c) {
    fill(faceId, c, -1);
    fill(triangleId, c, -1);
    fill(depth, c, std::numeric_limits<float>::infinity());
    fill(color, c, background);
    fill(writes, c, WriteCount(0));
  });
}

void Frame::resize(int w, int h, Rgba8 background, int threads) {
  allocate(w, h);
  clear(background, threads);
}

}  // namespace hsr

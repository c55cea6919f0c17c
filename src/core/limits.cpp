// The process-wide memory limit (hsr/limits.hpp): its machine default, checks and parsing.
#include <hsr/common.hpp>
#include <hsr/limits.hpp>

#include <atomic>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace hsr {
namespace {

std::atomic<uint64_t> gLimit{0};  // 0: not set

uint64_t machineDefault() {
  static const uint64_t bytes = [] {
    std::ifstream in("/proc/meminfo");
    std::string key;
    uint64_t kib = 0;
    std::string unit;
    while (in >> key >> kib >> unit)
      if (key == "MemAvailable:") return kib * 1024;
    return uint64_t(8) << 30;
  }();
  return bytes;
}

std::string mib(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f", std::ceil(bytes / double(1 << 20)));
  return text;
}

}  // namespace

uint64_t memoryLimit() {
  const uint64_t set = gLimit.load(std::memory_order_relaxed);
  return set ? set : machineDefault();
}

void setMemoryLimit(uint64_t bytes) { gLimit.store(bytes, std::memory_order_relaxed); }

void checkMemory(double bytes, const std::string& what) {
  const uint64_t limit = memoryLimit();
  if (!(bytes <= double(limit)))  // also NaN
    throw InputError(Setting::MaxMemory, what,
                     "needs about " + mib(bytes) + " MiB, more than the memory limit of " + mib(double(limit)) + " MiB");
}

uint64_t parseMemorySize(const std::string& text, const std::string& what) {
  double value = 0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value, std::chars_format::fixed);
  std::string unit(ptr, end);
  for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();
  if (unit.size() == 2 && unit.back() == 'I') unit.pop_back();  // KiB, MiB, ...
  double scale = 0;
  if (unit.empty() || unit == "B") scale = 1;
  else if (unit == "K") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  const double bytes = value * scale;
  if (ec != std::errc() || ptr == begin || scale == 0 || !(bytes >= 1 << 20) || !(bytes < 1e18))
    throw InputError(what + " '" + text + "': expected a size of at least 1M, such as 512M or 4G");
  return uint64_t(bytes);
}

}  // namespace hsr

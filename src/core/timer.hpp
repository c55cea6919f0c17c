// Wall-clock stage timer for Stats::time_ms.
#pragma once
#include <chrono>

namespace hsr {
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }
  double lap() {
    auto now = std::chrono::steady_clock::now();
    double r = std::chrono::duration<double, std::milli>(now - start_).count();
    start_ = now;
    return r;
  }
 private:
  std::chrono::steady_clock::time_point start_;
};
}  // namespace hsr

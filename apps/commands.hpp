// The subcommands that live in their own files (apps/NAME_cmd.cpp), for the table in
// hsr_main.cpp: each declares its flags on its CLI11 app and returns the runner that does the work.
#pragma once
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace hsr::cli {

using Runner = std::function<int()>;

Runner setupPrecision(CLI::App& cmd);
Runner setupCompare(CLI::App& cmd);

/// Wall-clock milliseconds since `start`.
inline double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The median of `values` (0 when empty).
inline double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n == 0 ? 0 : n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// The CPU's model name (Linux /proc/cpuinfo; "unknown" elsewhere), for benchmark records.
std::string cpuModel();

}  // namespace hsr::cli

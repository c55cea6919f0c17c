// The subcommands, each in its own file (apps/NAME_cmd.cpp), for the table in apps/main.cpp: each
// declares its flags on its CLI11 app and returns the runner that does the work once parsing
// succeeded; and the small helpers several of them share.
#pragma once
#include <hsr/common.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#ifndef HSR_VERSION
#define HSR_VERSION "0.1.0"  // normally set by CMake from project(VERSION)
#endif

namespace hsr::cli {

using Runner = std::function<int()>;

Runner setupRender(CLI::App& cmd);      // render_cmd.cpp
Runner setupBench(CLI::App& cmd);       // bench_cmd.cpp
Runner setupBatch(CLI::App& cmd);       // batch_cmd.cpp
Runner setupAlgorithms(CLI::App& cmd);  // catalog_cmd.cpp
Runner setupScenes(CLI::App& cmd);      // catalog_cmd.cpp
Runner setupInfo(CLI::App& cmd);        // info_cmd.cpp
Runner setupCompare(CLI::App& cmd);     // compare_cmd.cpp
Runner setupPrecision(CLI::App& cmd);   // precision_cmd.cpp

/// The listing of `hsr algorithms` (and `hsr help algorithms`) on stdout.
void printAlgorithms();
/// The registered algorithms' names, comma-separated (catalog_cmd.cpp).
std::string algorithmNames();

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

/// An InputError in the command line's terms: a keyed error names its setting by the flag that
/// sets it ("--size 0x5: ...", "... (--max-memory)"); a plain one is its what() (flags.cpp).
std::string cliMessage(const hsr::InputError& error);

/// The CPU's model name (Linux /proc/cpuinfo; "unknown" elsewhere), for benchmark records.
std::string cpuModel();

}  // namespace hsr::cli

// The subcommands that live in their own files (apps/NAME_cmd.cpp), for the table in
// hsr_main.cpp: each declares its flags on its CLI11 app and returns the runner that does the work.
#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace hsr::cli {

using Runner = std::function<int()>;

Runner setupPrecision(CLI::App& cmd);
Runner setupCompare(CLI::App& cmd);

/// The CPU's model name (Linux /proc/cpuinfo; "unknown" elsewhere), for benchmark records.
std::string cpuModel();

}  // namespace hsr::cli

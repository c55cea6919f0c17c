// The output files of one command, checked together before any work is done (docs/cli.md
// "Outputs"): every one named, none a special file, no two the same file.
#pragma once
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace hsr::cli {

/// One output flag as parsed: its name, its CLI11 option (to tell `-o ""` from no -o) and its value.
struct OutputFlag {
  std::string flag;
  const CLI::Option* option;
  const std::string* path;
  bool stdoutAllowed = false;  // "-" means standard output
};

/// Throws InputError "--flag: ..." when a flag given was given an empty path, "-" where standard
/// output is not allowed, a path that exists and is not a regular file, or the same file as
/// another flag (compared after resolving ".", ".." and symbolic links).
void checkOutputSet(const std::vector<OutputFlag>& outputs);

}  // namespace hsr::cli

// Checks a command's output files as a set (output_set.hpp).
#include "output_set.hpp"

#include <hsr/common.hpp>
#include <hsr/io.hpp>

#include <filesystem>
#include <map>

namespace hsr::cli {

void checkOutputSet(const std::vector<OutputFlag>& outputs) {
  namespace fs = std::filesystem;
  std::map<fs::path, std::string> seen;  // resolved path -> the flag that named it
  for (const OutputFlag& o : outputs) {
    const std::string& path = *o.path;
    if (o.option->count() == 0) continue;
    if (path.empty()) throw InputError(o.flag + ": the output path is empty");
    if (path == "-") {
      if (!o.stdoutAllowed) throw InputError(o.flag + " '-': standard output is accepted only by --stats");
      continue;
    }
    try {
      checkOutputTarget(path);
    } catch (const InputError& e) {
      throw InputError(o.flag + " " + e.what());
    }
    std::error_code ec;
    fs::path resolved = fs::weakly_canonical(fs::absolute(path), ec);
    if (ec) resolved = fs::absolute(path).lexically_normal();
    auto [it, fresh] = seen.emplace(resolved, o.flag);
    if (!fresh) throw InputError(o.flag + " " + path + ": the same file as " + it->second + " (one would overwrite the other)");
  }
}

}  // namespace hsr::cli

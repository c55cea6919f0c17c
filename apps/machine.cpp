// What the records of benchmarks and studies say about the machine (commands.hpp).
#include <fstream>
#include <string>

#include "commands.hpp"

namespace hsr::cli {

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (const size_t colon = line.find(':'); line.rfind("model name", 0) == 0 && colon != std::string::npos)
      if (const size_t start = line.find_first_not_of(' ', colon + 1); start != std::string::npos)
        return line.substr(start);
  return "unknown";
}

}  // namespace hsr::cli

// Fuzz target: the builtin: scene name and parameter parser and the generators it runs
// (src/scene/builtin*.cpp), under the fuzzing memory limit (fuzz_util.hpp).
#include <hsr/builtin.hpp>

#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hsr::fuzz::setLimits();
  std::string spec(reinterpret_cast<const char*>(data), size);
  hsr::fuzz::refusedOrDone([&] { hsr::makeBuiltin(spec); });
  return 0;
}

// Fuzz target: the own OFF loader (src/scene/load_off.cpp) and Scene::finalize() on any bytes.
#include "fuzz/fuzz_util.hpp"
#include "scene/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hsr::fuzz::refusedOrDone([&] { hsr::loaders::loadOff("fuzz.off", bytes).finalize(); });
  return 0;
}

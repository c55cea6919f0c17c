// Fuzz target: the own STL loader (src/scene/load_stl.cpp) and Scene::finalize() on any bytes.
#include "fuzz/fuzz_util.hpp"
#include "scene/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hsr::fuzz::refusedOrDone([&] { hsr::loaders::loadStl("fuzz.stl", bytes).finalize(); });
  return 0;
}

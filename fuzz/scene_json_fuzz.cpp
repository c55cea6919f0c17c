// Fuzz target: the scene JSON loader (src/scene/load_json.cpp) and finalize(). The scratch
// folder holds a small OBJ, "cube.obj", for the JSON's meshes to name.
#include "fuzz/fuzz_util.hpp"
#include "scene/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const bool ready = [] {
    hsr::fuzz::writeFile(hsr::fuzz::scratch() / "cube.obj",
                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                         "f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
    return true;
  }();
  (void)ready;
  hsr::fuzz::setLimits();  // a mesh may be a builtin of any size: the library's limit refuses it
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string path = (hsr::fuzz::scratch() / "scene.json").string();
  hsr::fuzz::refusedOrDone([&] {
    hsr::loaders::LoadContext context;
    hsr::loaders::loadSceneJson(path, bytes, context).finalize();
  });
  return 0;
}

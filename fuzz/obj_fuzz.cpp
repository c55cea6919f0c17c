// Fuzz target: the OBJ loader with its MTL reader (src/scene/load_obj.cpp) and finalize(). The
// input is an OBJ, optionally followed by a line "#%%mtl" and the contents of m.mtl, the
// material library that lies beside the OBJ (so "mtllib m.mtl" reads it).
#include "fuzz/fuzz_util.hpp"
#include "scene/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kMark = "\n#%%mtl\n";
  const size_t mark = bytes.find(kMark);
  std::string_view obj = bytes.substr(0, mark);
  std::string_view mtl = mark == std::string_view::npos ? std::string_view() : bytes.substr(mark + kMark.size());
  hsr::fuzz::writeFile(hsr::fuzz::scratch() / "m.mtl", mtl);
  const std::string path = (hsr::fuzz::scratch() / "f.obj").string();
  hsr::fuzz::refusedOrDone([&] { hsr::loaders::loadObj(path, obj).finalize(); });
  return 0;
}

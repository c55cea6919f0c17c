// Fuzz target: the assimp path of loadScene() (src/scene/load_assimp.cpp) for glTF 2 — a .glb
// when the input starts with the binary magic "glTF", else a .gltf — through a scratch file,
// since assimp reads files.
#include <hsr/io.hpp>

#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const bool binary = bytes.starts_with("glTF");
  const std::string path = (hsr::fuzz::scratch() / (binary ? "f.glb" : "f.gltf")).string();
  hsr::fuzz::writeFile(path, bytes);
  hsr::fuzz::refusedOrDone([&] { hsr::loadScene(path); });
  return 0;
}

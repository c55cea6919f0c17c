// Fuzz target: the camera JSON parser (src/core/camera.cpp), then resolveCamera() for a small
// image, and the spec written back as JSON, which must parse again.
#include <hsr/camera.hpp>

#include <cstdio>
#include <cstdlib>

#include "fuzz/fuzz_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hsr::fuzz::refusedOrDone([&] {
    const hsr::CameraSpec spec = hsr::parseCameraJson(text, "camera.json");
    const std::string again = hsr::cameraSpecToJson(spec);
    try {
      hsr::parseCameraJson(again, "written.json");
    } catch (const hsr::InputError& e) {
      std::fprintf(stderr, "a parsed camera, written back, does not parse: %s\n%s\n", e.what(), again.c_str());
      std::abort();
    }
    hsr::Bounds3 bounds;
    bounds.lo = hsr::dvec3(-1);
    bounds.hi = hsr::dvec3(1);
    hsr::resolveCamera(spec, spec.width.value_or(64) % 4096 + 1, spec.height.value_or(48) % 4096 + 1, bounds);
  });
  return 0;
}

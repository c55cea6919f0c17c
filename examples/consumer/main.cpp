// Embedding hsr: render a built-in scene's face ids and eye depth in memory, no files.
#include <hsr/hsr.hpp>

#include <cmath>
#include <cstdio>

int main() {
  hsr::Scene scene = hsr::loadScene("builtin:cubes");
  hsr::Camera camera = hsr::resolveCamera(*scene.camera, 160, 120, scene.bounds());
  hsr::RenderOptions options;  // z-buffer, f32:reversed depth
  hsr::Frame frame = hsr::render(scene, camera, options);
  const size_t centre = frame.index(80, 60);
  std::printf("covered %llu pixels; centre shows face %d at depth %.4f\n",
              static_cast<unsigned long long>(frame.stats.covered_pixels), frame.faceId[centre],
              double(frame.depth[centre]));
  return frame.stats.covered_pixels > 0 ? 0 : 1;
}

// Embedding hsr as an occlusion culler: rasterize the occluders once per frame into an
// OcclusionBuffer (depth only, kept in tiles), then ask for each object's bounding box whether
// any of it could show, and draw only those.
#include <hsr/hsr.hpp>

#include <cstdio>

int main() {
  const hsr::Scene city = hsr::loadScene("builtin:city");  // the occluders: blocks of buildings
  const hsr::Camera camera = hsr::resolveCamera(*city.camera, 640, 360, city.bounds());
  hsr::OcclusionBuffer buffer;
  const hsr::Stats& stats = buffer.render(city, camera);  // all cores, f32:reversed depth

  // Objects: a grid of small boxes over the city's ground, e.g. street furniture or props.
  const hsr::Bounds3 b = city.bounds();
  const hsr::dvec3 extent = b.hi - b.lo;
  int visible = 0, culled = 0;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      hsr::Bounds3 box;
      box.add(b.lo + hsr::dvec3((i + 0.4) / 40 * extent.x, 0.0, (j + 0.4) / 40 * extent.z));
      box.add(b.lo + hsr::dvec3((i + 0.6) / 40 * extent.x, 0.02 * extent.y, (j + 0.6) / 40 * extent.z));
      ++(buffer.boxVisible(box) ? visible : culled);
    }
  std::printf("occluders: %llu triangles in %.2f ms; %d of %d boxes may show, %d hidden or out of view\n",
              static_cast<unsigned long long>(stats.triangles), stats.time_ms.back().second, visible,
              visible + culled, culled);
  return visible > 0 && culled > 0 ? 0 : 1;
}

// Small scenes built directly in tests (independent of the loaders and the built-in generators).
#pragma once
#include <hsr/hsr.hpp>

#include <cstring>
#include <random>

namespace hsr::test {

/// First pixel where two frame buffers differ bitwise, or -1 (0 when their sizes differ).
template <class T>
long firstDifference(const FrameBuffer<T>& a, const FrameBuffer<T>& b) {
  if (a.size() != b.size()) return 0;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0) return long(i);
  return -1;
}

/// Axis-aligned box [lo, hi] as 6 quads, appended to `s` (call s.finalize() afterwards).
inline void addBox(Scene& s, dvec3 lo, dvec3 hi, Rgba8 color) {
  uint32_t b = uint32_t(s.positions.size());
  for (int i = 0; i < 8; ++i) s.positions.push_back({i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z});
  const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto& f : q) s.addFace({b + f[0], b + f[1], b + f[2], b + f[3]}, color);
}

/// Three boxes at different depths, partly hiding each other, optionally offset.
inline Scene boxesScene(dvec3 offset = dvec3(0)) {
  Scene s;
  s.source = "test:boxes";
  s.beginMesh("boxes");
  addBox(s, offset + dvec3(-1.5, -1, -1), offset + dvec3(0.5, 1, 1), {200, 60, 60, 255});
  addBox(s, offset + dvec3(0, -0.5, -3), offset + dvec3(2, 1.5, -1.5), {60, 200, 60, 255});
  addBox(s, offset + dvec3(-0.7, -0.2, 1.2), offset + dvec3(0.3, 0.6, 2.0), {60, 60, 200, 255});
  s.finalize();
  return s;
}

/// `n` random triangles in a cube of side 2 around the origin, intersecting each other.
inline Scene randomSoup(int n, uint64_t seed, double size = 0.6) {
  Scene s;
  s.source = "test:soup";
  s.beginMesh("soup");
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int i = 0; i < n; ++i) {
    dvec3 c{u() * 2 - 1, u() * 2 - 1, u() * 2 - 1};
    uint32_t b = uint32_t(s.positions.size());
    for (int k = 0; k < 3; ++k) s.positions.push_back(c + size * dvec3(u() - 0.5, u() - 0.5, u() - 0.5));
    s.addFace({b, b + 1, b + 2}, Rgba8{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), 255});
  }
  s.finalize();
  return s;
}

inline CameraSpec lookAt(dvec3 eye, dvec3 target, double fovy = 50, double near = 0.1, double far = 100) {
  CameraSpec c;
  c.eye = eye;
  c.target = target;
  c.fovyDeg = fovy;
  c.near = near;
  c.far = far;
  return c;
}

}  // namespace hsr::test

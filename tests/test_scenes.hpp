// Small scenes built directly in tests (independent of the loaders and the built-in generators).
#pragma once
#include <hsr/hsr.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <random>
#include <vector>

namespace hsr {
/// The z-buffer's rasterizers (its `raster` parameter), for tests that compare them.
enum class RasterKind : uint8_t { Tiled, HalfSpace, Scanline };
inline const char* rasterName(RasterKind k) {
  return k == RasterKind::Tiled ? "tiled" : k == RasterKind::HalfSpace ? "halfspace" : "scanline";
}
inline void setRaster(RenderOptions& options, RasterKind k) { options.params["raster"] = rasterName(k); }
}  // namespace hsr

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

/// `n` meshes in a cube of side 2 around the origin, intersecting each other: boxes turned at
/// random (some thin as walls), and every fifth a single triangle, some of them slivers.
inline Scene rotatedBoxes(int n, uint64_t seed) {
  Scene s;
  s.source = "test:rotated-boxes";
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int i = 0; i < n; ++i) {
    s.beginMesh("mesh " + std::to_string(i));
    const dvec3 c{u() * 2 - 1, u() * 2 - 1, u() * 2 - 1};
    const Rgba8 color{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), 255};
    const uint32_t b = uint32_t(s.positions.size());
    if (i % 5 == 4) {
      const double sliver = i % 10 == 9 ? 1e-4 : 1;
      const dvec3 a{u() - 0.5, u() - 0.5, u() - 0.5}, d{u() - 0.5, u() - 0.5, u() - 0.5};
      s.positions.push_back(c);
      s.positions.push_back(c + 0.6 * a);
      s.positions.push_back(c + 0.6 * (a + sliver * d));
      s.addFace({b, b + 1, b + 2}, color);
      continue;
    }
    // An orthonormal frame from a random unit quaternion; half sizes, one of them thin at times.
    double q[4];
    double len = 0;
    for (double& v : q) v = u() * 2 - 1, len += v * v;
    for (double& v : q) v /= std::sqrt(len);
    const auto [w, x, y, z] = std::array<double, 4>{q[0], q[1], q[2], q[3]};
    const dvec3 axes[3] = {{1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)},
                           {2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)},
                           {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)}};
    dvec3 half{0.05 + 0.25 * u(), 0.05 + 0.25 * u(), 0.05 + 0.25 * u()};
    if (i % 3 == 0) half.z = 0.002;
    for (int k = 0; k < 8; ++k)
      s.positions.push_back(c + axes[0] * (k & 1 ? half.x : -half.x) + axes[1] * (k & 2 ? half.y : -half.y) +
                            axes[2] * (k & 4 ? half.z : -half.z));
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (auto& f : quads) s.addFace({b + f[0], b + f[1], b + f[2], b + f[3]}, color);
  }
  s.finalize();
  return s;
}

/// `n` random planar convex polygons, quads and pentagons alternately, in a cube of side 2 around
/// the origin, of random orientation and radius 0.25 to 0.6: they interpenetrate and overlap in
/// cycles (the cases a depth sort must split).
inline Scene randomPolygons(int n, uint64_t seed) {
  Scene s;
  s.source = "test:polygons";
  s.beginMesh("polygons");
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int i = 0; i < n; ++i) {
    const dvec3 c{u() * 2 - 1, u() * 2 - 1, u() * 2 - 1};
    dvec3 a{u() - 0.5, u() - 0.5, u() - 0.5}, b{u() - 0.5, u() - 0.5, u() - 0.5};
    a = glm::normalize(a);
    b = glm::normalize(b - glm::dot(a, b) * a);
    const int k = 4 + i % 2;
    const double radius = 0.25 + 0.35 * u(), turn = u() * 2 * M_PI;
    const uint32_t first = uint32_t(s.positions.size());
    std::vector<uint32_t> corners;
    for (int j = 0; j < k; ++j) {
      const double angle = turn + 2 * M_PI * (j + 0.3 * u()) / k;
      s.positions.push_back(c + radius * (std::cos(angle) * a + std::sin(angle) * b));
      corners.push_back(first + uint32_t(j));
    }
    s.addFace(corners, Rgba8{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), 255});
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

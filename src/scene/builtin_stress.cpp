// Built-in parametric scenes for measurement: random intersecting triangles (KTH report, KTH thesis), a
// geodesic sphere of about a million triangles, stacked screen-filling layers (overdraw) and a
// city seen from the street (occlusion). Called by makeBuiltin() (builtin.cpp).
//
// Random numbers come from builtin::Random (a standard engine with our own real mapping) and
// geometry uses only +, *, / and sqrt, so every platform builds bit-identical scenes.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "scene/builtin_internal.hpp"

#ifdef __clang__
#pragma STDC FP_CONTRACT OFF  // no fused multiply-add: the same bits as GCC's ISO mode
#endif

namespace hsr::builtin {
namespace {

// Makes room for `extra` more elements, at least doubling the capacity when it grows, so that a
// scene built of many meshes, each reserving its own, grows in linear time.
template <class T>
void reserveMore(std::vector<T>& v, size_t extra) {
  if (v.size() + extra > v.capacity()) v.reserve(std::max(v.size() + extra, 2 * v.capacity()));
}

// Reserves room for `faces` faces of `corners` corners each and `vertices` more positions, so
// large scenes grow without repeated reallocation.
void reserve(Scene& scene, size_t faces, size_t corners, size_t vertices) {
  reserveMore(scene.positions, vertices);
  reserveMore(scene.polygonIndices, faces * corners);
  reserveMore(scene.polygonOffsets, faces);
  reserveMore(scene.faceColors, faces);
}

}  // namespace

// N triangles with random centres in a box (2.67 x 2 x 2, the image's 4:3) and random
// orientations. Each triangle's corners lie near 0, 120 and 240 degrees on its circumcircle,
// jittered within the circle, so no triangle is a sliver; with the default size many pierce
// each other.
Scene makeRandom(const Args& args) {
  const auto n = size_t(args.integer("n"));
  const double radius = args.real("size") * 2;  // fraction of the box height
  const dvec3 halfBox(4.0 / 3, 1, 1);
  const double root3half = std::sqrt(3.0) / 2;
  const dvec2 spoke[3] = {{1, 0}, {-0.5, root3half}, {-0.5, -root3half}};

  Random random(uint64_t(args.integer("seed")));
  Scene scene;
  reserve(scene, n, 3, 3 * n);
  scene.beginMesh("triangles");
  for (size_t t = 0; t < n; ++t) {
    // One draw per statement: the order of evaluation of function arguments is unspecified.
    dvec3 center;
    for (int axis = 0; axis < 3; ++axis)
      center[axis] = random.uniform(-halfBox[axis], halfBox[axis]);
    // An orthonormal frame (u, v) of a random plane through the centre.
    const dvec3 normal = random.unitVector();
    dvec3 u;
    do {
      const dvec3 other = random.unitVector();
      u = other - normal * glm::dot(normal, other);
    } while (glm::dot(u, u) < 0.01);
    u = glm::normalize(u);
    const dvec3 v = glm::cross(normal, u);

    const auto first = uint32_t(scene.positions.size());
    for (const dvec2& s : spoke) {
      dvec2 jitter;
      do {
        jitter.x = random.uniform(-1, 1);
        jitter.y = random.uniform(-1, 1);
      } while (glm::dot(jitter, jitter) > 1);
      const dvec2 p = 0.75 * s + 0.25 * jitter;  // within the circumcircle
      scene.positions.push_back(center + radius * (p.x * u + p.y * v));
    }
    scene.addFace({first, first + 1, first + 2}, paletteColor(t));
  }
  scene.camera = perspectiveCamera({0, 0, 4.5}, {0, 0, 0}, 45, 0.5, 10);
  return scene;
}

// A unit geodesic sphere: each face of an icosahedron divided into k x k triangles, the points
// pushed onto the sphere. 20 k^2 triangles (k chosen nearest to the target n), 10 k^2 + 2
// shared vertices: a closed, watertight mesh, wound counter-clockwise seen from outside. Each
// icosahedron face keeps one colour, so the 20 patches show the structure.
namespace {
// Adds a geodesic sphere of 20 K^2 triangles as the mesh begun last: unit sphere point p at
// place(p), icosahedron face f's triangles in colorOf(f).
template <class Place, class ColorOf>
void addGeodesicSphere(Scene& scene, uint32_t K, const Place& place, const ColorOf& colorOf) {
  // The icosahedron: corners (0, +-1, +-phi) and cyclic permutations; faces counter-clockwise
  // seen from outside.
  const double phi = (1 + std::sqrt(5.0)) / 2;
  const dvec3 corners[12] = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                             {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                             {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  static constexpr uint32_t kFaces[20][3] = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};

  reserve(scene, size_t(20) * K * K, 3, size_t(10) * K * K + 2);
  const auto base = uint32_t(scene.positions.size());
  const auto onSphere = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t i, uint32_t j) {
    // Point (i, j) of face (a, b, c): a + (b - a) i/k + (c - a) j/k, then normalised.
    const dvec3 p = corners[a] + (corners[b] - corners[a]) * (double(i) / K) +
                    (corners[c] - corners[a]) * (double(j) / K);
    return place(p / std::sqrt(glm::dot(p, p)));
  };

  // Vertices: the 12 corners, then k - 1 inner points per edge (numbered from the edge's lower
  // corner), then each face's interior points as the faces are triangulated.
  for (uint32_t c = 0; c < 12; ++c) scene.positions.push_back(onSphere(c, c, c, 0, 0));
  int edgeId[12][12];
  for (auto& row : edgeId) std::fill(std::begin(row), std::end(row), -1);
  int edges = 0;
  for (const auto& f : kFaces)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = std::min(f[e], f[(e + 1) % 3]), b = std::max(f[e], f[(e + 1) % 3]);
      if (edgeId[a][b] >= 0) continue;
      edgeId[a][b] = edgeId[b][a] = edges++;
      for (uint32_t t = 1; t < K; ++t) scene.positions.push_back(onSphere(a, b, a, t, 0));
    }
  // Index of the point t steps from corner `from` towards corner `to` (0 <= t <= k).
  const auto edgePoint = [&](uint32_t from, uint32_t to, uint32_t t) -> uint32_t {
    if (t == 0) return base + from;
    if (t == K) return base + to;
    const uint32_t edge = base + 12 + uint32_t(edgeId[from][to]) * (K - 1);
    return from < to ? edge + t - 1 : edge + (K - t) - 1;
  };

  // Per face, a triangular grid of vertex indices: row j holds points (0..k-j, j).
  std::vector<uint32_t> rowStart(K + 2);
  for (uint32_t j = 0; j <= K; ++j) rowStart[j + 1] = rowStart[j] + (K + 1 - j);
  std::vector<uint32_t> grid(rowStart[K + 1]);
  for (uint32_t f = 0; f < 20; ++f) {
    const uint32_t a = kFaces[f][0], b = kFaces[f][1], c = kFaces[f][2];
    for (uint32_t j = 0; j <= K; ++j)
      for (uint32_t i = 0; i + j <= K; ++i) {
        uint32_t& index = grid[rowStart[j] + i];
        if (j == 0)
          index = edgePoint(a, b, i);
        else if (i == 0)
          index = edgePoint(a, c, j);
        else if (i + j == K)
          index = edgePoint(b, c, j);
        else {
          index = uint32_t(scene.positions.size());
          scene.positions.push_back(onSphere(a, b, c, i, j));
        }
      }
    const Rgba8 color = colorOf(f);
    const auto at = [&](uint32_t i, uint32_t j) { return grid[rowStart[j] + i]; };
    for (uint32_t j = 0; j < K; ++j)
      for (uint32_t i = 0; i + j < K; ++i) {
        // "Up" triangle, then the "down" one sharing its right edge: both keep (a, b, c)'s
        // orientation.
        scene.addFace({at(i, j), at(i + 1, j), at(i, j + 1)}, color);
        if (i + j + 1 < K) scene.addFace({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)}, color);
      }
  }
}
}  // namespace

Scene makeSphere(const Args& args) {
  const auto target = double(args.integer("n"));
  int64_t k = std::max<int64_t>(1, int64_t(std::sqrt(target / 20)));
  if (std::abs(20.0 * double((k + 1) * (k + 1)) - target) <
          std::abs(20.0 * double(k * k) - target) &&
      20 * (k + 1) * (k + 1) <= kMaxTriangles)
    k += 1;
  Scene scene;
  scene.beginMesh("sphere");
  addGeodesicSphere(scene, uint32_t(k), [](const dvec3& p) { return p; }, [](uint32_t f) { return paletteColor(f); });
  scene.camera = perspectiveCamera({1.6, 1.0, 2.4}, {0, 0, 0}, 45, 1, 5);
  return scene;
}

// Closed solids and a CSG tree over them (Scene::csg), for the csg algorithm and its reference:
// a cube minus a sphere at its corner, a cube intersected with a sphere (a rounded cube), a cube
// united with a sphere, or the rounded cube minus three crossed bars. No two solids share a
// plane, so the tree's surfaces meet along curves, not in coplanar patches.
Scene makeCsg(const Args& args) {
  const std::string& op = args.text("op");
  const auto K = uint32_t(args.integer("detail"));
  Scene scene;
  auto solid = [&](uint32_t firstFace) {
    scene.csg.push_back({CsgNode::Op::Solid, firstFace, uint32_t(scene.faceCount()) - firstFace, 0, 0});
    return uint32_t(scene.csg.size() - 1);
  };
  auto combine = [&](CsgNode::Op kind, uint32_t left, uint32_t right) {
    scene.csg.push_back({kind, 0, 0, left, right});
    return uint32_t(scene.csg.size() - 1);
  };
  auto box = [&](const char* name, const dvec3& half, Rgba8 color) {
    const uint32_t first = uint32_t(scene.faceCount());
    scene.beginMesh(name);
    addBox(scene, dvec3(0.0), dmat3(1.0), half, [&](int k) { return shade(color, faceShade(k)); });
    return solid(first);
  };
  auto sphere = [&](const dvec3& centre, double radius) {
    const uint32_t first = uint32_t(scene.faceCount());
    scene.beginMesh("sphere");
    addGeodesicSphere(
        scene, K, [&](const dvec3& p) { return centre + radius * p; },
        [](uint32_t f) { return shade(Rgba8{90, 150, 230, 255}, 0.8 + 0.2 * double(f % 2)); });
    return solid(first);
  };
  const uint32_t cube = box("cube", dvec3(1.0), Rgba8{230, 160, 70, 255});
  if (op == "difference") {
    combine(CsgNode::Op::Difference, cube, sphere(dvec3(0.75), 1.0));
  } else if (op == "intersection") {
    combine(CsgNode::Op::Intersection, cube, sphere(dvec3(0.0), 1.35));
  } else if (op == "union") {
    combine(CsgNode::Op::Union, cube, sphere(dvec3(0.9), 0.8));
  } else {  // mixed
    const uint32_t rounded = combine(CsgNode::Op::Intersection, cube, sphere(dvec3(0.0), 1.35));
    const uint32_t x = box("bar-x", {1.5, 0.45, 0.45}, Rgba8{120, 200, 110, 255});
    const uint32_t y = box("bar-y", {0.42, 1.5, 0.42}, Rgba8{120, 200, 110, 255});
    const uint32_t z = box("bar-z", {0.39, 0.39, 1.5}, Rgba8{120, 200, 110, 255});
    combine(CsgNode::Op::Difference, rounded,
            combine(CsgNode::Op::Union, combine(CsgNode::Op::Union, x, y), z));
  }
  scene.camera = perspectiveCamera({2.6, 2.0, 3.4}, {0, 0, 0}, 48, 1, 10);
  return scene;
}

// N rounded objects (ellipsoids: geodesic spheres of 20 K^2 triangles, stretched and turned at
// random) scattered over a square floor, seen from its edge at eye level: many curved meshes
// hiding each other, as in a cluttered room or yard. Their triangles lie on hundreds of planes,
// so mesh culling (docs/occlusion.md) cannot bound them whole.
Scene makeClutter(const Args& args) {
  const auto n = uint32_t(args.integer("n"));
  const auto K = uint32_t(args.integer("detail"));
  Random random(uint64_t(args.integer("seed")));
  const double side = 2.5 * std::sqrt(double(n)) + 4;
  Scene scene;
  scene.beginMesh("floor");
  addPolygon(scene, {{-2, 0, -2}, {-2, 0, side + 2}, {side + 2, 0, side + 2}, {side + 2, 0, -2}},
             Rgba8{120, 118, 110, 255});
  for (uint32_t i = 0; i < n; ++i) {
    // A turn from a random unit quaternion (only +, *, / and sqrt), radii 0.3-1.2.
    double q[4], length = 0;
    for (double& v : q) v = random.uniform(-1, 1), length += v * v;
    length = std::sqrt(length);
    for (double& v : q) v /= length;
    const auto [w, x, y, z] = std::array<double, 4>{q[0], q[1], q[2], q[3]};
    const dmat3 turn(dvec3(1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)),
                     dvec3(2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)),
                     dvec3(2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)));
    // One draw per statement: the order of a call's arguments differs between compilers. The
    // draws run z before x, the order the pinned scenes were made with.
    dvec3 radii;
    radii.z = random.uniform(0.3, 1.2);
    radii.y = random.uniform(0.3, 1.2);
    radii.x = random.uniform(0.3, 1.2);
    const double lift = std::max({radii.x, radii.y, radii.z}) * 0.8;
    dvec3 centre(0, lift, 0);
    centre.z = random.uniform(1, side - 1);
    centre.x = random.uniform(1, side - 1);
    const Rgba8 color = paletteColor(i, 0.5, 0.9);
    scene.beginMesh("object" + std::to_string(i));
    addGeodesicSphere(
        scene, K, [&](const dvec3& p) { return centre + turn * (radii * p); },
        [&](uint32_t f) { return shade(color, 0.75 + 0.25 * double(f % 2)); });
  }
  // From the middle of the near edge, at eye height, looking across the floor.
  const dvec3 eye(side / 2, 1.2, side + 2);
  scene.camera = perspectiveCamera(eye, eye + dvec3(0.1, -0.04, -1) * 10.0, 60, 0.25, 2 * side);
  return scene;
}

// N quads facing the camera at eye depths evenly spaced in [2, 10]. Each is 2.5 times as tall
// as the 60-degree view at its depth and 4 times as wide as tall, so every pixel of any image
// with an aspect ratio up to 4:1 (with a margin) sees all N. Submitted back to front, front to
// back or shuffled.
Scene makeLayers(const Args& args) {
  const auto n = uint32_t(args.integer("n"));
  const std::string& order = args.text("order");
  const double tanHalfFov = std::sqrt(3.0) / 3;  // tan(30 degrees)
  const double nearest = 2, farthest = 10;

  // Depth rank (0 = nearest) of each submitted layer.
  std::vector<uint32_t> ranks(n);
  std::iota(ranks.begin(), ranks.end(), 0u);
  if (order == "back-to-front") {
    std::reverse(ranks.begin(), ranks.end());
  } else if (order == "random") {
    // Fisher-Yates with our own portable index draw (std::shuffle varies between libraries).
    Random random(uint64_t(args.integer("seed")));
    for (uint32_t i = n; i > 1; --i) std::swap(ranks[i - 1], ranks[random.below(i)]);
  }

  Scene scene;
  reserve(scene, n, 4, size_t(4) * n);
  for (uint32_t rank : ranks) {
    const double depth = n > 1 ? nearest + (farthest - nearest) * rank / (n - 1) : nearest;
    const double halfY = 1.25 * tanHalfFov * depth, halfX = 4 * halfY;
    scene.beginMesh("layer" + std::to_string(rank));
    addPolygon(scene,
               {{-halfX, -halfY, -depth},
                {halfX, -halfY, -depth},
                {halfX, halfY, -depth},
                {-halfX, halfY, -depth}},
               paletteColor(rank));
  }
  scene.camera = perspectiveCamera({0, 0, 0}, {0, 0, -1}, 60, 1, 11);
  return scene;
}

// A city of blocks x blocks blocks, 60 m apart with 12 m streets between them; each block holds
// 2 x 2 lots with one box building each (random setbacks, mostly 6-40 m tall, some towers up to
// 150 m). The camera stands 1.7 m above a street crossing at the city's edge, looking down the
// middle avenue, turned 5 degrees towards the facades: nearly everything is hidden.
Scene makeCity(const Args& args) {
  const auto blocks = uint32_t(args.integer("blocks"));
  const double pitch = 60, street = 12, lot = (pitch - street) / 2, size = blocks * pitch;
  Random random(uint64_t(args.integer("seed")));
  Scene scene;
  reserve(scene, size_t(6) * 4 * blocks * blocks + 1, 4, size_t(8) * 4 * blocks * blocks + 4);

  // The ground, counter-clockwise seen from above, reaching one block pitch beyond the city.
  scene.beginMesh("ground");
  const double lo = -pitch, hi = size + pitch;
  addPolygon(scene, {{lo, 0, lo}, {lo, 0, hi}, {hi, 0, hi}, {hi, 0, lo}},
             Rgba8{105, 110, 100, 255});

  const dmat3 upright(1.0);
  uint64_t building = 0;
  for (uint32_t bz = 0; bz < blocks; ++bz)
    for (uint32_t bx = 0; bx < blocks; ++bx)
      for (int lotIndex = 0; lotIndex < 4; ++lotIndex) {
        const double x0 = bx * pitch + street / 2 + (lotIndex & 1) * lot;
        const double z0 = bz * pitch + street / 2 + (lotIndex >> 1) * lot;
        const double west = random.uniform(0.5, 4);
        const double east = random.uniform(0.5, 4);
        const double north = random.uniform(0.5, 4);
        const double south = random.uniform(0.5, 4);
        const double u = random.uniform();
        const bool tower = random.uniform() < 0.06;
        const double height = tower ? 50 + 100 * random.uniform() : 6 + 34 * u * u;
        const dvec3 lowCorner(x0 + west, 0, z0 + north),
            highCorner(x0 + lot - east, height, z0 + lot - south);
        scene.beginMesh("building" + std::to_string(building));
        const Rgba8 base = paletteColor(building++, 0.3, 0.85);
        addBox(scene, (lowCorner + highCorner) * 0.5, upright, (highCorner - lowCorner) * 0.5,
               [&](int k) { return shade(base, faceShade(k)); });
      }

  // Looking along -z down the avenue x = (blocks / 2) * pitch; the direction (-0.0875, 0, -1)
  // is turned 5 degrees to the left.
  const dvec3 eye((blocks / 2) * pitch, 1.7, size);
  scene.camera =
      perspectiveCamera(eye, eye + dvec3(-0.0875, 0, -1) * 100.0, 60, 0.25, 1.5 * size + 2 * pitch);
  return scene;
}

}  // namespace hsr::builtin

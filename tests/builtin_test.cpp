// Tests of the built-in scenes (src/scene/builtin*.cpp): counts documented in docs/scenes.md,
// determinism, spec parsing and errors, default cameras, and the visibility properties each
// scene exists to show (cyclic overlap, midpoint-sort failure, full-screen layers, z-fighting).
// Visibility is checked with a tiny independent point sampler over the projected triangles.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <hsr/builtin.hpp>
#include <hsr/camera.hpp>
#include <hsr/depth_format.hpp>
#include <map>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>

namespace hsr {
namespace {

const std::vector<std::string> kSceneNames = {"cubes",         "random",         "sphere",           "layers",
                                              "city",          "clutter",        "painter-midpoint", "painter-cycle",
                                              "interpenetrate", "glass", "zfight", "csg"};

// Each default scene is generated once per test run (the sphere has a million triangles).
const Scene& defaultScene(const std::string& name) {
  static std::map<std::string, Scene> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, makeBuiltin(name)).first;
  return it->second;
}

Camera defaultCamera(const Scene& scene, int width, int height) {
  return resolveCamera(*scene.camera, width, height, scene.bounds(), scene.source);
}

double cross2(dvec2 a, dvec2 b) { return a.x * b.y - a.y * b.x; }

// The scene's triangles projected by a camera, for point sampling at pixel positions.
class Projection {
 public:
  Projection(const Scene& scene, const Camera& camera) : byFace_(scene.faceCount()) {
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
      const Triangle& tri = scene.triangles[t];
      Screen s;
      for (int i = 0; i < 3; ++i) {
        const dvec4 h = camera.toPixelH(scene.positions[tri.v[i]]);
        s.inFront = s.inFront && h.z > camera.near;
        s.p[i] = dvec2(h.x, h.y) / h.w;
        s.invW[i] = 1 / h.w;
        s.depthOverW[i] = h.z / h.w;
        s.lo = glm::min(s.lo, s.p[i]);
        s.hi = glm::max(s.hi, s.p[i]);
      }
      triangles_.push_back(s);
      byFace_[tri.face].push_back(t);
    }
  }
  size_t triangleCount() const { return triangles_.size(); }

  /// Eye depth of triangle t at pixel position q (edges inclusive), or nothing where it does not
  /// cover q or reaches behind the near plane. Perspective-correct: depth/w and 1/w are affine
  /// in the image.
  std::optional<double> triangleDepthAt(uint32_t t, dvec2 q) const {
    const Screen& s = triangles_[t];
    if (!s.inFront || q.x < s.lo.x || q.y < s.lo.y || q.x > s.hi.x || q.y > s.hi.y)
      return std::nullopt;
    const dvec2* p = s.p;
    const double area = cross2(p[1] - p[0], p[2] - p[0]);
    if (area == 0) return std::nullopt;
    const double l0 = cross2(p[2] - p[1], q - p[1]) / area;
    const double l1 = cross2(p[0] - p[2], q - p[2]) / area;
    const double l2 = cross2(p[1] - p[0], q - p[0]) / area;
    if (l0 < 0 || l1 < 0 || l2 < 0) return std::nullopt;
    return (l0 * s.depthOverW[0] + l1 * s.depthOverW[1] + l2 * s.depthOverW[2]) /
           (l0 * s.invW[0] + l1 * s.invW[1] + l2 * s.invW[2]);
  }
  /// Eye depth of a face at q, or nothing where it does not cover q.
  std::optional<double> depthAt(uint32_t face, dvec2 q) const {
    for (uint32_t t : byFace_[face])
      if (auto d = triangleDepthAt(t, q)) return d;
    return std::nullopt;
  }

 private:
  struct Screen {
    dvec2 p[3];
    double invW[3], depthOverW[3];
    dvec2 lo{INFINITY}, hi{-INFINITY};
    bool inFront = true;
  };
  std::vector<Screen> triangles_;
  std::vector<std::vector<uint32_t>> byFace_;
};

dvec2 pixelCentre(int x, int y) { return {x + 0.5, y + 0.5}; }

uint64_t fnv1a(const void* data, size_t bytes, uint64_t hash = 1469598103934665603ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  return hash;
}

uint64_t geometryHash(const Scene& scene) {
  uint64_t h = fnv1a(scene.positions.data(), scene.positions.size() * sizeof(dvec3));
  h = fnv1a(scene.polygonIndices.data(), scene.polygonIndices.size() * sizeof(uint32_t), h);
  return fnv1a(scene.faceColors.data(), scene.faceColors.size() * sizeof(Rgba8), h);
}

std::string errorOf(const std::string& spec) {
  try {
    makeBuiltin(spec);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Signed volume enclosed by faces [first, first + count): positive when wound outwards.
double signedVolume(const Scene& scene, uint32_t firstFace, uint32_t faceCount) {
  double volume = 0;
  for (const Triangle& t : scene.triangles)
    if (t.face >= firstFace && t.face < firstFace + faceCount)
      volume += glm::dot(scene.positions[t.v[0]],
                         glm::cross(scene.positions[t.v[1]], scene.positions[t.v[2]])) /
                6;
  return volume;
}

TEST(Builtin, ListsEveryScene) {
  std::vector<std::string> listed;
  for (const auto& info : builtinScenes()) {
    listed.push_back(info.name);
    EXPECT_FALSE(info.summary.empty()) << info.name;
    for (const auto& p : info.params) {
      EXPECT_FALSE(p.help.empty()) << info.name << " " << p.name;
      // Every listed default is accepted when given explicitly.
      EXPECT_NO_THROW(makeBuiltin(info.name + "?" + p.name + "=" + p.defaultValue))
          << info.name << " " << p.name;
    }
  }
  EXPECT_EQ(listed, kSceneNames);
}

TEST(Builtin, DefaultScenesAreFinalizedAndWellFormed) {
  for (const auto& name : kSceneNames) {
    SCOPED_TRACE(name);
    const Scene& scene = defaultScene(name);
    EXPECT_EQ(scene.source, "builtin:" + name);
    ASSERT_GT(scene.faceCount(), 0u);
    EXPECT_EQ(scene.faceColors.size(), scene.faceCount());
    // Every face triangulated (fan count), faces in order.
    size_t expectedTriangles = 0;
    for (size_t f = 0; f < scene.faceCount(); ++f) expectedTriangles += scene.face(f).size() - 2;
    ASSERT_EQ(scene.triangles.size(), expectedTriangles);
    EXPECT_EQ(scene.problems.degenerateFaces, 0u);
    EXPECT_EQ(scene.problems.nonPlanarFaces, 0u);
    EXPECT_EQ(scene.problems.concaveFaces, 0u);
    // Meshes cover all faces, contiguously, none empty.
    uint32_t next = 0;
    for (const auto& mesh : scene.meshes) {
      EXPECT_EQ(mesh.firstFace, next) << mesh.name;
      EXPECT_GT(mesh.faceCount, 0u) << mesh.name;
      next += mesh.faceCount;
    }
    EXPECT_EQ(next, scene.faceCount());
    for (const dvec3& p : scene.positions)
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    for (uint32_t index : scene.polygonIndices) ASSERT_LT(index, scene.positions.size());
    ASSERT_TRUE(scene.camera.has_value());
    EXPECT_EQ(scene.camera->kind, CameraSpec::Kind::OpenGL);
    ASSERT_TRUE(scene.camera->near && scene.camera->far);
    EXPECT_LT(*scene.camera->near, *scene.camera->far);
  }
}

// The figures of docs/scenes.md.
TEST(Builtin, DefaultCountsMatchTheDocs) {
  struct Counts {
    size_t faces, triangles, meshes, vertices;
  };
  const std::map<std::string, Counts> expected = {
      {"cubes", {24, 48, 4, 32}},
      {"random", {5000, 5000, 1, 15000}},
      {"sphere", {1003520, 1003520, 1, 501762}},
      {"layers", {64, 128, 64, 256}},
      {"city", {21601, 43202, 3601, 28804}},
      {"clutter", {392001, 392002, 401, 196804}},
      {"painter-midpoint", {2, 4, 2, 8}},
      {"painter-cycle", {3, 6, 3, 12}},
      {"interpenetrate", {2, 4, 2, 8}},
      {"glass", {6, 12, 6, 24}},
      {"zfight", {2, 4, 2, 8}},
      {"csg", {2886, 2892, 2, 1450}},
  };
  for (const auto& name : kSceneNames) {
    SCOPED_TRACE(name);
    const Scene& scene = defaultScene(name);
    const Counts& c = expected.at(name);
    EXPECT_EQ(scene.faceCount(), c.faces);
    EXPECT_EQ(scene.triangles.size(), c.triangles);
    EXPECT_EQ(scene.meshes.size(), c.meshes);
    EXPECT_EQ(scene.positions.size(), c.vertices);
  }
}

TEST(Builtin, SameSpecSameScene) {
  for (const std::string spec :
       {"cubes", "random", "layers?order=random", "city?blocks=4", "sphere?n=5000", "clutter?n=20&detail=3",
        "painter-midpoint", "painter-cycle", "interpenetrate", "zfight"}) {
    const Scene a = makeBuiltin(spec), b = makeBuiltin(spec);
    EXPECT_EQ(a.positions, b.positions) << spec;
    EXPECT_EQ(a.polygonIndices, b.polygonIndices) << spec;
    EXPECT_EQ(a.faceColors, b.faceColors) << spec;
  }
}

// Pinned checksums of the seeded scenes: the scenes must be bit-identical on every platform
// and across versions (benchmarks compare them). A change here means the scene changed:
// update docs/scenes.md and say so.
TEST(Builtin, SeededScenesArePinned) {
  EXPECT_EQ(geometryHash(defaultScene("random")), 3501254398163597264u);
  EXPECT_EQ(geometryHash(defaultScene("city")), 3790000146779425316u);
  EXPECT_EQ(geometryHash(makeBuiltin("clutter?n=50&detail=4")), 549254748427486164u);
  EXPECT_EQ(geometryHash(makeBuiltin("layers?order=random&n=50&seed=3")), 7258602076706724509u);
}

TEST(Builtin, SeedChangesTheScene) {
  EXPECT_NE(makeBuiltin("random?seed=1&n=100").positions,
            makeBuiltin("random?seed=2&n=100").positions);
  EXPECT_NE(makeBuiltin("city?seed=1&blocks=3").positions,
            makeBuiltin("city?seed=2&blocks=3").positions);
  EXPECT_NE(makeBuiltin("layers?order=random&seed=1").positions,
            makeBuiltin("layers?order=random&seed=2").positions);
  // A prefix of a longer random scene is the shorter one: n only adds triangles.
  const Scene few = makeBuiltin("random?n=10"), many = makeBuiltin("random?n=20");
  EXPECT_TRUE(std::equal(few.positions.begin(), few.positions.end(), many.positions.begin()));
}

TEST(Builtin, ParsesParameters) {
  const Scene random = makeBuiltin("random?n=50&seed=7&size=0.3&");
  EXPECT_EQ(random.faceCount(), 50u);
  EXPECT_EQ(random.source, "builtin:random?n=50&seed=7&size=0.3&");
  // Size scales the triangles: every corner within size x box height of the centroid.
  for (size_t f = 0; f < random.faceCount(); ++f) {
    const auto face = random.face(f);
    const dvec3 c =
        (random.positions[face[0]] + random.positions[face[1]] + random.positions[face[2]]) / 3.0;
    for (uint32_t v : face) EXPECT_LE(glm::length(random.positions[v] - c), 2 * 0.3 * 2);
  }

  // Sphere: 20 k^2 triangles, k nearest to the target.
  EXPECT_EQ(makeBuiltin("sphere?n=1").triangles.size(), 20u);
  EXPECT_EQ(makeBuiltin("sphere?n=80").triangles.size(), 80u);
  EXPECT_EQ(makeBuiltin("sphere?n=100").triangles.size(), 80u);
  EXPECT_EQ(makeBuiltin("sphere?n=150").triangles.size(), 180u);
  EXPECT_EQ(makeBuiltin("sphere?n=5000").positions.size(), 10u * 16 * 16 + 2);

  EXPECT_EQ(makeBuiltin("city?blocks=2").faceCount(), 2u * 2 * 4 * 6 + 1);
  EXPECT_EQ(makeBuiltin("layers?n=1").faceCount(), 1u);

  // Layer order: eye depth (-z) of each face's first vertex, in submission order.
  const auto depths = [](const Scene& s) {
    std::vector<double> d;
    for (size_t f = 0; f < s.faceCount(); ++f) d.push_back(-s.positions[s.face(f)[0]].z);
    return d;
  };
  const auto backToFront = depths(makeBuiltin("layers?n=5"));
  const auto frontToBack = depths(makeBuiltin("layers?n=5&order=front-to-back"));
  EXPECT_EQ(frontToBack, (std::vector<double>{2, 4, 6, 8, 10}));
  EXPECT_EQ(backToFront, (std::vector<double>{10, 8, 6, 4, 2}));
  auto shuffled = depths(makeBuiltin("layers?n=40&order=random&seed=5"));
  EXPECT_FALSE(std::is_sorted(shuffled.begin(), shuffled.end()));
  std::sort(shuffled.begin(), shuffled.end());
  EXPECT_EQ(shuffled, depths(makeBuiltin("layers?n=40&order=front-to-back")));

  // zfight: the front polygon is the back one's plane scaled towards the eye by 1 - gap: undoing
  // the scaling puts its corners back on the back polygon's plane.
  const Scene z = makeBuiltin("zfight?gap=0.01");
  const dvec3 eye = z.camera->eye;
  const auto corner = [&](uint32_t face, int i) { return z.positions[z.face(face)[i]]; };
  const dvec3 backNormal = glm::cross(corner(0, 1) - corner(0, 0), corner(0, 2) - corner(0, 0));
  for (int i = 0; i < 4; ++i) {
    const dvec3 unscaled = eye + (corner(1, i) - eye) / 0.99;
    EXPECT_NEAR(glm::dot(unscaled - corner(0, 0), glm::normalize(backNormal)), 0, 1e-12);
  }
}

TEST(Builtin, BadSpecsThrowClearErrors) {
  EXPECT_EQ(errorOf("teapot"),
            "builtin:teapot: unknown built-in scene (known: cubes, random, sphere, layers, city, clutter, "
            "painter-midpoint, painter-cycle, interpenetrate, glass, zfight, csg)");
  EXPECT_EQ(errorOf("random?x=1"), "builtin:random: unknown parameter 'x' (known: n, seed, size)");
  EXPECT_EQ(errorOf("cubes?seed=1"),
            "builtin:cubes: unknown parameter 'seed' (known: this scene has none)");
  EXPECT_EQ(errorOf("random?n=abc"),
            "builtin:random: bad value 'abc' for 'n' (expected an integer in 1..50000000)");
  EXPECT_EQ(errorOf("random?n"), "builtin:random: parameter 'n' needs a value (n=...)");
  EXPECT_EQ(errorOf("random?n=5&n=6"), "builtin:random: parameter 'n' given twice");
  EXPECT_EQ(errorOf("layers?order=sideways"),
            "builtin:layers: bad value 'sideways' for 'order' (expected one of back-to-front, "
            "front-to-back, random)");
  EXPECT_EQ(errorOf("zfight?gap=-1"),
            "builtin:zfight: bad value '-1' for 'gap' (expected a number in [0, 0.5])");
  // Out of range, malformed, non-finite or absurd values.
  for (const std::string spec : {"random?n=0",
                                 "random?n=-5",
                                 "random?n=1.5",
                                 "random?n=",
                                 "random?n=50000001",
                                 "random?n=99999999999999999999",
                                 "random?n= 5",
                                 "random?size=0",
                                 "random?size=nan",
                                 "random?size=inf",
                                 "random?size=1e400",
                                 "random?seed=-1",
                                 "sphere?n=60000000",
                                 "layers?n=100001",
                                 "city?blocks=1001",
                                 "city?blocks=0",
                                 "zfight?gap=0x1",
                                 "",
                                 "?n=5",
                                 "random?=5"}) {
    const std::string message = errorOf(spec);
    EXPECT_EQ(message.rfind("builtin:", 0), 0u) << spec << ": " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << spec;
  }
}

TEST(Builtin, DefaultCameraSeesTheBoundsCentre) {
  for (const auto& name : kSceneNames) {
    SCOPED_TRACE(name);
    const Scene& scene = defaultScene(name);
    const Camera camera = defaultCamera(scene, 64, 48);
    const dvec4 h = camera.toPixelH(scene.bounds().center());
    ASSERT_GT(h.w, 0);
    EXPECT_GE(h.x / h.w, 0);
    EXPECT_LE(h.x / h.w, 64);
    EXPECT_GE(h.y / h.w, 0);
    EXPECT_LE(h.y / h.w, 48);
    EXPECT_GT(h.z, camera.near);
    EXPECT_LT(h.z, camera.far);
  }
}

// Small scenes lie wholly in the default view; layers and zfight overfill it sideways but stay
// between the clipping planes. (The city's ground reaches behind the camera, as streets do.)
TEST(Builtin, FigureScenesFitTheirDefaultView) {
  for (const std::string name : {"cubes", "random", "painter-midpoint", "painter-cycle",
                                 "interpenetrate", "layers", "zfight", "sphere", "csg"}) {
    SCOPED_TRACE(name);
    const Scene& scene = defaultScene(name);
    const Camera camera = defaultCamera(scene, 64, 48);
    const bool lateral = name != "layers" && name != "zfight";
    for (const dvec3& p : scene.positions) {
      const dvec4 h = camera.toPixelH(p);
      ASSERT_GT(h.z, camera.near);
      ASSERT_LT(h.z, camera.far);
      if (lateral) {
        ASSERT_TRUE(h.x / h.w > 0 && h.x / h.w < 64 && h.y / h.w > 0 && h.y / h.w < 48)
            << p.x << " " << p.y << " " << p.z;
      }
    }
  }
  EXPECT_EQ(makeBuiltin("random?size=1").positions.size(), 15000u);
  const Scene big = makeBuiltin("random?size=1&n=500");
  const Camera camera = defaultCamera(big, 64, 48);
  for (const dvec3& p : big.positions) {
    ASSERT_GT(camera.toCamera(p).z, camera.near);
    ASSERT_LT(camera.toCamera(p).z, camera.far);
  }
}

TEST(Builtin, ClosedMeshesWindOutwards) {
  const Scene& cubes = defaultScene("cubes");
  for (const auto& mesh : cubes.meshes)
    EXPECT_GT(signedVolume(cubes, mesh.firstFace, mesh.faceCount), 0.1) << mesh.name;
  const Scene city = makeBuiltin("city?blocks=3");
  for (const auto& mesh : city.meshes)
    if (mesh.name != "ground") {
      EXPECT_GT(signedVolume(city, mesh.firstFace, mesh.faceCount), 1) << mesh.name;
    }

  for (const char* op : {"difference", "intersection", "union", "mixed"}) {
    const Scene csg = makeBuiltin(std::string("csg?op=") + op);
    for (const auto& mesh : csg.meshes) EXPECT_GT(signedVolume(csg, mesh.firstFace, mesh.faceCount), 0.1) << mesh.name;
  }

  const Scene clutter = makeBuiltin("clutter?n=30&detail=3");
  for (const auto& mesh : clutter.meshes)
    if (mesh.name != "floor") {
      EXPECT_GT(signedVolume(clutter, mesh.firstFace, mesh.faceCount), 0.01) << mesh.name;
    }

  // The sphere: every triangle faces outwards, every edge is shared by exactly two triangles in
  // opposite directions (watertight), and the volume approaches 4/3 pi.
  const Scene sphere = makeBuiltin("sphere?n=2000");
  std::map<std::pair<uint32_t, uint32_t>, int> directedEdges;
  for (const Triangle& t : sphere.triangles) {
    const dvec3 a = sphere.positions[t.v[0]], b = sphere.positions[t.v[1]],
                c = sphere.positions[t.v[2]];
    ASSERT_GT(glm::dot(glm::cross(b - a, c - a), a + b + c), 0);
    for (int e = 0; e < 3; ++e) ++directedEdges[{t.v[e], t.v[(e + 1) % 3]}];
  }
  for (const auto& [edge, count] : directedEdges) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(directedEdges.count({edge.second, edge.first}), 1u);
  }
  for (const dvec3& p : sphere.positions) ASSERT_NEAR(glm::length(p), 1.0, 1e-15);
  const double volume = signedVolume(sphere, 0, uint32_t(sphere.faceCount()));
  EXPECT_LT(volume, 4.0 / 3 * std::numbers::pi);  // inscribed
  EXPECT_GT(volume, 0.99 * 4.0 / 3 * std::numbers::pi);
}

// Flat scenes face their default camera (counter-clockwise as seen = negative area with y down).
TEST(Builtin, FlatScenesFaceTheCamera) {
  for (const std::string name :
       {"layers", "painter-midpoint", "painter-cycle", "interpenetrate", "zfight"}) {
    const Scene& scene = defaultScene(name);
    const Camera camera = defaultCamera(scene, 64, 48);
    for (size_t f = 0; f < scene.faceCount(); ++f) {
      double area = 0;
      const auto face = scene.face(f);
      for (size_t i = 0; i < face.size(); ++i) {
        const dvec4 a = camera.toPixelH(scene.positions[face[i]]);
        const dvec4 b = camera.toPixelH(scene.positions[face[(i + 1) % face.size()]]);
        area += cross2(dvec2(a) / a.w, dvec2(b) / b.w);
      }
      EXPECT_LT(area, 0) << name << " face " << f;
    }
  }
}

// For faces a and b of `scene`, over a 160x120 grid of pixel centres: how often each is nearer
// where both cover the pixel.
struct Overlap {
  int aNearer = 0, bNearer = 0;
};
Overlap overlap(const Scene& scene, uint32_t a, uint32_t b) {
  const Projection projection(scene, defaultCamera(scene, 160, 120));
  Overlap result;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      const auto da = projection.depthAt(a, pixelCentre(x, y));
      const auto db = projection.depthAt(b, pixelCentre(x, y));
      if (da && db) ++(*da < *db ? result.aNearer : result.bNearer);
    }
  return result;
}

TEST(Builtin, PainterCycleIsACycle) {
  const Scene& scene = defaultScene("painter-cycle");
  // Bar i is over bar i+1 wherever they overlap, for all three pairs: a cycle without any
  // intersection (the same one is in front at every shared pixel).
  for (uint32_t i = 0; i < 3; ++i) {
    const Overlap o = overlap(scene, i, (i + 1) % 3);
    EXPECT_GT(o.aNearer, 20) << "bar " << i;
    EXPECT_EQ(o.bNearer, 0) << "bar " << i;
  }
}

TEST(Builtin, PainterMidpointDefeatsAMidpointSort) {
  const Scene& scene = defaultScene("painter-midpoint");
  const Camera camera = defaultCamera(scene, 160, 120);
  const auto centroidDepth = [&](uint32_t f) {
    dvec3 sum(0);
    for (uint32_t v : scene.face(f)) sum += scene.positions[v];
    return camera.toCamera(sum / double(scene.face(f).size())).z;
  };
  const uint32_t square = 0, bar = 1;
  EXPECT_GT(centroidDepth(bar), centroidDepth(square) + 0.5);  // a midpoint sort draws it first
  const Overlap o = overlap(scene, bar, square);
  EXPECT_GT(o.aNearer, 50);  // ... yet it is in front wherever they overlap
  EXPECT_EQ(o.bNearer, 0);
}

TEST(Builtin, InterpenetratingQuadsAreEachInFrontSomewhere) {
  const Overlap o = overlap(defaultScene("interpenetrate"), 0, 1);
  EXPECT_GT(o.aNearer, 100);
  EXPECT_GT(o.bNearer, 100);
}

// Does segment pq cross triangle abc (interior)? Moeller-Trumbore.
bool segmentCrossesTriangle(dvec3 p, dvec3 q, dvec3 a, dvec3 b, dvec3 c) {
  const dvec3 dir = q - p, e1 = b - a, e2 = c - a;
  const dvec3 s = glm::cross(dir, e2);
  const double det = glm::dot(e1, s);
  if (std::abs(det) < 1e-15) return false;
  const dvec3 t = p - a;
  const double u = glm::dot(t, s) / det;
  const dvec3 r = glm::cross(t, e1);
  const double v = glm::dot(dir, r) / det, along = glm::dot(e2, r) / det;
  return u >= 0 && v >= 0 && u + v <= 1 && along >= 0 && along <= 1;
}

// Random triangles in general position intersect when an edge of one crosses the other.
TEST(Builtin, RandomTrianglesIntersectEachOther) {
  const Scene& scene = defaultScene("random");
  const size_t n = scene.faceCount();
  std::vector<std::array<dvec3, 3>> tri(n);
  for (size_t f = 0; f < n; ++f)
    for (int i = 0; i < 3; ++i) tri[f][i] = scene.positions[scene.face(f)[i]];
  const auto cross = [&](size_t f, size_t g) {
    for (int e = 0; e < 3; ++e)
      if (segmentCrossesTriangle(tri[f][e], tri[f][(e + 1) % 3], tri[g][0], tri[g][1], tri[g][2]) ||
          segmentCrossesTriangle(tri[g][e], tri[g][(e + 1) % 3], tri[f][0], tri[f][1], tri[f][2]))
        return true;
    return false;
  };
  // Only triangles whose bounding boxes overlap can meet: sweep along x.
  std::vector<Bounds3> box(n);
  for (size_t f = 0; f < n; ++f)
    for (const dvec3& p : tri[f]) box[f].add(p);
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return box[a].lo.x < box[b].lo.x; });
  std::vector<char> intersects(n, 0);
  size_t pairs = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n && box[order[j]].lo.x <= box[order[i]].hi.x; ++j) {
      const size_t f = order[i], g = order[j];
      const bool boxesOverlap = box[f].lo.y <= box[g].hi.y && box[g].lo.y <= box[f].hi.y &&
                                box[f].lo.z <= box[g].hi.z && box[g].lo.z <= box[f].hi.z;
      if (boxesOverlap && cross(f, g)) {
        ++pairs;
        intersects[f] = intersects[g] = 1;
      }
    }
  const auto intersecting = size_t(std::count(intersects.begin(), intersects.end(), 1));
  // docs/scenes.md: 39,340 intersecting pairs; every triangle intersects at least one other.
  EXPECT_GT(pairs, 39000u);
  EXPECT_LT(pairs, 39700u);
  EXPECT_EQ(intersecting, n);
}

TEST(Builtin, CubesPartlyOccludeEachOther) {
  const Scene& scene = defaultScene("cubes");
  const Projection projection(scene, defaultCamera(scene, 160, 120));
  std::set<uint32_t> visible, partlyHidden;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      // Nearest cube at this pixel, and the cubes behind it.
      std::map<double, uint32_t> hits;
      for (uint32_t f = 0; f < scene.faceCount(); ++f)
        if (auto d = projection.depthAt(f, pixelCentre(x, y))) hits.emplace(*d, f / 6);
      if (hits.empty()) continue;
      visible.insert(hits.begin()->second);
      for (const auto& [depth, cube] : hits)
        if (cube != hits.begin()->second) partlyHidden.insert(cube);
    }
  EXPECT_EQ(visible.size(), 4u);
  EXPECT_GE(partlyHidden.size(), 2u);
}

TEST(Builtin, LayersCoverEveryPixelNTimes) {
  for (const std::string spec : {"layers", "layers?n=7&order=random"}) {
    const Scene& scene = spec == "layers" ? defaultScene("layers") : makeBuiltin(spec);
    for (const auto& [width, height] : {std::pair{64, 48}, std::pair{256, 64}, std::pair{48, 64}}) {
      const Projection projection(scene, defaultCamera(scene, width, height));
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
          size_t covering = 0;
          for (uint32_t f = 0; f < scene.faceCount(); ++f)
            covering += projection.depthAt(f, pixelCentre(x, y)).has_value();
          ASSERT_EQ(covering, scene.faceCount())
              << spec << " " << width << "x" << height << " pixel " << x << "," << y;
        }
    }
  }
}

// With the default camera (near 0.1, far 1000) a 16-bit z-buffer cannot separate the surfaces
// over most of the overlap (ties: the back face, drawn first, wins), while f32:reversed and u24
// separate them everywhere, in the right order.
TEST(Builtin, ZfightFightsAtSixteenBitsOnly) {
  const Scene& scene = defaultScene("zfight");
  const Camera camera = defaultCamera(scene, 160, 120);
  const Projection projection(scene, camera);
  const DepthFormat u16 = DepthFormat::parse("u16:z"), u24 = DepthFormat::parse("u24:z"),
                    f32 = DepthFormat::parse("f32:reversed");
  const auto stored = [&](const DepthFormat& format, double depth) {
    return format.quantize(format.map(depth, camera.near, camera.far, false));
  };
  int both = 0, u16Ties = 0, u16Right = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      const auto back = projection.depthAt(0, pixelCentre(x, y));
      const auto front = projection.depthAt(1, pixelCentre(x, y));
      if (!back || !front) continue;
      ++both;
      EXPECT_NEAR(*front / *back, 1 - 1e-4, 1e-9);
      if (stored(u16, *front) == stored(u16, *back))
        ++u16Ties;
      else if (stored(u16, *front) < stored(u16, *back))
        ++u16Right;
      ASSERT_LT(stored(u24, *front), stored(u24, *back)) << x << "," << y;
      ASSERT_GT(stored(f32, *front), stored(f32, *back)) << x << "," << y;
    }
  EXPECT_GT(both, 1500);
  EXPECT_GT(u16Ties, both / 2);  // mostly wrong ...
  EXPECT_GT(u16Right, 0);        // ... in bands: it fights rather than losing uniformly
}

TEST(Builtin, CityHidesMostBuildings) {
  const Scene& scene = defaultScene("city");
  // The eye stands in a street: outside every building.
  for (const auto& mesh : scene.meshes) {
    if (mesh.name == "ground") continue;
    Bounds3 box;
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f)
      for (uint32_t v : scene.face(f)) box.add(scene.positions[v]);
    const dvec3 eye = scene.camera->eye;
    ASSERT_FALSE(eye.x >= box.lo.x && eye.x <= box.hi.x && eye.z >= box.lo.z && eye.z <= box.hi.z)
        << mesh.name;
  }
  EXPECT_DOUBLE_EQ(scene.camera->eye.y, 1.7);
  // Buildings visible at a 16x12 grid of samples: few of 3600. (Triangles reaching behind the
  // near plane, such as the ground's, are left out: that only makes more buildings visible.)
  const Projection projection(scene, defaultCamera(scene, 64, 48));
  std::vector<uint32_t> meshOfFace(scene.faceCount());
  for (uint32_t m = 0; m < scene.meshes.size(); ++m)
    for (uint32_t f = 0; f < scene.meshes[m].faceCount; ++f)
      meshOfFace[scene.meshes[m].firstFace + f] = m;
  std::set<uint32_t> seen;
  for (int y = 0; y < 48; y += 4)
    for (int x = 0; x < 64; x += 4) {
      double nearest = INFINITY;
      uint32_t nearestMesh = 0;
      for (uint32_t t = 0; t < projection.triangleCount(); ++t)
        if (auto d = projection.triangleDepthAt(t, pixelCentre(x, y)); d && *d < nearest) {
          nearest = *d;
          nearestMesh = meshOfFace[scene.triangles[t].face];
        }
      if (nearestMesh != 0) seen.insert(nearestMesh);
    }
  EXPECT_GT(seen.size(), 3u);
  EXPECT_LT(seen.size(), 200u);
}

}  // namespace
}  // namespace hsr

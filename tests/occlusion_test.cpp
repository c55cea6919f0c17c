// The occlusion buffer (include/hsr/occlusion.hpp): its stored values are the z-buffer's bit for
// bit (those of the scalar reference's winning triangles, every depth format, 1 and 2 threads,
// reused buffers); its depth image is its stored values' eye depths; rectVisible agrees with a pixel-by-pixel check of
// the stored values on random rectangles and depths, and with what the scenes' geometry says.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <random>
#include <vector>

#include "core/depth_map.hpp"
#include "frontend/frontend.hpp"
#include "frontend/mesh_bounds.hpp"
#include "frontend/triangle_setup.hpp"
#include "setup/fragment_depth.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

using test::firstDifference;

std::vector<DepthFormat> everyFormat() {
  std::vector<DepthFormat> formats;
  for (const char* s : {"u16", "u24", "u32", "f32"})
    for (const char* m : {"z", "reversed", "inv", "linear"}) formats.push_back(DepthFormat::parse(std::string(s) + ":" + m));
  return formats;
}

Camera cameraFor(const Scene& scene, int w, int h, int pose) {
  CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
  if (pose > 0) {  // off to one side, nearer: triangles cross tiles at other angles, some clipped
    const Bounds3 b = scene.bounds();
    const double r = glm::length(b.hi - b.lo) * 0.5;
    spec = test::lookAt(b.center() + dvec3(0.9 * r, 0.5 * r * pose, 1.1 * r), b.center(), 60, r * 0.05, r * 4);
    if (pose == 2) spec.orthoHeight = r * 1.5;
  }
  return resolveCamera(spec, w, h, scene.bounds());
}

// The scalar reference z-buffer's frame with triangle ids.
Frame referenceFrame(const Scene& scene, const Camera& cam, DepthFormat format) {
  RenderOptions o;
  o.depthFormat = format;
  setRaster(o, RasterKind::HalfSpace);
  o.outputs = FrameOutputs::TriangleIds;
  o.threads = 1;
  return render(scene, cam, o);
}

// The stored value where nothing was drawn.
double storedClear(DepthFormat f) {
  double q = 0;
  visitDepthFormat(f, [&]<DepthStorage S, DepthMapping>() { q = double(quantizeDepth<S>(f.clearValue())); });
  return q;
}

// What the z-buffer stores at pixel (x, y) for set-up triangle t (the drawing service's bits).
double storedOfFragment(DepthFormat f, const Camera& cam, const SetupTriangle& t, int x, int y) {
  double q = 0;
  visitDepthFormat(f, [&]<DepthStorage S, DepthMapping M>() {
    const MappedPlanes m = mapPlanes<M>(t.depthNum, t.depthDen, cam.near, cam.far, cam.orthographic);
    q = fragmentStored<S>(m, x + 0.5, m.p.b * (y + 0.5), m.q.b * (y + 0.5));
  });
  return q;
}

// Each scene triangle's set-up triangles: one, or the pieces clipping made of it, or none.
std::vector<std::vector<const SetupTriangle*>> setUpByTriangle(const Scene& scene, const std::vector<SetupTriangle>& all) {
  std::vector<std::vector<const SetupTriangle*>> of(scene.triangles.size());
  for (const SetupTriangle& t : all) of[t.triangle].push_back(&t);
  return of;
}

// "stored value a is nearer than b" in the format's direction.
bool nearer(DepthFormat f, double a, double b) {
  return f.greaterWins() ? a > b : a < b;
}

double storedOfEye(DepthFormat f, const Camera& cam, double eye) {
  double q = 0;
  visitDepthFormat(f, [&]<DepthStorage S, DepthMapping M>() {
    q = double(quantizeDepth<S>(mapDepth<M>(eye, cam.near, cam.far, cam.orthographic)));
  });
  return q;
}

double eyeOfStored(DepthFormat f, const Camera& cam, double stored) {
  double eye = 0;
  visitDepthFormat(f, [&]<DepthStorage S, DepthMapping M>() {
    eye = eyeDepthOfStored<S, M>(stored, cam.near, cam.far, cam.orthographic);
  });
  return eye;
}

const char* kScenes[] = {"builtin:cubes",         "builtin:layers?n=16", "builtin:random?n=1500",
                         "builtin:sphere?n=8000", "builtin:zfight",      "builtin:interpenetrate",
                         "builtin:city"};

// One buffer reused across scenes, sizes and formats (stale tiles of a bigger earlier frame must
// not show), 1 and 2 threads: every stored value is the one the reference z-buffer's winning
// triangle stores there (for a triangle clipped into pieces, one of the pieces': counted), the
// background is the clear value, and the depth image is the stored values' eye depths.
TEST(Occlusion, StoredValuesAreTheZBuffersOnEverySceneFormatAndThreadCount) {
  OcclusionBuffer buffer;
  int compared = 0;
  uint64_t pixels = 0, ofPieces = 0;
  for (const char* name : kScenes) {
    const Scene scene = loadScene(name);
    for (int pose = 0; pose < 3; ++pose)
      for (auto [w, h] : {std::pair{200, 150}, std::pair{333, 97}}) {
        const Camera cam = cameraFor(scene, w, h, pose);
        for (const DepthFormat& format : everyFormat()) {
          const Frame reference = referenceFrame(scene, cam, format);
          RenderOptions feOptions;
          feOptions.depthFormat = format;
          FrontEndOutput fe;
          runFrontEnd(scene, cam, feOptions, fe);
          const std::vector<SetupTriangle> all = fe.flatten();
          const std::vector<std::vector<const SetupTriangle*>> setUp = setUpByTriangle(scene, all);
          const double clear = storedClear(format);
          for (int threads : {1, 2}) {
            const std::string what = fmt::format("{} pose {} {}x{} {} threads {}", name, pose, w, h, format.name(), threads);
            const Stats& st = buffer.render(scene, cam, {format, Cull::None, threads});
            EXPECT_EQ(st.algorithm, "occlusion");
            EXPECT_LE(st.depth_tests, reference.stats.depth_tests) << what;
            Frame image;
            buffer.depthImage(image);
            ++compared;
            ASSERT_TRUE(image.faceId.empty() && image.color.empty()) << what;
            EXPECT_EQ(image.stats.covered_pixels, reference.stats.covered_pixels) << what;
            for (int y = 0; y < h; ++y)
              for (int x = 0; x < w; ++x) {
                const double stored = buffer.storedAt(x, y);
                const int32_t winner = reference.triangleId[reference.index(x, y)];
                if (winner < 0) {
                  ASSERT_EQ(stored, clear) << what << " pixel " << x << "," << y;
                  ASSERT_TRUE(std::isinf(image.depth[image.index(x, y)])) << what << " pixel " << x << "," << y;
                  continue;
                }
                const float eye = image.depth[image.index(x, y)];
                if (!std::isinf(eye))  // (a stored value may map to infinity: inv's 0)
                  ASSERT_EQ(float(eyeOfStored(format, cam, stored)), eye) << what << " pixel " << x << "," << y;
                const std::vector<const SetupTriangle*>& pieces = setUp[size_t(winner)];
                ASSERT_FALSE(pieces.empty()) << what << " triangle " << winner << " won without being set up";
                ++pixels;
                ofPieces += pieces.size() > 1;
                bool same = false;
                for (const SetupTriangle* piece : pieces) same |= stored == storedOfFragment(format, cam, *piece, x, y);
                ASSERT_TRUE(same) << what << " pixel " << x << "," << y << " triangle " << winner << ": stored "
                                  << stored << ", the triangle's " << storedOfFragment(format, cam, *pieces[0], x, y);
              }
          }
        }
      }
  }
  RecordProperty("pixels_compared", int(pixels));
  RecordProperty("pixels_of_clipped_triangles", int(ofPieces));
  EXPECT_GT(pixels - ofPieces, 5000000u) << "millions of pixels are won by whole triangles";
  EXPECT_EQ(compared, 7 * 3 * 2 * 16 * 2);
}

// rectVisible against the stored values pixel by pixel: random rectangles (some partly or wholly
// outside the image, some a single pixel) and depths, half of them exactly a stored value's eye
// depth, so that ties (equal is not visible) are met.
TEST(Occlusion, RectVisibleAgreesWithThePixels) {
  OcclusionBuffer buffer;
  std::mt19937_64 rng(7);
  int visible = 0, hidden = 0;
  for (const char* name : kScenes) {
    const Scene scene = loadScene(name);
    for (const char* fmtName : {"f32:reversed", "u16:z", "u24:inv", "u32:linear", "f32:z"}) {
      const DepthFormat format = DepthFormat::parse(fmtName);
      const int w = 300, h = 170;
      const Camera cam = cameraFor(scene, w, h, int(rng() % 3));
      buffer.render(scene, cam, {format, Cull::None, 2});
      for (int i = 0; i < 300; ++i) {
        const int size = i % 3 == 0 ? 1 : int(rng() % 140) + 1;
        const int x0 = int(rng() % (w + 40)) - 20, y0 = int(rng() % (h + 40)) - 20;
        const int x1 = x0 + int(rng() % size), y1 = y0 + int(rng() % size);
        double eye;
        if (i % 2 == 0) {
          const int px = std::clamp(x0, 0, w - 1), py = std::clamp(y0, 0, h - 1);
          eye = eyeOfStored(format, cam, buffer.storedAt(px, py));
        } else {
          eye = cam.near * 0.5 + double(rng() % 1000) / 1000.0 * (cam.far * 1.2 - cam.near * 0.5);
        }
        const double q = storedOfEye(format, cam, eye);
        bool expected = false;
        for (int y = std::max(y0, 0); y <= std::min(y1, h - 1) && !expected; ++y)
          for (int x = std::max(x0, 0); x <= std::min(x1, w - 1) && !expected; ++x)
            expected = nearer(format, q, buffer.storedAt(x, y));
        ASSERT_EQ(buffer.rectVisible(x0, y0, x1, y1, eye), expected)
            << name << " " << fmtName << " rect [" << x0 << ", " << x1 << "] x [" << y0 << ", " << y1 << "] eye depth "
            << eye;
        ++(expected ? visible : hidden);
      }
    }
  }
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(visible, 1000);
  EXPECT_GT(hidden, 1000);
}

// What the geometry says: behind the nearest of the stacked full-screen layers nothing shows;
// in front of it, everything; an empty buffer hides nothing nearer than the far plane.
TEST(Occlusion, LayersHideWhatIsBehindThem) {
  const Scene layers = loadScene("builtin:layers?n=8");
  const Camera cam = cameraFor(layers, 256, 192, 0);
  OcclusionBuffer buffer;
  buffer.render(layers, cam);
  double nearest = std::numeric_limits<double>::infinity(), farthest = 0;
  Frame image;
  buffer.depthImage(image);
  for (float d : image.depth) {
    ASSERT_TRUE(std::isfinite(d)) << "the layers cover the whole image";
    nearest = std::min(nearest, double(d));
    farthest = std::max(farthest, double(d));
  }
  EXPECT_FALSE(buffer.rectVisible(0, 0, 255, 191, farthest * 1.01));
  EXPECT_FALSE(buffer.rectVisible(-100, -100, 1000, 1000, cam.far));
  EXPECT_TRUE(buffer.rectVisible(0, 0, 255, 191, nearest * 0.99));
  EXPECT_TRUE(buffer.rectVisible(100, 100, 100, 100, nearest * 0.99));
  EXPECT_FALSE(buffer.rectVisible(300, 0, 400, 10, nearest * 0.99)) << "outside the image";
  EXPECT_FALSE(buffer.rectVisible(10, 10, 9, 20, nearest * 0.99)) << "empty rectangle";

  Scene empty;
  empty.finalize();
  buffer.render(empty, cam);
  EXPECT_TRUE(buffer.rectVisible(0, 0, 0, 0, cam.far * 0.99));
  EXPECT_TRUE(buffer.rectVisible(0, 0, 255, 191, cam.near));
  EXPECT_EQ(buffer.width(), 256);
}

// boxVisible is conservative: a box whose faces, drawn after the occluders by the z-buffer, win
// any pixel is reported visible (every format); and it is useful: most boxes that win nothing
// are reported hidden. Boxes at random over and around the occluders, some crossing the near
// plane, some beyond the far plane, some thin.
TEST(Occlusion, BoxVisibleNeverHidesAVisibleBox) {
  std::mt19937_64 rng(11);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  int shown = 0, hiddenTruth = 0, hiddenReported = 0;
  for (const char* name : {"builtin:layers?n=4", "builtin:city", "builtin:cubes"}) {
    const Scene occluders = loadScene(name);
    const Bounds3 b = occluders.bounds();
    const Camera cam = cameraFor(occluders, 160, 120, 0);
    for (const char* f : {"f32:reversed", "u16:z", "u24:inv", "u32:linear"}) {
      const DepthFormat format = DepthFormat::parse(f);
      OcclusionBuffer buffer;
      buffer.render(occluders, cam, {format, Cull::None, 1});
      for (int i = 0; i < 40; ++i) {
        const dvec3 size = (b.hi - b.lo) * dvec3(0.02 + 0.2 * u(), 0.02 + 0.2 * u(), i % 7 == 0 ? 0.0 : 0.02 + 0.2 * u());
        const dvec3 lo = b.lo - (b.hi - b.lo) * 0.3 + (b.hi - b.lo) * 1.6 * dvec3(u(), u(), u());
        Scene scene = occluders;
        scene.beginMesh("box");
        test::addBox(scene, lo, lo + size, {255, 255, 255, 255});
        scene.finalize();
        RenderOptions o;
        o.depthFormat = format;
        o.outputs = FrameOutputs::IdsAndDepth;
        o.threads = 1;
        const Frame frame = render(scene, cam, o);
        const int firstBoxFace = int(occluders.faceCount());
        bool truth = false;
        for (int32_t id : frame.faceId) truth |= id >= firstBoxFace;
        Bounds3 box;
        box.add(lo);
        box.add(lo + size);
        const bool reported = buffer.boxVisible(box);
        if (truth) {
          ++shown;
          ASSERT_TRUE(reported) << name << " " << f << " box " << lo.x << "," << lo.y << "," << lo.z << " size " << size.x
                                << "," << size.y << "," << size.z << " shows but was reported hidden";
        } else {
          ++hiddenTruth;
          hiddenReported += !reported;
        }
      }
    }
  }
  RecordProperty("shown", shown);
  RecordProperty("hidden", hiddenTruth);
  RecordProperty("hidden_reported", hiddenReported);
  EXPECT_GT(shown, 50);
  EXPECT_GT(hiddenTruth, 50);
  EXPECT_GT(hiddenReported * 2, hiddenTruth) << "most hidden boxes are found hidden";
}

// The city moved far from the origin (coordinates near 2e5: the planes' offsets and the eye's
// dot products lose digits to rounding, which the bounds' slack must cover).
Scene movedCity() {
  Scene scene = loadScene("builtin:city");
  const dvec3 offset(1e5, 3e3, -2e5);
  for (dvec3& p : scene.positions) p += offset;
  if (scene.camera) scene.camera->eye += offset, scene.camera->target += offset;
  scene.source = "city moved";
  scene.finalize();
  return scene;
}

// Turned boxes whose vertices are stored in reverse order: each mesh's vertices still its own,
// but the ranges descend, so Scene::meshVerticesApart is false and mesh culling transforms every
// vertex up front.
Scene reversedVertices(int n, uint64_t seed) {
  const Scene boxes = test::rotatedBoxes(n, seed);
  Scene scene;
  scene.source = "test:reversed-vertices";
  scene.positions.assign(boxes.positions.rbegin(), boxes.positions.rend());
  const uint32_t last = uint32_t(boxes.positions.size()) - 1;
  for (const MeshRange& mesh : boxes.meshes) {
    scene.beginMesh(mesh.name);
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f) {
      std::vector<uint32_t> indices;
      for (uint32_t v : boxes.face(f)) indices.push_back(last - v);
      scene.addFace(indices, boxes.faceColors[f]);
    }
  }
  scene.finalize();
  return scene;
}

TEST(Occlusion, MeshVertexRanges) {
  const Scene city = loadScene("builtin:city");
  EXPECT_TRUE(city.meshVerticesApart);
  for (const MeshRange& mesh : city.meshes)
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f)
      for (uint32_t v : city.face(f)) ASSERT_TRUE(v >= mesh.firstVertex && v < mesh.firstVertex + mesh.vertexCount);
  EXPECT_TRUE(test::rotatedBoxes(50, 3).meshVerticesApart);
  EXPECT_FALSE(reversedVertices(50, 3).meshVerticesApart);
  Scene shared;  // two meshes sharing an edge
  shared.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  shared.beginMesh("a");
  shared.addFace({0, 1, 2}, Rgba8{});
  shared.beginMesh("b");
  shared.addFace({0, 2, 3}, Rgba8{});
  shared.finalize();
  EXPECT_FALSE(shared.meshVerticesApart);
}

// Cameras for the mesh culling tests: the scene's own, then seeded random perspective poses
// looking in from around it, some from inside its box, with wide and narrow lenses.
std::vector<Camera> meshCameras(const Scene& scene, int w, int h, int random, uint64_t seed) {
  std::vector<Camera> list{cameraFor(scene, w, h, 0), cameraFor(scene, w, h, 1)};
  const Bounds3 b = scene.bounds();
  const dvec3 c = b.center();
  const double r = glm::length(b.hi - b.lo) * 0.5;
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int i = 0; i < random; ++i) {
    const double z = u() * 2 - 1, phi = u() * 2 * M_PI, sz = std::sqrt(1 - z * z);
    const dvec3 eye = c + dvec3(sz * std::cos(phi), z, sz * std::sin(phi)) * (r * (0.1 + 2 * u()));
    const dvec3 target = c + dvec3(u() - 0.5, u() - 0.5, u() - 0.5) * r;
    list.push_back(resolveCamera(test::lookAt(eye, target, 20 + 80 * u(), r * 0.002, r * 5), w, h, b));
  }
  return list;
}

// meshBounds (the occlusion buffer's mesh culling, several meshes at once with SIMD; meshBound,
// one at a time, gives the same): for every mesh it bounds, every triangle is inside the clip
// volume and its own set-up (setupTriangle) lies in the mesh's pixel box with a nearest bound no
// nearer than the mesh's, in every depth format; a mesh found Outside has no triangle that
// covers a pixel centre. Box buildings (city) and turned boxes, walls and slivers
// (rotatedBoxes), seen from many sides.
TEST(Occlusion, MeshBoundHoldsForEveryTriangle) {
  size_t bounded = 0, outside = 0, triangles = 0;
  for (const Scene& scene : {loadScene("builtin:city"), test::rotatedBoxes(400, 5), movedCity()})
    for (auto [w, h] : {std::pair{256, 160}, std::pair{1920, 1080}})
      for (const Camera& cam : meshCameras(scene, w, h, 6, 23)) {
        FrontEndOutput fe;
        runVertexPass(scene, cam, RenderOptions{}, fe);
        for (const DepthFormat& format : everyFormat()) {
          const DepthSetup depth{format, cam.near, cam.far, cam.orthographic};
          const MeshView view = meshView(cam, depth);
          const bool greater = format.greaterWins();
          std::vector<MeshTest> tests(scene.meshes.size());
          std::vector<MeshBound> bounds(scene.meshes.size());
          meshBounds(scene, 0, scene.meshes.size(), view, tests.data(), bounds.data());
          for (size_t m = 0; m < scene.meshes.size(); ++m) {
            MeshBound b;
            const MeshTest test = meshBound(scene, m, view, b);  // (one mesh at a time: the same)
            ASSERT_EQ(test, tests[m]) << "mesh " << m;
            if (test == MeshTest::Bounded)
              ASSERT_TRUE(b.minX == bounds[m].minX && b.maxX == bounds[m].maxX && b.minY == bounds[m].minY &&
                          b.maxY == bounds[m].maxY && b.zMin == bounds[m].zMin && b.nearest == bounds[m].nearest)
                  << "mesh " << m;
            if (test == MeshTest::None) continue;
            ++(test == MeshTest::Bounded ? bounded : outside);
            const MeshRange& mesh = scene.meshes[m];
            for (uint32_t i = mesh.firstTriangle; i < mesh.firstTriangle + mesh.triangleCount; ++i) {
              const Triangle& t = scene.triangles[i];
              ProjectedVertex v[3];
              for (int j = 0; j < 3; ++j) {
                ASSERT_EQ(fe.outcodes[t.v[j]], 0) << "mesh " << m << " triangle " << i;
                v[j] = fe.projected[t.v[j]];
              }
              SetupTriangle st;
              FrontEndCounters counters;
              if (!setupTriangle(v, i, t.face, cam, Cull::None, counters, st)) continue;
              ASSERT_EQ(test, MeshTest::Bounded) << "mesh " << m << " was found outside but triangle " << i << " draws";
              ++triangles;
              EXPECT_TRUE(st.minX >= b.minX && st.maxX <= b.maxX && st.minY >= b.minY && st.maxY <= b.maxY)
                  << "mesh " << m << " triangle " << i;
              const double own = nearestStored(st, depth);
              ASSERT_TRUE(greater ? own <= b.nearest : own >= b.nearest)
                  << fmt::format("mesh {} triangle {} {}: own nearest {} mesh's {}", m, i, format.name(), own, b.nearest);
            }
          }
        }
      }
  RecordProperty("bounded", int(bounded));
  RecordProperty("outside", int(outside));
  RecordProperty("triangles", int(triangles));
  EXPECT_GT(bounded, 50000u);
  EXPECT_GT(outside, 1000u);
  EXPECT_GT(triangles, 500000u);
}

// Mesh culling changes no stored value: the occlusion buffer with it (the default) and without
// (the switch mesh-culling off) stores the same bits at every pixel, culling back faces or not, in
// several formats, on 1 and 2 threads, whether each pass transforms only its meshes' vertices
// or all are transformed up front (reversedVertices); and it does cull (the city's hidden
// buildings).
TEST(Occlusion, MeshCullingChangesNoStoredValue) {
  uint64_t culled = 0, passes = 0;
  int compared = 0;
  for (const Scene& scene : {loadScene("builtin:city"), test::rotatedBoxes(400, 9), movedCity(), reversedVertices(400, 9),
                             loadScene("builtin:clutter?n=80&detail=4")})
    for (const Camera& cam : meshCameras(scene, 320, 200, 4, 31))
      for (const char* f : {"f32:reversed", "u16:z", "u24:inv", "u32:linear", "f32:z"})
        for (Cull cull : {Cull::None, Cull::Back})
          for (int threads : {1, 2}) {
            const DepthFormat format = DepthFormat::parse(f);
            const std::string what = fmt::format("{} {} cull {} threads {}", scene.source, f, int(cull), threads);
            OcclusionBuffer without, with;
            const Stats plain = without.render(scene, cam, {format, cull, threads, {.meshCulling = false}});
            const Stats& st = with.render(scene, cam, {format, cull, threads});
            EXPECT_FALSE(plain.detailCount("meshes_culled_occlusion").has_value()) << what;
            culled += st.detailCount("meshes_culled_occlusion").value_or(0);
            passes += st.detailCount("occlusion_passes").value_or(0) > 1;
            ++compared;
            for (int y = 0; y < cam.height; ++y)
              for (int x = 0; x < cam.width; ++x)
                ASSERT_EQ(with.storedAt(x, y), without.storedAt(x, y)) << what << " pixel " << x << "," << y;
          }
  RecordProperty("meshes_culled", int(culled));
  EXPECT_EQ(compared, 5 * 6 * 5 * 2 * 2);
  EXPECT_GT(passes, 50u);
  EXPECT_GT(culled, 10000u);
}

// render()'s depth-only frames of scenes with many meshes go through an occlusion buffer with
// mesh culling: the same depth bits as the reference's depth-only frame, 1 and 2 threads.
TEST(Occlusion, DepthOnlyRenderWithMeshCullingIsTheReference) {
  uint64_t culled = 0;
  for (const Scene& scene : {loadScene("builtin:city"), test::rotatedBoxes(1000, 13)})
    for (const Camera& cam : meshCameras(scene, 320, 200, 3, 41))
      for (const char* f : {"f32:reversed", "u16:z", "u24:inv"})
        for (Cull cull : {Cull::None, Cull::Back}) {
          const DepthFormat format = DepthFormat::parse(f);
          RenderOptions o;
          o.depthFormat = format;
          o.cull = cull;
          o.outputs = FrameOutputs::DepthOnly;
          setRaster(o, RasterKind::HalfSpace);
          o.threads = 1;
          const Frame reference = render(scene, cam, o);
          setRaster(o, RasterKind::Tiled);
          for (int threads : {1, 2}) {
            o.threads = threads;
            const Frame frame = render(scene, cam, o);
            const std::string what = fmt::format("{} {} cull {} threads {}", scene.source, f, int(cull), threads);
            const long at = firstDifference(reference.depth, frame.depth);
            ASSERT_EQ(at, -1) << what << " at pixel " << at;
            EXPECT_EQ(frame.stats.covered_pixels, reference.stats.covered_pixels) << what;
            EXPECT_EQ(frame.stats.algorithm, "zbuffer") << what;
            culled += frame.stats.detailCount("meshes_culled_occlusion").value_or(0);
          }
        }
  EXPECT_GT(culled, 1000u) << "the depth-only frames went through mesh culling";
}

// Quads facing the camera in pairs of meshes that tie: mesh 2k holds a quad, mesh 2k + 1 the
// same quad and a small triangle far nearer, elsewhere (so that it is drawn in mesh culling's
// first pass, and its twin is tested against it). Each twin's fragments equal what the first pass
// stored there, and the first submitted wins a tie: the earlier mesh shows. Behind them a wall of
// 8192 triangles (render() culls meshes for frames of 8192 triangles or more).
Scene tiedQuads(int pairs, uint64_t seed) {
  Scene s;
  s.source = "test:tied-quads";
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  auto quad = [&](dvec3 lo, double w, double h, Rgba8 color) {
    const uint32_t b = uint32_t(s.positions.size());
    s.positions.push_back(lo);
    s.positions.push_back(lo + dvec3(w, 0, 0));
    s.positions.push_back(lo + dvec3(w, h, 0));
    s.positions.push_back(lo + dvec3(0, h, 0));
    s.addFace({b, b + 1, b + 2, b + 3}, color);
  };
  for (int k = 0; k < pairs; ++k) {
    const double z = -5 - 5 * u();
    const dvec3 lo{(u() * 2 - 1) * 2.5, (u() * 2 - 1) * 1.8, z};
    const double w = 0.2 + 0.6 * u(), h = 0.2 + 0.6 * u();
    const Rgba8 color{uint8_t(rng()), uint8_t(rng()), uint8_t(rng()), 255};
    s.beginMesh("quad " + std::to_string(k));
    quad(lo, w, h, color);
    s.beginMesh("twin " + std::to_string(k));
    quad(lo, w, h, color);
    const uint32_t b = uint32_t(s.positions.size());
    const dvec3 c{(u() * 2 - 1) * 0.5, (u() * 2 - 1) * 0.4, -1 - 0.001 * k};
    s.positions.push_back(c);
    s.positions.push_back(c + dvec3(0.01, 0, 0));
    s.positions.push_back(c + dvec3(0, 0.01, 0));
    s.addFace({b, b + 1, b + 2}, color);
  }
  s.beginMesh("wall");
  constexpr int kCells = 64;
  for (int i = 0; i < kCells; ++i)
    for (int j = 0; j < kCells; ++j)
      quad(dvec3(-12 + 24.0 * i / kCells, -8 + 16.0 * j / kCells, -20), 24.0 / kCells, 16.0 / kCells,
           Rgba8{uint8_t(4 * i), uint8_t(4 * j), 90, 255});
  s.finalize();
  return s;
}

// render()'s frames with ids of scenes with many meshes go through mesh culling (a depth-only
// first pass, then the frame of the meshes not found hidden): every buffer is the same bits as
// with mesh culling off — face and triangle ids, colour and depth — for box buildings, turned
// boxes, vertices in reverse order and quads that tie with their twins (where dropping a mesh
// behind values equal to its bound would show the later twin); and rounded objects, which mesh
// culling cannot bound (the frame then draws no first pass).
TEST(Occlusion, FramesWithIdsAndMeshCullingAreTheSameBits) {
  uint64_t culled = 0, culledTied = 0;
  int compared = 0;
  std::vector<Scene> scenes;
  scenes.push_back(tiedQuads(400, 17));
  scenes.push_back(loadScene("builtin:city"));
  scenes.push_back(test::rotatedBoxes(1000, 13));
  scenes.push_back(reversedVertices(1000, 7));
  scenes.push_back(loadScene("builtin:clutter?n=80&detail=4"));
  ASSERT_GE(scenes[0].triangles.size(), 8192u);
  for (const Scene& scene : scenes) {
    const bool tied = &scene == &scenes[0];
    std::vector<Camera> cams =
        tied ? std::vector<Camera>{resolveCamera(test::lookAt(dvec3(0), dvec3(0, 0, -1), 60, 0.5, 50), 320, 200,
                                                 scene.bounds())}
             : meshCameras(scene, 320, 200, 2, 43);
    if (scene.source == "builtin:city") cams.push_back(cameraFor(scene, 1920, 1080, 0));  // (many tiles, both threads)
    for (const Camera& cam : cams)
      for (const char* f : {"f32:reversed", "u16:z", "u24:inv", "f32:z"})
        for (Cull cull : {Cull::None, Cull::Back})
          for (int threads : {1, 2}) {
            RenderOptions o;
            o.depthFormat = DepthFormat::parse(f);
            o.cull = cull;
            o.threads = threads;
            const std::string what = fmt::format("{} {} cull {} threads {}", scene.source, f, int(cull), threads);
            o.tiled.meshCulling = false;
            const Frame plain = render(scene, cam, o);
            o.tiled.meshCulling = true;
            const Frame frame = render(scene, cam, o);
            EXPECT_FALSE(plain.stats.detailCount("meshes_culled_occlusion").has_value()) << what;
            (tied ? culledTied : culled) += frame.stats.detailCount("meshes_culled_occlusion").value_or(0);
            if (scene.source.starts_with("builtin:clutter"))  // (curved meshes: no bound, so no first pass)
              EXPECT_EQ(frame.stats.detailCount("occlusion_passes"), 1u) << what;
            ++compared;
            ASSERT_EQ(firstDifference(plain.faceId, frame.faceId), -1) << what;
            ASSERT_EQ(firstDifference(plain.triangleId, frame.triangleId), -1) << what;
            ASSERT_EQ(firstDifference(plain.color, frame.color), -1) << what;
            ASSERT_EQ(firstDifference(plain.depth, frame.depth), -1) << what;
            EXPECT_EQ(frame.stats.covered_pixels, plain.stats.covered_pixels) << what;
          }
  }
  RecordProperty("meshes_culled", int(culled));
  RecordProperty("tied_meshes_culled", int(culledTied));
  EXPECT_EQ(compared, (1 + 4 * 4 + 1) * 4 * 2 * 2);
  EXPECT_GT(culled, 1000u) << "the frames went through mesh culling";
  EXPECT_GT(culledTied, 0u) << "some quads were found hidden";
}

TEST(Occlusion, BadUseIsAClearError) {
  OcclusionBuffer buffer;
  EXPECT_THROW(buffer.rectVisible(0, 0, 1, 1, 1.0), InputError);
  EXPECT_THROW(buffer.storedAt(0, 0), InputError);
  EXPECT_THROW(buffer.boxVisible(Bounds3{}), InputError);
  Frame frame;
  EXPECT_THROW(buffer.depthImage(frame), InputError);
  const Scene scene = loadScene("builtin:cubes");
  Camera cam = cameraFor(scene, 64, 48, 0);
  buffer.render(scene, cam);
  EXPECT_THROW(buffer.rectVisible(0, 0, 1, 1, std::nan("")), InputError);
  Bounds3 nanBox;
  nanBox.lo = dvec3(0, std::nan(""), 0);
  nanBox.hi = dvec3(1, 1, 1);
  EXPECT_THROW(buffer.boxVisible(nanBox), InputError);
  EXPECT_THROW(buffer.storedAt(64, 0), InputError);
  EXPECT_THROW(buffer.storedAt(0, -1), InputError);
  Camera huge = cam;
  huge.width = 0;
  EXPECT_THROW(buffer.render(scene, huge), InputError);
  EXPECT_EQ(buffer.width(), 0) << "a failed render leaves nothing to query";
  EXPECT_THROW(buffer.rectVisible(0, 0, 1, 1, 1.0), InputError);
}

}  // namespace
}  // namespace hsr

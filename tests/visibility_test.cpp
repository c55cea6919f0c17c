// instanceVisibility (include/hsr/visibility.hpp): each instance's pixels covered alone equal the
// covered pixels of rendering its faces alone, and its visible pixels those of the frame, on
// built-in scenes, several cameras (one cutting the scene with its near plane), culling, instances
// of several meshes apart, and 1 or 2 threads; a VisibilityCounter kept from view to view counts
// as a fresh one; the CLI's --visibility-json.
#include <hsr/visibility.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>

#include "cli_runner.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

// The scene's own camera, two others around it, and one whose near plane cuts the scene.
std::vector<Camera> camerasFor(const Scene& scene, int width, int height) {
  const Bounds3 b = scene.bounds();
  const CameraSpec own = scene.camera ? *scene.camera : frameBounds(b);
  std::vector<Camera> cameras{resolveCamera(own, width, height, b)};
  const double r = std::max(1e-3, glm::length(b.hi - b.lo));
  for (int i = 0; i < 2; ++i) {
    CameraSpec spec;
    spec.target = b.center();
    spec.eye = b.center() + dvec3(r * std::cos(2.0 + 2.5 * i), 0.4 * r, r * std::sin(2.0 + 2.5 * i));
    cameras.push_back(resolveCamera(spec, width, height, b));
  }
  CameraSpec cut;
  cut.target = b.center();
  cut.eye = b.center() + dvec3(0.3 * r, 0.3 * r, 0.9 * r);
  cut.near = glm::length(cut.eye - cut.target) * 0.95;  // just before the centre: slices through objects
  cut.far = 4 * r;
  cameras.push_back(resolveCamera(cut, width, height, b));
  return cameras;
}

// Pixels showing a face in a render of the faces of `meshes` alone.
uint64_t coveredAlone(const Scene& scene, const std::vector<size_t>& meshes, const Camera& camera,
                      const RenderOptions& options) {
  std::vector<FaceRange> pieces;
  for (size_t m : meshes) pieces.push_back({scene.meshes[m].firstFace, scene.meshes[m].faceCount});
  const SceneRange part = extractFaces(scene, pieces);
  const Frame frame = render(part.scene, camera, options);
  uint64_t covered = 0;
  for (int32_t f : frame.faceId) covered += f >= 0;
  return covered;
}

// What the views of checkScene held: pixels covered but hidden, triangles clipped at near or far.
struct Checked {
  uint64_t hidden = 0, clipped = 0;
};

// Every instance's counts against renders of it alone and against the frame, for `faceInstance`
// given per mesh by instanceOfMesh.
Checked checkScene(const Scene& scene, const std::function<int32_t(size_t)>& instanceOfMesh, Cull cull,
                    int width, int height) {
  std::vector<int32_t> faceInstance(scene.faceCount(), -1);
  std::map<int32_t, std::vector<size_t>> meshesOf;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const int32_t id = instanceOfMesh(m);
    if (scene.meshes[m].faceCount == 0) continue;
    meshesOf[id].push_back(m);
    std::fill_n(faceInstance.begin() + scene.meshes[m].firstFace, scene.meshes[m].faceCount, id);
  }
  Checked checked;
  const std::vector<Camera> cameras = camerasFor(scene, width, height);
  for (size_t c = 0; c < cameras.size(); ++c) {
    std::vector<InstanceVisibility> first;
    for (int threads : {1, 2}) {
      RenderOptions options;
      options.threads = threads;
      options.cull = cull;
      options.outputs = FrameOutputs::FaceIds;
      const Frame frame = render(scene, cameras[c], options);
      const std::vector<InstanceVisibility> v = instanceVisibility(scene, cameras[c], options, frame, faceInstance);
      EXPECT_EQ(v.size(), meshesOf.size());
      if (v.size() != meshesOf.size()) return checked;
      if (threads == 1) checked.clipped += frame.stats.triangles_clipped;
      if (threads == 1) first = v;
      size_t k = 0;
      for (const auto& [id, meshes] : meshesOf) {
        const std::string where = scene.source + ", camera " + std::to_string(c) + ", instance " +
                                  std::to_string(id) + ", threads " + std::to_string(threads);
        EXPECT_EQ(v[k].instance, id) << where;
        EXPECT_EQ(v[k].pixelsAlone, coveredAlone(scene, meshes, cameras[c], options)) << where;
        uint64_t visible = 0;
        for (int32_t f : frame.faceId) visible += f >= 0 && faceInstance[size_t(f)] == id;
        EXPECT_EQ(v[k].pixelsVisible, visible) << where;
        EXPECT_LE(v[k].pixelsVisible, v[k].pixelsAlone) << where;
        EXPECT_EQ(v[k].pixelsVisible, first[k].pixelsVisible) << where;
        EXPECT_EQ(v[k].pixelsAlone, first[k].pixelsAlone) << where;
        if (threads == 1) checked.hidden += v[k].pixelsAlone - v[k].pixelsVisible;
        ++k;
      }
    }
  }
  return checked;
}

TEST(InstanceVisibility, EachInstanceEqualsItsRenderAloneOnBuiltinScenes) {
  for (const char* spec : {"cubes", "clutter?n=12&detail=3", "city?blocks=2", "glass", "painter-cycle"}) {
    const Scene scene = makeBuiltin(spec);
    ASSERT_GT(scene.meshes.size(), 1u) << spec;
    // Occlusion in the views (instances cover pixels they do not show, so the two counts differ),
    // and the near plane cuts triangles.
    const Checked checked = checkScene(scene, [](size_t m) { return int32_t(m); }, Cull::None, 160, 120);
    EXPECT_GT(checked.hidden, 0u) << spec;
    EXPECT_GT(checked.clipped, 0u) << spec;
  }
}

TEST(InstanceVisibility, BackFaceCullingIsTheRendersToo) {
  for (const char* spec : {"cubes", "clutter?n=8&detail=4"})
    checkScene(makeBuiltin(spec), [](size_t m) { return int32_t(m); }, Cull::Back, 128, 96);
}

TEST(InstanceVisibility, InstancesOfSeveralMeshesApartCountEachPixelOnce) {
  // Meshes m, m + 3, m + 6, ... make one instance: they interleave in submission order and overlap.
  const Scene scene = makeBuiltin("clutter?n=14&detail=3");
  checkScene(scene, [](size_t m) { return int32_t(100 + 7 * (m % 3)); }, Cull::None, 160, 120);
}

TEST(InstanceVisibility, ACounterKeptFromViewToViewCountsAsAFreshOne) {
  const Scene scene = makeBuiltin("clutter?n=10&detail=3");
  for (const bool apart : {false, true}) {  // instances of one mesh each, or of meshes apart
    std::vector<int32_t> faceInstance = faceMeshIndices(scene);
    if (apart)
      for (int32_t& id : faceInstance) id %= 3;
    VisibilityCounter counter(scene, faceInstance);
    int view = 0;
    for (const auto [width, height] : {std::pair{160, 120}, {64, 48}, {200, 150}, {160, 120}}) {
      for (const Camera& camera : camerasFor(scene, width, height)) {
        RenderOptions options;
        options.threads = 1 + view++ % 2;
        const Frame frame = render(scene, camera, options);
        const std::vector<InstanceVisibility> kept = counter.count(camera, options, frame);
        const std::vector<InstanceVisibility> fresh = instanceVisibility(scene, camera, options, frame, faceInstance);
        ASSERT_EQ(kept.size(), fresh.size());
        for (size_t i = 0; i < kept.size(); ++i) {
          EXPECT_EQ(kept[i].instance, fresh[i].instance);
          EXPECT_EQ(kept[i].pixelsAlone, fresh[i].pixelsAlone) << "view " << view << ", instance " << i;
          EXPECT_EQ(kept[i].pixelsVisible, fresh[i].pixelsVisible);
        }
      }
    }
  }
}

TEST(InstanceVisibility, FacesOfNoInstanceAreLeftOut) {
  const Scene scene = makeBuiltin("cubes");
  const Camera camera = resolveCamera(*scene.camera, 96, 72, scene.bounds());
  RenderOptions options;
  const Frame frame = render(scene, camera, options);
  std::vector<int32_t> faceInstance(scene.faceCount(), -1);
  faceInstance[0] = 5;
  const std::vector<InstanceVisibility> v = instanceVisibility(scene, camera, options, frame, faceInstance);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].instance, 5);
  const SceneRange part = extractFaces(scene, std::vector<FaceRange>{{0, 1}});
  uint64_t alone = 0, visible = 0;
  for (int32_t f : render(part.scene, camera, options).faceId) alone += f >= 0;
  for (int32_t f : frame.faceId) visible += f == 0;
  EXPECT_GT(alone, 0u);
  EXPECT_EQ(v[0].pixelsAlone, alone);
  EXPECT_EQ(v[0].pixelsVisible, visible);
}

TEST(InstanceVisibility, OutOfViewIsZeroAndItsFractionToo) {
  const Scene scene = makeBuiltin("cubes");
  CameraSpec away;
  away.eye = scene.bounds().center();
  away.target = away.eye + dvec3(0, 0, 1) * 1e6;  // looking away from most of the scene
  away.eye = away.eye + dvec3(0, 0, 1) * 1e3;
  const Camera camera = resolveCamera(away, 64, 48, scene.bounds());
  RenderOptions options;
  const Frame frame = render(scene, camera, options);
  const std::vector<InstanceVisibility> v =
      instanceVisibility(scene, camera, options, frame, faceMeshIndices(scene));
  ASSERT_EQ(v.size(), scene.meshes.size());
  for (const InstanceVisibility& i : v) {
    EXPECT_EQ(i.pixelsAlone, 0u);
    EXPECT_EQ(i.pixelsVisible, 0u);
    EXPECT_EQ(i.fraction(), 0.0);
  }
}

TEST(InstanceVisibility, RefusesIdsOrFramesThatDoNotFit) {
  const Scene scene = makeBuiltin("cubes");
  const Camera camera = resolveCamera(*scene.camera, 32, 24, scene.bounds());
  RenderOptions options;
  options.outputs = FrameOutputs::DepthOnly;
  const Frame depthOnly = render(scene, camera, options);
  EXPECT_THROW(instanceVisibility(scene, camera, options, depthOnly, faceMeshIndices(scene)), std::invalid_argument);
  options.outputs = FrameOutputs::FaceIds;
  const Frame frame = render(scene, camera, options);
  const std::vector<int32_t> short_(scene.faceCount() - 1, 0);
  EXPECT_THROW(instanceVisibility(scene, camera, options, frame, short_), std::invalid_argument);
}

// hsr render --visibility-json: the library's counts per mesh, the same file for any thread count,
// written with the other outputs or not at all, and bad paths refused before rendering.
class VisibilityJson : public test::CliTest {};

TEST_F(VisibilityJson, HoldsTheLibrarysCountsPerMesh) {
  const std::string scene = "'builtin:clutter?n=6&detail=3'";
  ASSERT_EQ(hsr("render " + scene + " --size 160x120 --threads 1 -q --visibility-json v1.json").status, 0);
  ASSERT_EQ(hsr("render " + scene + " --size 160x120 --threads 2 -q --visibility-json v2.json").status, 0);
  EXPECT_EQ(test::readText(file("v1.json")), test::readText(file("v2.json")));

  const Scene s = makeBuiltin("clutter?n=6&detail=3");
  const Camera camera = resolveCamera(*s.camera, 160, 120, s.bounds());
  const RenderOptions options;
  const std::vector<InstanceVisibility> v =
      instanceVisibility(s, camera, options, render(s, camera, options), faceMeshIndices(s));
  const nlohmann::json j = nlohmann::json::parse(test::readText(file("v1.json")));
  EXPECT_EQ(j["width"], 160);
  EXPECT_EQ(j["height"], 120);
  ASSERT_EQ(j["instances"].size(), s.meshes.size());
  for (size_t m = 0; m < s.meshes.size(); ++m) {
    const nlohmann::json& e = j["instances"][m];
    EXPECT_EQ(e["instance_id"], int(m));
    EXPECT_EQ(e["mesh"], s.meshes[m].name);
    EXPECT_EQ(e["px_count_all"], v[m].pixelsAlone);
    EXPECT_EQ(e["px_count_visib"], v[m].pixelsVisible);
    EXPECT_EQ(e["visib_fract"], v[m].fraction());
  }
}

TEST_F(VisibilityJson, BadPathsAndOutputsAreRefused) {
  std::filesystem::create_directory(file("adir"));
  for (const std::string flags : {"--visibility-json ''", "--visibility-json adir", "--outputs depth --visibility-json v.json",
                                  "--visibility-json v.json --stats v.json"}) {
    const test::CliResult r = hsr("render builtin:cubes --size 32x24 " + flags);
    EXPECT_EQ(r.status, 2) << flags << "\n" << r;
    EXPECT_TRUE(r.oneErrorLine()) << r;
    EXPECT_NE(r.err.find("--visibility-json"), std::string::npos) << r;
    EXPECT_FALSE(std::filesystem::exists(file("v.json")));
  }
  // A file that cannot be created: exit 1, and no output written.
  const test::CliResult r = hsr("render builtin:cubes --size 32x24 -o c.png --visibility-json missing/v.json");
  EXPECT_EQ(r.status, 1) << r;
  EXPECT_FALSE(std::filesystem::exists(file("c.png")));
}

}  // namespace
}  // namespace hsr

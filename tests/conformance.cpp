// The conformance harness (conformance.hpp).
#include "conformance.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "test_scenes.hpp"

namespace hsr::conformance {

std::vector<Pose> posesAround(const Scene& scene, int count, uint64_t seed) {
  Bounds3 b = scene.bounds();
  dvec3 c = b.center();
  double r = glm::length(b.hi - b.lo) * 0.5;
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  std::vector<Pose> poses;
  for (int i = 0; i < count; ++i) {
    double z = u() * 2 - 1, phi = u() * 2 * M_PI, s = std::sqrt(1 - z * z);
    dvec3 dir{s * std::cos(phi), z, s * std::sin(phi)};
    double dist = r * (0.4 + 2.6 * u());  // sometimes inside the bounds: near clipping
    Pose p;
    p.spec.eye = c + dir * dist;
    p.spec.target = c + dvec3(u() - 0.5, u() - 0.5, u() - 0.5) * r * 0.5;
    p.spec.up = glm::normalize(dvec3(u() - 0.5, 2, u() - 0.5));
    p.spec.fovyDeg = 25 + 70 * u();
    double eyeDist = glm::length(p.spec.eye - c);
    p.spec.near = std::max(r * 0.01, (eyeDist - r) * (0.5 + 0.6 * u()));  // cuts into the scene at times
    p.spec.far = (eyeDist + r) * (0.7 + 0.5 * u());                         // and at times cuts off its back
    if (i % 7 == 3) p.spec.orthoHeight = r * (1 + u());
    poses.push_back(p);
  }
  return poses;
}

Pose ownPose(const Scene& scene) { return {scene.camera ? *scene.camera : frameBounds(scene.bounds())}; }

Scene load(const std::string& name) {
  if (name == "test:boxes") return test::boxesScene();
  if (name == "test:soup") return test::randomSoup(200, 42);
  if (name == "test:polygons") return test::randomPolygons(60, 11);
  return loadScene(name);
}

std::string Variant::describe() const {
  std::string out = algorithm->name;
  for (const auto& [k, v] : params) out += " " + k + "=" + v;
  return out;
}

std::vector<Variant> variantsOf(const AlgorithmInfo& algorithm) {
  std::vector<Variant> list{{&algorithm, {}}};
  for (const ParamSpec& p : algorithm.params) {
    std::vector<std::string> values = p.choices;
    if (p.type == ParamType::Bool) values = {"on", "off"};
    for (const std::string& v : values)
      if (v != p.defaultValue && !(p.type == ParamType::Bool && (v == "on") == (p.defaultValue == "on")))
        list.push_back({&algorithm, {{p.name, v}}});
  }
  return list;
}

namespace {

}  // namespace

VariantRenderer::VariantRenderer(const Variant& variant, const Scene& scene)
    : variant_(variant), params_(resolveParams(*variant.algorithm, variant.params)) {
  if (findAlgorithm(variant.algorithm->name) == variant.algorithm) {
    RenderOptions options;
    options.algorithm = variant.algorithm->name;
    options.params = variant.params;
    registered_.emplace(scene, options);
  } else {
    object_ = variant.algorithm->create(scene, params_);
  }
}

Frame VariantRenderer::render(const Camera& cam, RenderOptions options) {
  options.algorithm = variant_.algorithm->name;
  options.params = variant_.params;
  Frame frame;
  if (registered_) {
    registered_->render(cam, options, frame);
    return frame;
  }
  // An algorithm outside the registry: Renderer's set-up around its object.
  frame.stats.width = cam.width;
  frame.stats.height = cam.height;
  frame.allocate(cam.width, cam.height, options.outputs);
  object_->render(cam, options, frame);
  frame.stats.algorithm = variant_.algorithm->name;
  frame.stats.params = params_.entries();
  return frame;
}

namespace {

std::string replayCommand(const Variant& variant, const std::string& sceneName, int w, int h, DepthFormat format,
                          const Pose& pose) {
  std::string params;
  for (const auto& [k, v] : variant.params) params += " --param " + k + "=" + v;
  return fmt::format(
      "Replay: save the camera below as cam.json, then\n"
      "  hsr render '{}' --camera cam.json --size {}x{} --algorithm {}{} --depth-format {} --verify --threads 1\n{}",
      sceneName, w, h, variant.algorithm->name, params, format.name(), pose.describe());
}

template <class T>
bool sameBits(const FrameBuffer<T>& a, const FrameBuffer<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// What the guarantee says of one outcome: "" when it holds, else why not.
std::string judge(const Guarantee& g, const Outcome& o, bool failureScene, bool conditionHolds) {
  using Kind = Guarantee::Kind;
  if (g.kind == Kind::FailsByDesign && failureScene)
    return o.wrong > 0 ? "" : "declared to fail here, but no pixel is wrong";
  if ((g.kind == Kind::ExactWhen || g.kind == Kind::FailsByDesign) && !conditionHolds) return "";
  if (g.kind == Kind::Approximate)
    return double(o.wrong) <= g.maxWrongFraction * double(o.covered)
               ? ""
               : fmt::format("{} wrong pixels of {} covered: over the declared bound {}", o.wrong, o.covered,
                             g.maxWrongFraction);
  return o.wrong == 0 ? "" : fmt::format("{} wrong pixels ({} ambiguous)", o.wrong, o.ambiguous);
}

// The statistics as JSON without what differs from run to run by design: the times (time_ms,
// and the algorithms' own details named *_ms) and the details that tell the algorithm object's
// history rather than the frame (the BSP tree's "built": 1 on the first render only; the
// half-range buffer's frame count, half, first clear and pixels reset from the frame before);
// with `threads` other than 1, also the memory (memory_bytes and its buffers), which counts each
// worker's own scratch.
std::string statsWithoutTimes(const Stats& stats, int threads = 1) {
  Stats copy = stats;
  copy.time_ms.clear();
  if (threads != 1) {
    copy.memory_bytes = 0;
    copy.memory.clear();
  }
  std::erase_if(copy.details, [](const auto& detail) {
    for (const char* history : {"built", "frames_kept", "half", "cleared", "pixels_reset"})
      if (detail.first == history) return true;
    return detail.first.ends_with("_ms");
  });
  return copy.toJson(-1);
}

bool failureScene(const Guarantee& g, const std::string& scene) {
  for (const std::string& s : g.failsOn)
    if (s == scene) return true;
  return false;
}

}  // namespace

Outcome run(const Variant& variant, const std::string& sceneName, const Scene& scene, const Pose& pose, int width,
            int height, DepthFormat format, int threads) {
  VariantRenderer renderer(variant, scene);
  return run(renderer, sceneName, scene, pose, width, height, format, threads);
}

Outcome run(VariantRenderer& renderer, const std::string& sceneName, const Scene& scene, const Pose& pose, int width,
            int height, DepthFormat format, int threads) {
  const Variant& variant = renderer.variant();
  const Camera cam = resolveCamera(pose.spec, width, height, scene.bounds());
  RenderOptions options;
  options.depthFormat = format;
  options.threads = threads;
  const Frame frame = renderer.render(cam, options);
  RenderOptions refOptions = options;
  refOptions.algorithm = "raycast";
  const Frame reference = render(scene, cam, refOptions);
  options.algorithm = variant.algorithm->name;
  const VerifyResult v = verifyAgainstReference(scene, cam, options, frame, reference);
  Outcome o;
  o.wrong = v.wrong_pixels;
  o.ambiguous = v.ambiguous_pixels;
  o.covered = reference.stats.covered_pixels;
  o.replay = replayCommand(variant, sceneName, width, height, format, pose);
  return o;
}

Plan fullPlan() {
  Plan p;
  p.cases = {
      {"test:boxes", 40},
      {"test:soup", 40},
      {"test:polygons", 20},
      {"builtin:cubes", 40},
      {"builtin:random?n=400&seed=3", 30},
      {"builtin:painter-midpoint", 25},
      {"builtin:painter-cycle", 25},
      {"builtin:interpenetrate", 25},
      {"builtin:layers?n=12", 20},
      {"builtin:sphere?n=20000", 15},
      {"builtin:city", 12},
      {"builtin:zfight", 15},
      {"builtin:csg", 25},
      {"builtin:csg?op=intersection", 20},
      {"builtin:csg?op=union", 15},
      {"builtin:csg?op=mixed", 25},
  };
  p.oddSizes = {{1, 1}, {37, 23}, {129, 67}};
  for (const char* s : {"u16", "u24", "u32", "f32"})
    for (const char* m : {"z", "reversed", "inv", "linear"}) p.formats.push_back(std::string(s) + ":" + m);
  p.formatScenes = {"builtin:cubes", "builtin:random?n=300&seed=5", "builtin:zfight", "test:soup"};
  p.determinismScenes = {"builtin:random?n=400&seed=3", "builtin:city", "builtin:painter-cycle",
                         "builtin:csg?op=mixed"};
  return p;
}

Plan suitePlan() {
#ifdef HSR_SANITIZED
  // A sanitized build runs ten to twenty times slower and looks for memory and undefined-behaviour
  // errors, which the same code paths show with fewer poses: every scene, size and depth format
  // of the full plan, a fifth of its poses, and determinism on two of its three scenes (not the
  // city, whose BSP tree under the first-polygon heuristic holds millions of fragments).
  Plan p = fullPlan();
  for (Plan::Case& c : p.cases) c.poses = std::max(2, c.poses / 5);
  p.oddSizePoses = 1;
  p.formatPoses = 1;
  p.determinismPoses = 1;
  std::erase(p.determinismScenes, "builtin:city");
  return p;
#else
  return fullPlan();
#endif
}

namespace {

bool contains(const std::vector<std::string>& list, const std::string& name) {
  return std::find(list.begin(), list.end(), name) != list.end();
}

// One case: the scene's own pose and its seeded poses at 64x48, the first poses at the odd sizes.
template <class Record>
void checkPoses(const Plan::Case& c, const Scene& scene, const Plan& plan, Record& record) {
  const DepthFormat defaultFormat;
  const std::vector<Pose> poses = posesAround(scene, c.poses, std::hash<std::string>{}(c.scene) & 0xffff);
  record(c.scene, scene, ownPose(scene), 64, 48, defaultFormat, true);
  for (const Pose& pose : poses) record(c.scene, scene, pose, 64, 48, defaultFormat, false);
  for (const auto& [w, h] : plan.oddSizes)
    for (int i = 0; i < std::min<int>(plan.oddSizePoses, int(poses.size())); ++i)
      record(c.scene, scene, poses[size_t(i)], w, h, defaultFormat, false);
}

// Determinism: the same bits in every buffer and the same statistics (times aside, and the
// memory of the workers' scratch across thread counts) for 1, 2 and 8 threads, and for a second
// run on 1 thread. Each view is drawn once before the runs compared, so that every one of them
// follows the same frame (an algorithm may carry what the last frame showed: temporal coherence).
void checkDeterminism(VariantRenderer& renderer, const std::string& name, const Scene& scene, int poseCount,
                      std::vector<std::string>& failures) {
  const Variant& variant = renderer.variant();
  std::vector<Pose> poses = posesAround(scene, poseCount, 7);
  poses.push_back(ownPose(scene));
  for (const Pose& pose : poses) {
    const Camera cam = resolveCamera(pose.spec, 150, 90, scene.bounds());
    RenderOptions options;
    options.threads = 1;
    (void)renderer.render(cam, options);
    const Frame one = renderer.render(cam, options);
    for (int threads : {1, 2, 8}) {
      options.threads = threads;
      const Frame many = renderer.render(cam, options);
      const bool sameBuffers = sameBits(one.faceId, many.faceId) && sameBits(one.triangleId, many.triangleId) &&
                               sameBits(one.depth, many.depth) && sameBits(one.color, many.color);
      const std::string oneStats = statsWithoutTimes(one.stats, threads);
      const std::string manyStats = statsWithoutTimes(many.stats, threads);
      if (!sameBuffers || manyStats != oneStats)
        failures.push_back(fmt::format("{} on {} at 150x90: {} threads differ from a first run on 1 ({}){}\n{}",
                                       variant.describe(), name, threads, sameBuffers ? "statistics" : "buffers",
                                       sameBuffers ? "\n" + oneStats + "\n" + manyStats : "", pose.describe()));
    }
  }
}

}  // namespace

std::vector<std::string> Plan::scenes() const {
  std::vector<std::string> names;
  auto add = [&](const std::string& name) {
    if (!contains(names, name)) names.push_back(name);
  };
  for (const Case& c : cases) add(c.scene);
  for (const std::string& name : formatScenes) add(name);
  for (const std::string& name : determinismScenes) add(name);
  return names;
}

std::vector<std::string> check(const Variant& variant, const Plan& plan) {
  const Guarantee g = variant.algorithm->guaranteeWith(resolveParams(*variant.algorithm, variant.params));
  std::vector<std::string> failures;
  std::optional<VariantRenderer> renderer;  // the variant made for the scene being checked
  auto record = [&](const std::string& sceneName, const Scene& scene, const Pose& pose, int w, int h,
                    DepthFormat format, bool own) {
    const Outcome o = run(*renderer, sceneName, scene, pose, w, h, format);
    const Camera cam = resolveCamera(pose.spec, w, h, scene.bounds());
    RenderOptions options;
    options.depthFormat = format;
    const bool holds = !g.holds || g.holds(scene, cam, options);
    // A scene it fails on by design is judged as such with its own camera; other poses of it
    // are not judged (the painter's failure there depends on the view).
    const bool failing = failureScene(g, sceneName);
    if (failing && !own) return;
    const std::string why = judge(g, o, failing, holds);
    if (!why.empty())
      failures.push_back(fmt::format("{} on {} at {}x{}, {}: {} (guarantee: {})\n{}", variant.describe(), sceneName, w,
                                     h, format.name(), why, g.describe(), o.replay));
  };
  // Scene by scene, with one algorithm object per scene, so that what an algorithm builds for a
  // scene (the BSP tree) is built once for all of that scene's checks.
  for (const std::string& name : plan.scenes()) {
    const Scene scene = load(name);
    // A scene with a CSG tree is judged against the tree's result (raycast shows it): only the
    // algorithms that declare Capability::Csg show it; the others draw its solids as plain meshes.
    if (!scene.csg.empty() && variant.algorithm->capability != Capability::Csg) continue;
    renderer.emplace(variant, scene);
    for (const Plan::Case& c : plan.cases)
      if (c.scene == name) checkPoses(c, scene, plan, record);
    if (contains(plan.formatScenes, name))
      for (const Pose& pose : posesAround(scene, plan.formatPoses, 99))
        for (const std::string& f : plan.formats) record(name, scene, pose, 64, 48, DepthFormat::parse(f), false);
    if (contains(plan.determinismScenes, name))
      checkDeterminism(*renderer, name, scene, plan.determinismPoses, failures);
  }
  return failures;
}

}  // namespace hsr::conformance

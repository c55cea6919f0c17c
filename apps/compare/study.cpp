// The study's cases and runs (study.hpp): render, time, count, verify against raycast, picture.
#include "study.hpp"

#include "../commands.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

namespace hsr::cli {
namespace {

constexpr double kSlowFrameMs = 2000;           // a run whose first frame is slower times that frame only
constexpr int kMaxPicturePixels = 800 * 600;     // cases this small get pictures

std::string fileSafe(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : '_';
  return out;
}

StudyCase makeCase(const std::string& group, const std::string& scene, int w, int h) {
  std::string name = scene.rfind("builtin:", 0) == 0 ? scene.substr(8) : std::filesystem::path(scene).stem().string();
  return {fileSafe(fmt::format("{}-{}x{}", name, w, h)), group, scene, w, h, w * h <= kMaxPicturePixels};
}

}  // namespace

std::vector<StudyCase> defaultStudy(bool quick) {
  // Quick: the same experiments at a fraction of the size, for the test suite.
  const auto size = [quick](int w, int h) { return quick ? std::pair{std::max(w / 6, 16), std::max(h / 6, 12)} : std::pair{w, h}; };
  const std::string manyPolygons = quick ? "builtin:random?n=2000" : "builtin:random?n=10000";
  const std::string thesisPolygons = quick ? "builtin:random?n=1000" : "builtin:random?n=5000";
  std::vector<StudyCase> cases;
  auto add = [&](const std::string& group, const std::string& scene, int w, int h) {
    const auto [sw, sh] = size(w, h);
    cases.push_back(makeCase(group, scene, sw, sh));
  };
  const char* report = "KTH report: few and many polygons, low and high resolution";
  for (const std::string& scene : {std::string("builtin:random?n=50"), manyPolygons})
    for (const auto& [w, h] : {std::pair{640, 480}, std::pair{1920, 1080}}) add(report, scene, w, h);
  const char* thesis = "KTH thesis: four cubes and 5,000 intersecting polygons";
  add(thesis, "builtin:cubes", 160, 120);
  add(thesis, "builtin:cubes", 1920, 1080);
  add(thesis, thesisPolygons, 320, 240);
  add(thesis, thesisPolygons, 1920, 1080);
  const char* paper = "Ukrainian paper: 800x600";
  add(paper, "builtin:city", 800, 600);
  add(paper, "builtin:layers?n=16&order=random", 800, 600);
  const char* failures = "The painter's failures";
  for (const char* scene : {"builtin:painter-midpoint", "builtin:painter-cycle", "builtin:interpenetrate"})
    add(failures, scene, 480, 360);
  const char* occlusion = "Depth complexity and occlusion at 1920x1080";
  add(occlusion, "builtin:layers?n=64&order=random", 1920, 1080);
  add(occlusion, "builtin:city", 1920, 1080);
  const char* csg = "CSG by the z-buffer (KTH report)";
  for (const char* scene : {"builtin:csg", "builtin:csg?op=mixed"}) add(csg, scene, 640, 480);
  return cases;
}

std::vector<StudyCase> casesOf(const std::vector<std::string>& scenes, const std::vector<std::pair<int, int>>& sizes) {
  std::vector<StudyCase> cases;
  for (const std::string& scene : scenes)
    for (const auto& [w, h] : sizes) cases.push_back(makeCase("Given scenes", scene, w, h));
  return cases;
}

Variant parseVariant(const std::string& text) {
  Variant v;
  std::vector<std::string> parts;
  for (size_t start = 0; start <= text.size();) {
    const size_t colon = std::min(text.find(':', start), text.size());
    parts.push_back(text.substr(start, colon - start));
    start = colon + 1;
  }
  v.algorithm = parts[0];
  if (!findAlgorithm(v.algorithm))
    throw InputError("--algorithms: unknown algorithm '" + v.algorithm + "' in '" + text + "' ('hsr algorithms' lists them)");
  v.label = v.algorithm;
  for (size_t i = 1; i < parts.size(); ++i) {
    const size_t eq = parts[i].find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("--algorithms: '" + text + "': expected NAME[:KEY=VALUE...]");
    v.params[parts[i].substr(0, eq)] = parts[i].substr(eq + 1);
    v.label += " " + parts[i];
  }
  resolveParams(*findAlgorithm(v.algorithm), v.params);  // a bad key or value fails before anything runs
  return v;
}

std::vector<Variant> defaultVariants() {
  std::vector<Variant> variants;
  for (const AlgorithmInfo& a : algorithms()) {
    variants.push_back({a.name, a.name, {}});
    if (a.name == "zbuffer")  // the textbook z-buffer, on the painter's family's rasterizer and the reference one
      for (const char* raster : {"binned", "halfspace"})
        variants.push_back({std::string("zbuffer raster=") + raster, "zbuffer", {{"raster", raster}}});
    // The painter's family on the z-buffer's SIMD tile kernel too, so that each is compared with
    // the z-buffer on both rasterizers: "NAME" (binned, scalar) beside "zbuffer raster=binned",
    // "NAME raster=tiled" beside "zbuffer".
    for (const ParamSpec& p : a.params)
      if (p.name == "raster" && a.name != "zbuffer" && p.defaultValue != "tiled" &&
          std::find(p.choices.begin(), p.choices.end(), "tiled") != p.choices.end())
        variants.push_back({a.name + " raster=tiled", a.name, {{"raster", "tiled"}}});
  }
  return variants;
}

namespace {

// What the algorithm's guarantee says of this case's wrong pixels.
std::string judge(const AlgorithmInfo& info, const AlgorithmParams& params, const StudyCase& c, const Scene& scene,
                  const Camera& camera, const RenderOptions& options, uint64_t wrong, uint64_t covered) {
  if (!scene.csg.empty() && info.capability != Capability::Csg)
    return wrong == 0 ? "exact (the plain meshes show the tree here)" : "plain meshes, not the tree (no CSG)";
  const Guarantee g = info.guaranteeWith(params);
  using K = Guarantee::Kind;
  if (g.kind == K::FailsByDesign && std::find(g.failsOn.begin(), g.failsOn.end(), c.scene) != g.failsOn.end())
    return wrong > 0 ? "fails, as declared" : "declared to fail here, but exact";
  if ((g.kind == K::ExactWhen || (g.kind == K::FailsByDesign && g.holds)) && !g.holds(scene, camera, options))
    return wrong == 0 ? "exact (outside its condition)" : "wrong outside its condition, as declared";
  if (g.kind == K::Approximate)
    return double(wrong) <= g.maxWrongFraction * double(covered) ? "within its bound" : "VIOLATES its bound";
  return wrong == 0 ? "exact, as declared" : "VIOLATES its guarantee";
}

void writeErrorMap(const Frame& frame, const std::vector<PixelVerdict>& verdicts, const std::string& path) {
  Frame map;
  map.width = frame.width;
  map.height = frame.height;
  map.color.resize(verdicts.size());
  for (size_t i = 0; i < verdicts.size(); ++i) {
    const Rgba8 c = frame.color.empty() ? Rgba8{0, 0, 0, 255} : frame.color[i];
    const uint8_t grey = uint8_t((c.r + c.g + c.b) / 12 + 20);  // the image, dimmed
    map.color[i] = verdicts[i] == PixelVerdict::Wrong       ? Rgba8{255, 30, 30, 255}
                   : verdicts[i] == PixelVerdict::Ambiguous ? Rgba8{255, 200, 0, 255}
                                                            : Rgba8{grey, grey, grey, 255};
  }
  writeColorPng(map, path);
}

struct RunContext {
  const StudyCase& c;
  const Scene& scene;
  const Camera& camera;
  const Frame& reference;
  const StudySettings& settings;
  std::string imageDir;  // relative to outDir; empty: no pictures
};

Json timedRun(const RunContext& ctx, const RenderOptions& options, Frame& frame) {
  std::vector<double> ms;
  std::map<std::string, std::vector<double>> stages;
  std::vector<std::string> stageOrder;
  Renderer renderer(ctx.scene, options);  // one algorithm object for every frame: built once
  for (int i = 0; i < ctx.settings.frames; ++i) {
    const auto start = std::chrono::steady_clock::now();
    renderer.render(ctx.camera, frame);
    ms.push_back(millisecondsSince(start));
    for (const auto& [stage, t] : frame.stats.time_ms) {
      if (!stages.count(stage)) stageOrder.push_back(stage);
      stages[stage].push_back(t);
    }
    // A slow first frame is the only one, unless it built what later frames reuse (a BSP tree).
    const bool built = std::any_of(frame.stats.time_ms.begin(), frame.stats.time_ms.end(),
                                   [](const auto& stage) { return stage.first == "build"; });
    if (i == 0 && ms[0] > kSlowFrameMs && !built) break;
  }
  Json stageJson = Json::object();
  for (const std::string& s : stageOrder) stageJson[s] = median(stages[s]);
  return {{"frames", ms.size()}, {"median_ms", median(ms)}, {"min_ms", *std::min_element(ms.begin(), ms.end())},
          {"first_ms", ms.front()}, {"stages_ms", stageJson}};
}

void writePictures(const RunContext& ctx, const Variant& v, RenderOptions options, const Frame& frame,
                   const std::vector<PixelVerdict>& verdicts, Json& run) {
  const std::string base = ctx.imageDir + "/" + fileSafe(v.label);
  const std::string root = ctx.settings.outDir + "/";
  Json images = Json::object();
  if (!frame.color.empty()) {
    writeColorPng(frame, root + base + "-color.png");
    images["color"] = base + "-color.png";
  }
  writeDepthImage(frame, root + base + "-depth.png");
  images["depth"] = base + "-depth.png";
  writeErrorMap(frame, verdicts, root + base + "-error.png");
  images["error"] = base + "-error.png";
  options.countWrites = true;  // the overdraw picture, where the algorithm counts writes per pixel
  try {
    Frame counted;
    render(ctx.scene, ctx.camera, options, counted);
    writeOverdrawImage(counted, root + base + "-overdraw.png");
    images["overdraw"] = base + "-overdraw.png";
  } catch (const InputError&) {
  }
  run["images"] = images;
}

Json runVariant(const RunContext& ctx, const Variant& v) {
  Json run = {{"variant", v.label}, {"algorithm", v.algorithm}};
  const AlgorithmInfo& info = *findAlgorithm(v.algorithm);
  RenderOptions options;
  options.algorithm = v.algorithm;
  options.params = v.params;
  options.threads = ctx.settings.threads;
  const AlgorithmParams params = resolveParams(info, v.params);
  run["guarantee"] = info.guaranteeWith(params).describe();
  Frame frame;
  try {
    run.update(timedRun(ctx, options, frame));
  } catch (const InputError& e) {  // e.g. a BSP tree over its fragment budget: reported, not fatal
    run["error"] = cliMessage(e);
    return run;
  }
  std::vector<PixelVerdict> verdicts;
  const VerifyResult verify = verifyPixels(ctx.scene, ctx.camera, options, frame, ctx.reference, verdicts);
  const Stats& st = frame.stats;
  run["depth_tests"] = st.depth_tests;
  run["depth_writes"] = st.depth_writes;
  run["color_writes"] = st.color_writes;
  run["covered_pixels"] = st.covered_pixels;
  run["overdraw"] = st.overdraw();
  run["memory_bytes"] = st.memory_bytes;
  run["wrong_pixels"] = verify.wrong_pixels;
  run["ambiguous_pixels"] = verify.ambiguous_pixels;
  run["check"] = judge(info, params, ctx.c, ctx.scene, ctx.camera, options, verify.wrong_pixels, st.covered_pixels);
  run["stats"] = Json::parse(st.toJson());
  if (!ctx.imageDir.empty()) writePictures(ctx, v, options, frame, verdicts, run);
  return run;
}

Json runCase(const StudyCase& c, const std::vector<Variant>& variants, const StudySettings& settings, size_t& runIndex,
             size_t runs) {
  Scene scene = loadScene(c.scene);
  const CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
  const Camera camera = resolveCamera(spec, c.width, c.height, scene.bounds(), c.scene);
  if (settings.progress) settings.progress(runIndex, runs, c, "reference (raycast)");
  RenderOptions refOptions;
  refOptions.algorithm = "raycast";
  refOptions.threads = settings.threads;
  const auto refStart = std::chrono::steady_clock::now();
  const Frame reference = render(scene, camera, refOptions);
  const double refMs = millisecondsSince(refStart);

  Json out = {{"id", c.id},          {"group", c.group},        {"scene", c.scene},
              {"width", c.width},    {"height", c.height},      {"faces", scene.faceCount()},
              {"triangles", scene.triangles.size()}, {"reference_ms", refMs}, {"runs", Json::array()}};
  RunContext ctx{c, scene, camera, reference, settings, ""};
  if (c.pictures) {
    ctx.imageDir = "img/" + c.id;
    std::filesystem::create_directories(settings.outDir + "/" + ctx.imageDir);
  }
  for (const Variant& v : variants) {
    if (settings.interrupted && settings.interrupted->load()) break;
    // A CSG scene: the algorithms that show the tree, and the z-buffer to show what drawing the
    // solids as plain meshes gets wrong.
    if (!scene.csg.empty() && findAlgorithm(v.algorithm)->capability != Capability::Csg && v.algorithm != "zbuffer") {
      ++runIndex;
      continue;
    }
    if (settings.progress) settings.progress(runIndex, runs, c, v.label);
    out["runs"].push_back(runVariant(ctx, v));
    ++runIndex;
  }
  return out;
}

}  // namespace

Json runStudy(const std::vector<StudyCase>& cases, const std::vector<Variant>& variants, const StudySettings& settings,
              const std::function<void(const Json&)>& caseDone) {
  Json results = {{"cases", Json::array()}};
  size_t runIndex = 0;
  const size_t runs = cases.size() * variants.size();
  for (const StudyCase& c : cases) {
    if (settings.interrupted && settings.interrupted->load()) break;
    results["cases"].push_back(runCase(c, variants, settings, runIndex, runs));
    if (caseDone) caseDone(results);
  }
  if (settings.progress && !cases.empty()) settings.progress(runs, runs, cases.back(), "done");
  return results;
}

}  // namespace hsr::cli

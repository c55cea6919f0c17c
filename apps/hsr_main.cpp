// The `hsr` command line: a table of subcommands (render, bench, compare, precision, algorithms, scenes, info, help),
// each with its own flags and help (compare and precision in their own files); docs/cli.md documents them. Used by people
// and by the scripts that compare hsr with other renderers, so flags, output files and exit
// status follow docs/conventions.md "Command line": 0 success, 2 bad usage or input, 1 otherwise.
#include <hsr/hsr.hpp>

#include "commands.hpp"
#include "core/parallel.hpp"
#include "output_set.hpp"

#include <CLI/CLI.hpp>
#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>

#ifndef HSR_VERSION
#define HSR_VERSION "0.1.0"  // normally set by CMake from project(VERSION)
#endif

namespace {

using hsr::InputError;
using Json = nlohmann::ordered_json;

constexpr int kMaxImageSide = 16384;

// ---------------------------------------------------------------------------------------------
// Flag values. Each parser throws InputError "--flag 'text': problem" (exit status 2).

// A whole-string, finite number: "1e3" yes; "1e3x", "nan", "inf" no.
bool parseFinite(std::string_view text, double& value) {
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(value);
}

// Comma-separated finite numbers, minCount to maxCount of them; `form` shows the expected text.
std::vector<double> parseNumbers(const std::string& flag, const std::string& text, size_t minCount, size_t maxCount,
                                 const char* form) {
  std::vector<double> values;
  size_t start = 0;
  bool ok = true;
  while (ok) {
    size_t comma = std::min(text.find(',', start), text.size());
    double v;
    ok = parseFinite(std::string_view(text).substr(start, comma - start), v);
    values.push_back(v);
    if (comma == text.size()) break;
    start = comma + 1;
  }
  if (!ok || values.size() < minCount || values.size() > maxCount)
    throw InputError(fmt::format("{} '{}': expected {} (finite numbers)", flag, text, form));
  return values;
}

hsr::dvec3 parseVec3(const std::string& flag, const std::string& text) {
  std::vector<double> v = parseNumbers(flag, text, 3, 3, "x,y,z");
  return {v[0], v[1], v[2]};
}

struct ImageSize {
  int width = 0, height = 0;
};

// An OpenCV K whose principal point lies outside the image was most likely made for another
// image size: say so (on stderr; the render goes on).
void warnPrincipalPointOutside(const hsr::CameraSpec& spec, ImageSize size, const std::string& cameraName) {
  if (spec.kind != hsr::CameraSpec::Kind::OpenCV) return;
  const double cx = spec.K[0][2], cy = spec.K[1][2];
  if (cx >= 0 && cx <= size.width && cy >= 0 && cy <= size.height) return;
  fmt::print(stderr,
             "hsr: warning: {}: K's principal point ({:g}, {:g}) lies outside the {}x{} image (give --size, or "
             "'width' and 'height' in the camera JSON)\n",
             cameraName, cx, cy, size.width, size.height);
}
ImageSize parseSize(const std::string& text) {
  size_t x = text.find_first_of("xX");
  ImageSize size;
  auto side = [](std::string_view s, int& out) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size() && out >= 1 && out <= kMaxImageSide;
  };
  if (x == std::string::npos || !side(std::string_view(text).substr(0, x), size.width) ||
      !side(std::string_view(text).substr(x + 1), size.height))
    throw InputError(fmt::format("--size '{}': expected WIDTHxHEIGHT, each 1 to {}", text, kMaxImageSide));
  return size;
}

hsr::Rgba8 parseColor(const std::string& text) {
  std::vector<double> v = parseNumbers("--background", text, 3, 4, "r,g,b or r,g,b,a");
  for (double c : v)
    if (c < 0 || c > 255 || c != std::floor(c))
      throw InputError("--background '" + text + "': components are integers 0 to 255");
  return {uint8_t(v[0]), uint8_t(v[1]), uint8_t(v[2]), uint8_t(v.size() == 4 ? v[3] : 255)};
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read: " + std::strerror(errno));
  return text.str();
}

// A positive finite number, checked by CLI11 before it converts the flag's value.
const CLI::Validator kPositive(
    [](std::string& text) {
      double v;
      return parseFinite(text, v) && v > 0 ? std::string() : "'" + text + "' is not a positive finite number";
    },
    "POSITIVE");

template <class Enum>
using Names = std::vector<std::pair<std::string, Enum>>;
const Names<hsr::Cull> kCullNames{{"none", hsr::Cull::None}, {"back", hsr::Cull::Back}, {"front", hsr::Cull::Front}};
const Names<hsr::Shading> kShadingNames{
    {"lambert", hsr::Shading::Lambert}, {"flat", hsr::Shading::Flat}, {"faceid", hsr::Shading::FaceId}};

// The names, for CLI11 to check a flag's value against (in any letter case).
template <class Enum>
CLI::IsMember oneOf(const Names<Enum>& names) {
  std::vector<std::string> keys;
  for (const auto& entry : names) keys.push_back(entry.first);
  return CLI::IsMember(keys, CLI::ignore_case);
}
template <class Enum>
std::string nameOf(const Names<Enum>& names, Enum value) {
  for (const auto& [key, v] : names)
    if (v == value) return key;
  throw std::logic_error("nameOf: unnamed value");
}
// The value of a name oneOf() accepted (in any letter case).
template <class Enum>
Enum valueOf(const Names<Enum>& names, std::string name) {
  for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
  for (const auto& [key, value] : names)
    if (key == name) return value;
  throw std::logic_error("valueOf: '" + name + "' was not checked");
}

// ---------------------------------------------------------------------------------------------
// What render and bench share: the scene, the image size, the camera and the algorithm settings.

struct Job {
  std::string sceneName;
  hsr::Scene scene;
  hsr::Camera camera;
  hsr::RenderOptions options;
};

std::string algorithmNames() {
  std::string names;
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) names += (names.empty() ? "" : ", ") + a.name;
  return names;
}

struct ViewFlags {
  std::string scene, cameraFile, size = "1280x720", depthFormat, background;
  std::string cull = "none", shading = "lambert";
  std::vector<std::string> params;  // --param KEY=VALUE, repeatable
  bool depthOnly = false;
  std::string outputs;  // --outputs (not given: all)
  std::string eye, target, up;
  double fov = 0, near = 0, far = 0, ortho = 0;
  CLI::Option *fovFlag = nullptr, *nearFlag = nullptr, *farFlag = nullptr, *orthoFlag = nullptr;
  CLI::Option* outputsFlag = nullptr;
  CLI::Option* sizeFlag = nullptr;
  hsr::RenderOptions options;  // algorithm and threads: set by CLI11 directly

  void declare(CLI::App& cmd) {
    cmd.add_option("scene", scene, "Mesh file (OBJ, PLY, STL, OFF, glTF/GLB, ...), scene JSON or builtin:NAME[?k=v&...]")
        ->type_name("SCENE")
        ->required();
    cmd.add_option("--camera", cameraFile, "Camera JSON (OpenGL or OpenCV style); the flags below override it")
        ->type_name("CAM.json");
    sizeFlag = cmd.add_option("--size", size, "Image size (default: the camera JSON's width and height, else 1280x720)")->type_name("WxH")->capture_default_str();

    cmd.add_option("--algorithm", options.algorithm, "Visibility algorithm: " + algorithmNames())
        ->type_name("NAME")
        ->capture_default_str();
    cmd.add_option("--depth-format", depthFormat,
                   "Depth buffer STORAGE[:MAPPING]: storage u16|u24|u32|f32, mapping z|reversed|inv|linear "
                   "(default f32:reversed)")
        ->type_name("FMT");
    cmd.add_option("--threads", options.threads, "Worker threads (0 = all cores)")
        ->type_name("N")
        ->check(CLI::Range(0, 4096))
        ->capture_default_str();
    cmd.add_option("--param", params,
                   "An algorithm parameter, repeatable (e.g. --param raster=halfspace); 'hsr algorithms' lists "
                   "each algorithm's parameters, values and defaults")
        ->type_name("KEY=VALUE")
        ->take_all();
    CLI::Option* depthOnlyFlag = cmd.add_flag(
        "--depth-only", depthOnly,
        "z-buffer keeps only depth: no face ids or colour; depth is the stored value mapped back to eye depth");
    outputsFlag = cmd.add_option("--outputs", outputs,
                   "Buffers the z-buffer resolves, comma-separated: depth (always), face, triangle, color (default: "
                   "all; depth alone = --depth-only). Buffers not asked for are not written")
        ->type_name("LIST")
        ->excludes(depthOnlyFlag);
    cmd.add_option("--cull", cull, "Face culling (faces are two-sided by default)")
        ->check(oneOf(kCullNames))
        ->capture_default_str();
    cmd.add_option("--shading", shading, "Colour of the image")->check(oneOf(kShadingNames))->capture_default_str();
    cmd.add_option("--background", background, "Background colour, 0-255 (default 0,0,0)")->type_name("R,G,B[,A]");

    const char* group = "Camera (override or extend --camera; default: the scene's camera or a framing of it)";
    cmd.add_option("--eye", eye, "Camera position")->type_name("X,Y,Z")->group(group);
    cmd.add_option("--target", target, "Point looked at")->type_name("X,Y,Z")->group(group);
    cmd.add_option("--up", up, "Up direction")->type_name("X,Y,Z")->group(group);
    fovFlag = cmd.add_option("--fov", fov, "Vertical field of view, degrees")->type_name("DEG")->check(kPositive)->group(group);
    nearFlag = cmd.add_option("--near", near, "Near clipping plane (eye depth)")->type_name("N")->check(kPositive)->group(group);
    farFlag = cmd.add_option("--far", far, "Far clipping plane (eye depth)")->type_name("F")->check(kPositive)->group(group);
    orthoFlag = cmd.add_option("--ortho", ortho, "Orthographic, view volume HEIGHT world units tall")
                    ->type_name("HEIGHT")
                    ->check(kPositive)
                    ->group(group);
  }

  // What the z-buffer resolves (checked before the scene is loaded).
  hsr::FrameOutputs frameOutputs() const {
    if (depthOnly) return hsr::FrameOutputs::DepthOnly;
    return outputsFlag->count() ? hsr::parseFrameOutputs(outputs, "--outputs") : hsr::FrameOutputs::All;
  }

  // --param KEY=VALUE flags as a map (a key given twice is an error).
  std::map<std::string, std::string> parsedParams() const {
    std::map<std::string, std::string> out;
    for (const std::string& p : params) {
      const size_t eq = p.find('=');
      if (eq == std::string::npos || eq == 0)
        throw InputError(fmt::format("--param '{}': expected KEY=VALUE (see 'hsr algorithms')", p));
      if (!out.emplace(p.substr(0, eq), p.substr(eq + 1)).second)
        throw InputError(fmt::format("--param '{}': {} is given twice", p, p.substr(0, eq)));
    }
    return out;
  }

  bool openGlFlagsGiven() const {
    return !eye.empty() || !target.empty() || !up.empty() || fovFlag->count() || orthoFlag->count();
  }

  // Checks every flag, then loads the scene and resolves the camera: bad flags fail before a
  // possibly long scene load.
  Job prepare() const {
    Job job;
    job.sceneName = scene;
    ImageSize imageSize = parseSize(size);
    job.options = options;
    job.options.params = parsedParams();
    job.options.outputs = frameOutputs();
    job.options.cull = valueOf(kCullNames, cull);
    job.options.shading = valueOf(kShadingNames, shading);
    if (!depthFormat.empty()) job.options.depthFormat = hsr::DepthFormat::parse(depthFormat);
    if (!background.empty()) job.options.background = parseColor(background);
    const hsr::AlgorithmInfo* algorithm = hsr::findAlgorithm(options.algorithm);
    if (!algorithm)
      throw InputError(fmt::format("--algorithm '{}': unknown (known: {})", options.algorithm, algorithmNames()));
    hsr::resolveParams(*algorithm, job.options.params);  // a parameter typo fails before the scene loads
    std::optional<hsr::CameraSpec> fileCamera;
    if (!cameraFile.empty()) fileCamera = hsr::parseCameraJson(readTextFile(cameraFile), cameraFile);
    std::optional<hsr::dvec3> eyeValue, targetValue, upValue;
    if (!eye.empty()) eyeValue = parseVec3("--eye", eye);
    if (!target.empty()) targetValue = parseVec3("--target", target);
    if (!up.empty()) upValue = parseVec3("--up", up);

    job.scene = hsr::loadScene(scene);
    const hsr::Bounds3 bounds = job.scene.bounds();
    hsr::CameraSpec spec = fileCamera         ? *fileCamera
                           : job.scene.camera ? *job.scene.camera
                           : fovFlag->count() ? hsr::frameBounds(bounds, fov)
                                              : hsr::frameBounds(bounds);
    // The name camera errors carry: where the camera came from.
    bool flagsGiven = openGlFlagsGiven() || nearFlag->count() || farFlag->count();
    std::string cameraName = !cameraFile.empty() ? cameraFile : flagsGiven ? "command line" : scene;
    if (!cameraFile.empty() && flagsGiven) cameraName += " (with camera flags)";
    if (openGlFlagsGiven() && spec.kind != hsr::CameraSpec::Kind::OpenGL)
      throw InputError(cameraName + ": --eye/--target/--up/--fov/--ortho apply to OpenGL-style cameras, not this OpenCV one");
    // A scene's clipping planes suit its own viewpoint: when the flags move the camera, let
    // resolveCamera fit them to the scene again (a camera file's planes are the user's choice).
    if (!fileCamera && (eyeValue || targetValue || orthoFlag->count())) {
      spec.near.reset();
      spec.far.reset();
    }
    if (eyeValue) spec.eye = *eyeValue;
    if (targetValue) spec.target = *targetValue;
    if (upValue) spec.up = *upValue;
    if (fovFlag->count()) spec.fovyDeg = fov;
    if (orthoFlag->count()) spec.orthoHeight = ortho;
    if (nearFlag->count()) spec.near = near;
    if (farFlag->count()) spec.far = far;
    if (!sizeFlag->count() && spec.width && spec.height) imageSize = {*spec.width, *spec.height};
    warnPrincipalPointOutside(spec, imageSize, cameraName);
    job.camera = hsr::resolveCamera(spec, imageSize.width, imageSize.height, bounds, cameraName);
    return job;
  }
};

using hsr::cli::millisecondsSince;

// ---------------------------------------------------------------------------------------------
// Subcommands. Each declares its flags on its CLI11 app, bound to state that the returned
// runner owns, and the runner does the work once parsing succeeded.

using Runner = std::function<int()>;

struct RenderFlags {
  ViewFlags view;
  std::string out, ids, depth, depthImage, overdrawImage, stats, svg;
  std::string instanceIds, barycentric;  // attributes resolved from the ids (hsr/views.hpp)
  bool verify = false, quiet = false, json = false;
  std::vector<hsr::cli::OutputFlag> outputFlags;  // every output flag, checked as a set
  // --shadows (docs/shadows.md): the light from the flags, else the scene's, else the default.
  bool shadows = false;
  std::string lightDir, lightPos;
  hsr::ShadowOptions shadowOptions;
};

// The light --light-dir or --light-pos give (checked before the scene loads), if any.
std::optional<hsr::Light> flagLight(const RenderFlags& f) {
  if (f.lightDir.empty() && f.lightPos.empty()) return std::nullopt;
  hsr::Light light;
  light.kind = f.lightDir.empty() ? hsr::Light::Kind::Point : hsr::Light::Kind::Directional;
  const char* flag = f.lightDir.empty() ? "--light-pos" : "--light-dir";
  light.vector = parseVec3(flag, f.lightDir.empty() ? f.lightPos : f.lightDir);
  hsr::checkLight(light, fmt::format("{} '{}'", flag, f.lightDir.empty() ? f.lightPos : f.lightDir));
  return light;
}

void printShadowSummary(const hsr::Stats& s) {
  auto count = [&s](std::string_view key) { return s.detailCount(key).value_or(0); };
  fmt::print("  shadows: {}, map {}x{}, lit {} pixels, shadowed {} (of which facing away {})\n",
             s.detailText("shadow_light"), count("shadow_map_size"), count("shadow_map_size"),
             count("shadow_lit_pixels"), count("shadow_shadowed_pixels"), count("shadow_facing_away_pixels"));
  if (s.detailCount("shadow_wrong_pixels"))
    fmt::print("  shadow verify: {} wrong pixels against shadow rays, {} away from shadow edges, {} away from "
               "shadow and face edges, {} unexplained (away from edges at the map's scale too)\n",
               count("shadow_wrong_pixels"), count("shadow_wrong_away_from_shadow_edges"),
               count("shadow_wrong_away_from_edges"), count("shadow_wrong_unexplained"));
}

// The human summary of one rendered frame.
void printSummary(const Job& job, const hsr::Stats& s, double wallMs, const std::vector<std::string>& written) {
  double pixels = double(s.width) * double(s.height);
  std::string params;
  for (const auto& [key, value] : s.params) params += fmt::format(" {}={}", key, value);
  fmt::print("{}{} on {}: {}x{}{}, {} threads, cull {}\n", s.algorithm, params, job.sceneName, s.width, s.height,
             s.depth_format.empty() ? "" : ", depth " + s.depth_format, hsr::resolveThreads(job.options.threads),
             nameOf(kCullNames, job.options.cull));
  fmt::print("  faces {}, triangles {} (clipped {}, zero area on the pixel grid {}; culled back-face {}, frustum {}, "
             "occlusion {})\n",
             s.faces, s.triangles, s.triangles_clipped, s.triangles_degenerate, s.culled_backface, s.culled_frustum,
             s.culled_occlusion);
  fmt::print("  covered {} pixels ({:.1f}%), overdraw {:.2f}, depth tests {}, writes {}, memory {:.1f} MB\n",
             s.covered_pixels, pixels > 0 ? 100.0 * double(s.covered_pixels) / pixels : 0.0, s.overdraw(),
             s.depth_tests, s.depth_writes, double(s.memory_bytes) / 1e6);
  std::string stages;
  for (const auto& [stage, ms] : s.time_ms) stages += fmt::format("{}{} {:.2f}", stages.empty() ? "" : ", ", stage, ms);
  fmt::print("  time {:.2f} ms wall{}\n", wallMs, stages.empty() ? "" : " (" + stages + ")");
  if (s.wrong_pixels)
    fmt::print("  verify: {} wrong pixels, {} ambiguous\n", *s.wrong_pixels, s.ambiguous_pixels.value_or(0));
  if (!written.empty()) fmt::print("  wrote {}\n", fmt::join(written, ", "));
}

// --instance-ids and --barycentric: their file names, and the ids they are resolved from.
void checkAttributeOutputs(const RenderFlags& f, hsr::FrameOutputs kept) {
  if (!f.instanceIds.empty()) {
    hsr::checkInstanceIdsPath(f.instanceIds);
    if (!has(kept, hsr::FrameOutputs::FaceIds))
      throw InputError("--instance-ids: the outputs kept (" + hsr::frameOutputsName(kept) + ") have no face ids (add face)");
  }
  if (!f.barycentric.empty()) {
    hsr::checkBarycentricsPath(f.barycentric);
    if (!has(kept, hsr::FrameOutputs::TriangleIds))
      throw InputError("--barycentric: the outputs kept (" + hsr::frameOutputsName(kept) +
                       ") have no triangle ids (add triangle)");
  }
}

void writeAttributeOutputs(const RenderFlags& f, const Job& job, const hsr::Frame& frame,
                           std::vector<std::string>& written) {
  if (!f.instanceIds.empty()) {
    hsr::writeInstanceIds(frame, hsr::faceMeshIndices(job.scene), f.instanceIds);
    written.push_back(f.instanceIds);
  }
  if (!f.barycentric.empty()) {
    hsr::writeBarycentrics(job.scene, job.camera, frame, f.barycentric);
    written.push_back(f.barycentric);
  }
}

int runRender(const RenderFlags& f) {
  struct Output {
    const std::string& path;  // empty: not requested
    hsr::OutputKind kind;
    void (*write)(const hsr::Frame&, const std::string&);
  };
  const Output outputs[] = {{f.out, hsr::OutputKind::Color, hsr::writeColorPng},
                            {f.ids, hsr::OutputKind::FaceIds, hsr::writeFaceIds},
                            {f.depth, hsr::OutputKind::Depth, hsr::writeDepth},
                            {f.depthImage, hsr::OutputKind::DepthImage, hsr::writeDepthImage},
                            {f.overdrawImage, hsr::OutputKind::OverdrawImage, hsr::writeOverdrawImage}};
  // Reject output names no writer knows, or that name no file, a special file or another
  // output's file, before any work is done.
  hsr::cli::checkOutputSet(f.outputFlags);
  for (const Output& o : outputs)
    if (!o.path.empty()) hsr::checkOutputPath(o.kind, o.path);
  if (f.view.depthOnly && (!f.out.empty() || !f.ids.empty()))
    throw InputError("--depth-only keeps no colour or face ids: drop --out/--ids or --depth-only");
  if (f.view.depthOnly && f.verify) throw InputError("--verify compares face ids, which --depth-only does not keep");
  const hsr::FrameOutputs kept = f.view.frameOutputs();
  if (!f.out.empty() && !has(kept, hsr::FrameOutputs::Color))
    throw InputError("--out: --outputs " + f.view.outputs + " keeps no colour (add color)");
  if (!f.ids.empty() && !has(kept, hsr::FrameOutputs::FaceIds))
    throw InputError("--ids: --outputs " + f.view.outputs + " keeps no face ids (add face)");
  if (f.verify && !has(kept, hsr::FrameOutputs::IdsAndDepth))
    throw InputError("--verify compares face and triangle ids: --outputs " + f.view.outputs + " lacks face or triangle");
  checkAttributeOutputs(f, kept);
  if (f.shadows && !has(kept, hsr::FrameOutputs::TriangleIds))
    throw InputError("--shadows finds each pixel's point on its triangle: the outputs kept (" +
                     hsr::frameOutputsName(kept) + ") have no triangle ids (add triangle)");
  const std::optional<hsr::Light> lightFromFlags = flagLight(f);
  if (f.shadows) hsr::checkShadowOptions(f.shadowOptions);

  if (!f.svg.empty()) hsr::checkSvgPath(f.svg);

  Job job = f.view.prepare();
  if (!f.svg.empty() && !hsr::paintsPolygons(job.options.algorithm))
    throw InputError("--svg: " + job.options.algorithm +
                     " paints no polygons (vector output needs --algorithm painter, newell or bsp)");
  job.options.verify = f.verify;
  job.options.countWrites = !f.overdrawImage.empty();
  auto start = std::chrono::steady_clock::now();
  hsr::Frame frame = hsr::render(job.scene, job.camera, job.options);
  if (f.shadows) {
    hsr::ShadowOptions shadowOptions = f.shadowOptions;
    shadowOptions.depthFormat = job.options.depthFormat;
    shadowOptions.threads = job.options.threads;
    const hsr::Light light = lightFromFlags ? *lightFromFlags
                             : job.scene.light ? *job.scene.light
                                               : hsr::defaultLight(job.camera);
    hsr::addShadows(job.scene, job.camera, frame, light, shadowOptions, f.verify);
  }
  double wallMs = millisecondsSince(start);

  // All outputs or none: each is written to a temporary file, and all are renamed at the end.
  std::vector<std::string> written;
  std::string statsJson;
  {
    hsr::OutputBatch batch;
    if (!f.svg.empty()) {  // the same order again, as polygons (timed apart from the frame)
      const auto svgStart = std::chrono::steady_clock::now();
      hsr::writeSvg(job.scene, job.camera, job.options, f.svg);
      frame.stats.addTime("svg", millisecondsSince(svgStart));
      written.push_back(f.svg);
    }
    statsJson = frame.stats.toJson();
    for (const Output& o : outputs) {
      if (o.path.empty()) continue;
      o.write(frame, o.path);
      written.push_back(o.path);
    }
    writeAttributeOutputs(f, job, frame, written);
    if (!f.stats.empty() && f.stats != "-") {
      hsr::writeTextFile(statsJson + "\n", f.stats);
      written.push_back(f.stats);
    }
    batch.commit();
  }

  if (f.json || f.stats == "-")  // --stats -: the statistics JSON on standard output
    fmt::print("{}\n", statsJson);
  else if (!f.quiet) {
    printSummary(job, frame.stats, wallMs, written);
    if (f.shadows) printShadowSummary(frame.stats);
  }
  return 0;
}

Runner setupRender(CLI::App& cmd) {
  auto f = std::make_shared<RenderFlags>();
  f->view.declare(cmd);
  const char* outputs = "Outputs (written atomically, only after a successful render)";
  cmd.add_option("-o,--out", f->out, "Colour image")->type_name("COLOR.png")->group(outputs);
  cmd.add_option("--ids", f->ids, "Face ids: PNG (24-bit id+1, 0 = background) or .npy (int32, -1)")
      ->type_name("IDS.png|.npy")
      ->group(outputs);
  cmd.add_option("--depth", f->depth, "Eye depth, float32, +inf background")
      ->type_name("DEPTH.npy|.pfm|.exr|.f32")
      ->group(outputs);
  cmd.add_option("--depth-image", f->depthImage, "Depth as a grey picture, near white, background black")
      ->type_name("DEPTH.png")
      ->group(outputs);
  cmd.add_option("--overdraw-image", f->overdrawImage,
                 "Fragments written per pixel, on a fixed colour scale: black 0, blue 1, green 2, yellow 3, orange "
                 "4, red 5, magenta 6, white 7 or more")
      ->type_name("OVERDRAW.png")
      ->group(outputs);
  cmd.add_option("--instance-ids", f->instanceIds,
                 "Instance ids: per pixel the mesh its face belongs to (its position among the scene's meshes, as "
                 "'hsr info' lists them); PNG (24-bit id+1, 0 = background) or .npy (int32, -1)")
      ->type_name("INST.png|.npy")
      ->group(outputs);
  cmd.add_option("--barycentric", f->barycentric,
                 "Barycentric coordinates of each pixel centre on the visible triangle, float32 (H, W, 3), 0 on the "
                 "background; for a triangle face, of its vertices in file order (--ids names the face)")
      ->type_name("BARY.npy")
      ->group(outputs);
  cmd.add_option("--stats", f->stats, "Statistics JSON ('-': standard output, as --json)")->type_name("STATS.json")->group(outputs);
  cmd.add_option("--svg", f->svg,
                 "Vector image: the painting order of painter, newell or bsp as SVG polygons, back to front "
                 "(docs/vector-output.md)")
      ->type_name("IMAGE.svg")
      ->group(outputs);
  const std::pair<const char*, std::string*> outputFlags[] = {
      {"--out", &f->out},           {"--ids", &f->ids},
      {"--depth", &f->depth},       {"--depth-image", &f->depthImage},
      {"--overdraw-image", &f->overdrawImage}, {"--instance-ids", &f->instanceIds},
      {"--barycentric", &f->barycentric},      {"--stats", &f->stats},
      {"--svg", &f->svg}};
  for (auto [flag, path] : outputFlags)
    f->outputFlags.push_back({flag, cmd.get_option(flag), path, std::string_view(flag) == "--stats"});
  cmd.add_flag("--verify", f->verify, "Also render the exact reference and count wrong/ambiguous pixels");
  const char* shadows = "Shadows (docs/shadows.md)";
  CLI::Option* shadowsFlag =
      cmd.add_flag("--shadows", f->shadows,
                   "Shadow-map the image: a depth map rendered by the z-buffer from the light, each visible pixel "
                   "tested against it, shadowed pixels darkened in the colour output (with --verify, also checked "
                   "against shadow rays)")
          ->group(shadows);
  CLI::Option* lightDirFlag =
      cmd.add_option("--light-dir", f->lightDir,
                     "A directional light: the direction its light travels (overrides the scene's light; default: "
                     "the scene's, else a sun over the viewer's left shoulder)")
          ->type_name("X,Y,Z")
          ->needs(shadowsFlag)
          ->group(shadows);
  cmd.add_option("--light-pos", f->lightPos, "A point light at this position, outside the scene's bounds")
      ->type_name("X,Y,Z")
      ->needs(shadowsFlag)
      ->excludes(lightDirFlag)
      ->group(shadows);
  cmd.add_option("--shadow-map-size", f->shadowOptions.mapSize,
                 fmt::format("Shadow map side in texels, {} to {}", hsr::kMinShadowMapSize, hsr::kMaxShadowMapSize))
      ->type_name("N")
      ->needs(shadowsFlag)
      ->capture_default_str()
      ->group(shadows);
  cmd.add_option("--shadow-bias", f->shadowOptions.bias,
                 "Depth bias in texel widths at the receiver (besides the depth format's rounding): an occluder "
                 "nearer the light than the receiver's plane by less than this casts no shadow")
      ->type_name("TEXELS")
      ->needs(shadowsFlag)
      ->capture_default_str()
      ->group(shadows);
  cmd.add_flag("--json", f->json, "Print the statistics JSON to stdout instead of the summary");
  cmd.add_flag("-q,--quiet", f->quiet, "Print nothing on success");

  std::string footer = "Algorithms ('hsr algorithms' lists their parameters and guarantees):\n";
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) footer += fmt::format("  {:<12} {}\n", a.name, a.summary);
  footer +=
      "\nExamples:\n"
      "  hsr render builtin:painter-cycle --algorithm zbuffer --param raster=halfspace --overdraw-image o.png\n"
      "  hsr render builtin:cubes -o cubes.png\n"
      "  hsr render model.obj --camera cam.json --size 1920x1080 --ids ids.png --depth depth.npy --verify\n"
      "  hsr render scene.json --eye 4,3,5 --target 0,0,0 --depth-format u16:z --depth-image z.png\n"
      "  hsr render builtin:city --shadows --light-dir 1,-2,0.5 --shadow-map-size 4096 -o city.png --verify";
  cmd.footer(footer);
  return [f] { return runRender(*f); };
}

struct BenchFlags {
  ViewFlags view;
  int frames = 10, warmup = 2;
  double warmupSeconds = 1;  // and at least this long (see setupBench)
  bool json = false, occlusion = false, orbit = false;
};

using hsr::cli::median;

// What a benchmark measured: whole frames, each frame's stages (Stats::time_ms), and the first
// frame of the process apart (it builds what later frames reuse, such as a BSP tree).
struct BenchRecord {
  std::vector<double> frameMs;
  std::vector<std::pair<std::string, std::vector<double>>> stageMs;  // in pipeline order
  double firstMs = 0;
  std::vector<std::pair<std::string, double>> firstStages;
  int warmupFrames = 0;
  double warmupMs = 0;
  int poses = 1;

  void addStages(const hsr::Stats& stats) {
    for (const auto& [stage, ms] : stats.time_ms) {
      auto it = std::find_if(stageMs.begin(), stageMs.end(), [&](const auto& s) { return s.first == stage; });
      if (it == stageMs.end()) it = stageMs.insert(stageMs.end(), {stage, {}});
      it->second.push_back(ms);
    }
  }
};

BenchRecord timeFrames(const BenchFlags& f, const Job& job, hsr::Frame& frame) {
  hsr::OcclusionBuffer occlusion;
  BenchRecord rec;
  // --orbit: every frame from another side of the scene, poses evenly around it.
  const std::vector<hsr::Camera> cameras =
      f.orbit ? hsr::orbitCameras(job.camera, job.scene.bounds().center(), f.frames) : std::vector{job.camera};
  rec.poses = int(cameras.size());
  std::optional<hsr::Renderer> renderer;  // one algorithm object for every frame: what it builds, built once
  if (!f.occlusion) renderer.emplace(job.scene, job.options);
  int rendered = 0;
  // One frame, timed; the first of the process is recorded apart.
  auto renderOnce = [&](size_t pose) {
    const auto start = std::chrono::steady_clock::now();
    const hsr::Camera& camera = cameras[pose % cameras.size()];
    if (f.occlusion)  // depth kept in tiles, no image: what an occlusion culler pays per frame
      occlusion.render(job.scene, camera, {job.options.depthFormat, job.options.cull, job.options.threads});
    else
      renderer->render(camera, frame);  // reuses the frame's buffers
    const double ms = millisecondsSince(start);
    if (rendered++ == 0) {
      rec.firstMs = ms;
      if (!f.occlusion) rec.firstStages = frame.stats.time_ms;
    }
    return ms;
  };
  // Warm-up: f.warmup frames, and more until f.warmupSeconds have passed.
  const auto warmupStart = std::chrono::steady_clock::now();
  while (rec.warmupFrames < f.warmup || (f.warmupSeconds > 0 && millisecondsSince(warmupStart) < 1e3 * f.warmupSeconds))
    renderOnce(size_t(rec.warmupFrames++));
  rec.warmupMs = millisecondsSince(warmupStart);
  for (int i = 0; i < f.frames; ++i) {
    rec.frameMs.push_back(renderOnce(size_t(i)));
    if (!f.occlusion) rec.addStages(frame.stats);
  }
  if (f.occlusion) occlusion.depthImage(frame);  // its statistics, with covered_pixels (not timed)
  return rec;
}

// The stages every timed frame ran (a stage of only some frames, such as a build, is the first frame's).
bool everyFrame(const BenchRecord& rec, const std::vector<double>& stageMs) { return stageMs.size() == rec.frameMs.size(); }

std::string stageText(const BenchRecord& rec) {
  std::string text;
  for (const auto& [stage, ms] : rec.stageMs)
    if (everyFrame(rec, ms)) text += fmt::format("{}{} {:.3f}", text.empty() ? "" : ", ", stage, median(ms));
  return text;
}

void printBenchText(const BenchRecord& rec, const Job& job, const hsr::Frame& frame, int threads) {
  const double min = *std::min_element(rec.frameMs.begin(), rec.frameMs.end());
  fmt::print("{} on {}: {}x{}, {} threads{}: median {:.3f} ms, min {:.3f} ms over {} frames ({} warm-up in {:.2f} s)\n",
             frame.stats.algorithm, job.sceneName, frame.width, frame.height, threads,
             rec.poses > 1 ? fmt::format(", an orbit of {} poses", rec.poses) : "", median(rec.frameMs), min,
             rec.frameMs.size(), rec.warmupFrames, rec.warmupMs / 1e3);
  if (rec.stageMs.empty()) return;
  fmt::print("  per frame, median ms: {}\n", stageText(rec));
  std::string first;
  for (const auto& [stage, ms] : rec.firstStages)
    if (stage == "build") first = fmt::format(" (build {:.3f} ms, once: later frames reuse it)", ms);
  fmt::print("  first frame: {:.3f} ms{}\n", rec.firstMs, first);
}

Json benchJson(const BenchRecord& rec, const Job& job, const hsr::Frame& frame, int threads) {
  // Every figure travels with what produced it: scene, size, threads, build.
  Json out;
  out["scene"] = job.sceneName;
  out["size"] = fmt::format("{}x{}", frame.width, frame.height);
  out["threads"] = threads;
  out["outputs"] = hsr::frameOutputsName(job.options.outputs);
  out["kernel_isa"] = hsr::kernelInstructionSet();
  out["cpu"] = hsr::cli::cpuModel();
  out["frames"] = rec.frameMs.size();
  out["poses"] = rec.poses;
  out["warmup"] = rec.warmupFrames;
  out["warmup_ms"] = rec.warmupMs;
  out["median_ms"] = median(rec.frameMs);
  out["min_ms"] = *std::min_element(rec.frameMs.begin(), rec.frameMs.end());
  out["frame_ms"] = rec.frameMs;
  out["first_frame_ms"] = rec.firstMs;
  Json firstStages = Json::object(), stages = Json::object();
  for (const auto& [stage, ms] : rec.firstStages) firstStages[stage] = ms;
  for (const auto& [stage, ms] : rec.stageMs)
    if (everyFrame(rec, ms)) stages[stage] = median(ms);
  out["first_frame_stages_ms"] = firstStages;
  out["stage_median_ms"] = stages;
  out["build"] = {{"version", HSR_VERSION},
                  {"build_type", HSR_BUILD_TYPE},
                  {"flags", HSR_BUILD_FLAGS},
#ifdef __clang__
                  {"compiler", "clang " __clang_version__},
#else
                  {"compiler", "gcc " __VERSION__},
#endif
#ifdef NDEBUG
                  {"assertions", false}
#else
                  {"assertions", true}
#endif
  };
  const Json stats = Json::parse(frame.stats.toJson());
  for (const auto& [key, value] : stats.items())
    if (!out.contains(key)) out[key] = value;
  return out;
}

int runBench(const BenchFlags& f) {
  Job job = f.view.prepare();
  if (f.occlusion && (job.options.algorithm != "zbuffer" || !job.options.params.empty()))
    throw hsr::InputError("--occlusion: times the occlusion buffer (the tiled z-buffer, depth only); drop "
                          "--algorithm and --param");
  hsr::Frame frame;
  const BenchRecord rec = timeFrames(f, job, frame);
  const int threads = hsr::resolveThreads(job.options.threads);
  if (f.json)
    fmt::print("{}\n", benchJson(rec, job, frame, threads).dump(2));
  else
    printBenchText(rec, job, frame, threads);
  return 0;
}

Runner setupBench(CLI::App& cmd) {
  auto f = std::make_shared<BenchFlags>();
  f->view.declare(cmd);
  cmd.add_option("--frames", f->frames, "Timed frames")->type_name("N")->check(CLI::Range(1, 1000000))->capture_default_str();
  cmd.add_option("--warmup", f->warmup, "Untimed frames first")->type_name("K")->check(CLI::Range(0, 1000000))->capture_default_str();
  cmd.add_option("--warmup-time", f->warmupSeconds,
                 "Untimed frames for at least this many seconds too (0: --warmup frames only). On the 2-core VMs "
                 "this project is measured on, a new process runs 1.5-3x slower for its first ~0.5 s (docs/benchmarks.md)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd.add_flag("--occlusion", f->occlusion,
               "Time the occlusion buffer (hsr::OcclusionBuffer::render): the tiled z-buffer's depth only, kept in "
               "tiles, no image written (what an occlusion culler pays per frame)");
  cmd.add_flag("--orbit", f->orbit,
               "Render each timed frame from another pose: --frames poses evenly around the scene (the camera "
               "turned about its up axis through the scene's centre), so what an algorithm builds once per scene "
               "(a BSP tree) is timed apart from what it does per view");
  cmd.add_flag("--json", f->json,
               "Print one JSON object: median_ms, min_ms, frames, frame_ms, stage_median_ms, first_frame_ms, "
               "first_frame_stages_ms, poses, threads, scene, size, build and the last frame's statistics");
  cmd.footer(
      "Times are wall-clock milliseconds of whole render() calls (with --occlusion, of OcclusionBuffer::render "
      "calls).\n\n"
      "Examples:\n"
      "  hsr bench builtin:cubes --frames 20\n"
      "  hsr bench builtin:sphere --size 1920x1080 --outputs depth,face,color\n"
      "  hsr bench builtin:city --size 1920x1080 --algorithm bsp --orbit --frames 20\n"
      "  hsr bench model.obj --camera cam.json --size 1920x1080 --algorithm zbuffer --threads 1 --json");
  return [f] { return runBench(*f); };
}

Runner setupScenes(CLI::App& cmd) {
  auto json = std::make_shared<bool>(false);
  auto names = std::make_shared<bool>(false);
  cmd.add_flag("--json", *json, "Print a JSON array instead");
  cmd.add_flag("--names", *names, "Print only the names, one per line (for scripts)");
  cmd.footer("Use one as SCENE: builtin:NAME or builtin:NAME?param=value&param=value");
  return [json, names] {
    if (*names) {
      for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) fmt::print("{}\n", b.name);
      return 0;
    }
    if (*json) {
      Json out = Json::array();
      for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) {
        Json params = Json::array();
        for (const hsr::BuiltinParam& p : b.params)
          params.push_back({{"name", p.name}, {"default", p.defaultValue}, {"help", p.help}});
        out.push_back({{"name", b.name}, {"summary", b.summary}, {"params", params}});
      }
      fmt::print("{}\n", out.dump(2));
      return 0;
    }
    for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) {
      fmt::print("builtin:{:<16} {}\n", b.name, b.summary);
      for (const hsr::BuiltinParam& p : b.params) fmt::print("    {:<20} {}\n", p.name + "=" + p.defaultValue, p.help);
    }
    return 0;
  };
}

// The guarantees an algorithm gives with other values of its choice parameters, where they
// differ from its default one: (parameter, value, guarantee).
std::vector<std::tuple<std::string, std::string, std::string>> otherGuarantees(const hsr::AlgorithmInfo& a) {
  std::vector<std::tuple<std::string, std::string, std::string>> out;
  if (!a.guaranteeFor) return out;
  const std::string byDefault = a.guaranteeWith(hsr::resolveParams(a, {})).describe();
  for (const hsr::ParamSpec& p : a.params)
    for (const std::string& value : p.choices) {
      const std::string g = a.guaranteeWith(hsr::resolveParams(a, {{p.name, value}})).describe();
      if (g != byDefault) out.emplace_back(p.name, value, g);
    }
  return out;
}

// `hsr algorithms`: the registry, as text or JSON.
Json algorithmsJson() {
  Json out = Json::array();
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) {
    Json params = Json::array();
    for (const hsr::ParamSpec& p : a.params) {
      Json entry = {{"name", p.name}, {"type", hsr::paramTypeName(p.type)}, {"default", p.defaultValue}};
      if (p.type == hsr::ParamType::Choice) entry["values"] = p.choices;
      if (p.type == hsr::ParamType::Int || p.type == hsr::ParamType::Real || p.type == hsr::ParamType::Size)
        entry["range"] = {p.min, p.max};
      entry["help"] = p.help;
      params.push_back(entry);
    }
    Json others = Json::array();
    for (const auto& [param, value, guarantee] : otherGuarantees(a))
      others.push_back({{"param", param}, {"value", value}, {"guarantee", guarantee}});
    out.push_back({{"name", a.name}, {"summary", a.summary}, {"source", a.source},
                   {"guarantee", a.guaranteeWith(hsr::resolveParams(a, {})).describe()}, {"params", params},
                   {"guarantee_with", others}});
  }
  return out;
}

// `text` broken into lines of at most `width` characters, each after `indent`.
std::string wrapped(const std::string& text, const std::string& indent, size_t width = 96) {
  std::string out, line;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (!line.empty() && indent.size() + line.size() + 1 + word.size() > width) {
      out += indent + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += indent + line + "\n";
  return out;
}

void printAlgorithms() {
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) {
    const hsr::Guarantee byDefault = a.guaranteeWith(hsr::resolveParams(a, {}));
    fmt::print("{}\n  {}\n  source: {}\n{}", a.name, a.summary, a.source,
               wrapped("guarantee: " + byDefault.describe(), "  "));
    if (!byDefault.condition.empty() && byDefault.kind == hsr::Guarantee::Kind::Exact)
      fmt::print("{}", wrapped("(" + byDefault.condition + ")", "    "));
    for (const auto& [param, value, guarantee] : otherGuarantees(a))
      fmt::print("{}", wrapped("with " + param + "=" + value + ": " + guarantee, "    "));
    if (a.params.empty()) fmt::print("  parameters: none\n");
    for (const hsr::ParamSpec& p : a.params) {
      std::string values = p.type == hsr::ParamType::Choice ? fmt::format("{}", fmt::join(p.choices, "|"))
                           : p.type == hsr::ParamType::Bool ? "on|off"
                           : p.type == hsr::ParamType::Size
                               ? fmt::format("WxH|full (each in [{}, {}])", p.min, p.max)
                               : fmt::format("{} in [{}, {}]", hsr::paramTypeName(p.type), p.min, p.max);
      fmt::print("  --param {}={}  (default {})\n{}", p.name, values, p.defaultValue, wrapped(p.help, "      "));
    }
    fmt::print("\n");
  }
  fmt::print("Set a parameter with 'hsr render SCENE --algorithm NAME --param KEY=VALUE'.\n");
}

Runner setupAlgorithms(CLI::App& cmd) {
  auto json = std::make_shared<bool>(false);
  cmd.add_flag("--json", *json, "Print a JSON array instead");
  return [json] {
    if (*json) fmt::print("{}\n", algorithmsJson().dump(2));
    else printAlgorithms();
    return 0;
  };
}

Json boundsJson(const hsr::Bounds3& b) {
  if (b.empty()) return nullptr;
  return {{"min", {b.lo.x, b.lo.y, b.lo.z}}, {"max", {b.hi.x, b.hi.y, b.hi.z}}};
}

int runInfo(const std::string& sceneName, bool json) {
  hsr::Scene scene = hsr::loadScene(sceneName);
  const hsr::Bounds3 bounds = scene.bounds();
  const hsr::SceneProblems& problems = scene.problems;
  if (json) {
    Json out;
    out["scene"] = sceneName;
    out["faces"] = scene.faceCount();
    out["triangles"] = scene.triangles.size();
    out["vertices"] = scene.positions.size();
    out["meshes"] = Json::array();
    for (const hsr::MeshRange& m : scene.meshes)
      out["meshes"].push_back({{"name", m.name}, {"first_face", m.firstFace}, {"faces", m.faceCount}});
    out["bounds"] = boundsJson(bounds);
    out["problems"] = {{"degenerate_faces", problems.degenerateFaces},
                       {"non_planar_faces", problems.nonPlanarFaces},
                       {"concave_faces", problems.concaveFaces},
                       {"notes", problems.notes}};
    out["camera"] = scene.camera ? Json::parse(hsr::cameraSpecToJson(*scene.camera)) : Json(nullptr);
    fmt::print("{}\n", out.dump(2));
    return 0;
  }
  fmt::print("{}\n  faces {}, triangles {}, vertices {}\n", sceneName, scene.faceCount(), scene.triangles.size(),
             scene.positions.size());
  // A file can hold thousands of meshes: the text view shows the first few.
  constexpr size_t kMeshesShown = 20;
  fmt::print("  meshes {}\n", scene.meshes.size());
  for (size_t i = 0; i < std::min(scene.meshes.size(), kMeshesShown); ++i)
    fmt::print("    {:<24} {} faces\n", scene.meshes[i].name.empty() ? "(unnamed)" : scene.meshes[i].name,
               scene.meshes[i].faceCount);
  if (scene.meshes.size() > kMeshesShown) fmt::print("    ... and {} more (see --json)\n", scene.meshes.size() - kMeshesShown);
  if (bounds.empty())
    fmt::print("  bounds: empty\n");
  else
    fmt::print("  bounds [{:.6g}, {:.6g}, {:.6g}] .. [{:.6g}, {:.6g}, {:.6g}] (--json: exact)\n", bounds.lo.x, bounds.lo.y, bounds.lo.z, bounds.hi.x,
               bounds.hi.y, bounds.hi.z);
  fmt::print("  problems: {} degenerate (not drawn), {} non-planar, {} concave faces\n", problems.degenerateFaces,
             problems.nonPlanarFaces, problems.concaveFaces);
  for (const std::string& note : problems.notes) fmt::print("    {}\n", note);
  fmt::print("  camera: {}\n",
             scene.camera ? Json::parse(hsr::cameraSpecToJson(*scene.camera)).dump() : "none (hsr frames the bounds)");
  return 0;
}

Runner setupInfo(CLI::App& cmd) {
  auto scene = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd.add_option("scene", *scene, "Mesh file, scene JSON or builtin:NAME")->type_name("SCENE")->required();
  cmd.add_flag("--json", *json, "Print one JSON object instead");
  return [scene, json] { return runInfo(*scene, *json); };
}

Runner setupHelp(CLI::App& cmd);

// The subcommands, in the order `hsr help` lists them.
struct Subcommand {
  const char* name;
  const char* summary;
  Runner (*setup)(CLI::App&);
};
const Subcommand kSubcommands[] = {
    {"render", "Render a scene to colour, face-id and depth files, with statistics", setupRender},
    {"bench", "Time repeated renders of a scene: median and minimum", setupBench},
    {"algorithms", "List the visibility algorithms: parameters, sources and guarantees", setupAlgorithms},
    {"scenes", "List the built-in scenes and their parameters", setupScenes},
    {"info", "Describe a scene: counts, meshes, bounds, problems, camera", setupInfo},
    {"compare", "The documents' comparisons: every algorithm on the study's scenes, a table, results.json and an "
                "HTML report", hsr::cli::setupCompare},
    {"precision", "Depth precision per format: separable depth differences and the spread of stored values",
     hsr::cli::setupPrecision},
    {"help", "Explain hsr or one of its commands", setupHelp},
};

Runner setupHelp(CLI::App& cmd) {
  auto topic = std::make_shared<std::string>();
  cmd.add_option("command", *topic, "Command to explain")->type_name("COMMAND");
  const CLI::App* root = cmd.get_parent();
  return [root, topic] {
    // App::help() of the root would describe the subcommand being run (this one): format the
    // root page directly.
    if (topic->empty()) {
      std::cout << root->get_formatter()->make_help(root, root->get_name(), CLI::AppFormatMode::Normal);
      return 0;
    }
    if (*topic == "algorithms") {  // the listing itself is the help
      printAlgorithms();
      return 0;
    }
    std::string known;
    for (const Subcommand& s : kSubcommands) {
      if (*topic == s.name) {
        std::cout << root->get_subcommand(s.name)->help(root->get_name());
        return 0;
      }
      known += (known.empty() ? "" : ", ") + std::string(s.name);
    }
    throw InputError("help: unknown command '" + *topic + "' (commands: " + known + ")");
  };
}

int runCli(int argc, char** argv) {
  CLI::App app("hsr " HSR_VERSION " - hidden-surface removal: an exact z-buffer and a lab of classic visibility algorithms",
               "hsr");
  app.set_version_flag("--version", "hsr " HSR_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Run 'hsr help COMMAND' or 'hsr COMMAND --help' for a command's flags.\n"
      "Exit status: 0 success, 2 bad usage or bad input (one line on stderr), 1 any other failure.");
  std::map<const CLI::App*, Runner> runners;
  std::string maxMemory;
  std::vector<CLI::Option*> maxMemoryFlags;
  for (const Subcommand& s : kSubcommands) {
    CLI::App* cmd = app.add_subcommand(s.name, s.summary);
    runners[cmd] = s.setup(*cmd);
    maxMemoryFlags.push_back(cmd->add_option("--max-memory", maxMemory,
                    "Refuse up front a request that would need more memory than this (e.g. 512M, 4G; default: the "
                    "machine's available memory)")
        ->type_name("SIZE"));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::vector<CLI::App*> chosen = app.get_subcommands();
    std::string topic = chosen.empty() ? "hsr help" : "hsr help " + chosen.front()->get_name();
    throw InputError(std::string(e.what()) + " (see '" + topic + "')");
  }
  if (std::any_of(maxMemoryFlags.begin(), maxMemoryFlags.end(), [](CLI::Option* o) { return o->count() > 0; }))
    hsr::setMemoryLimit(hsr::parseMemorySize(maxMemory));
  return runners.at(app.get_subcommands().front())();  // require_subcommand(1): exactly one
}

// One line on stderr, whatever the message holds.
int fail(int status, std::string message) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::cout.flush();
  std::cerr << "hsr: " << message << '\n';
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return runCli(argc, argv);
  } catch (const InputError& e) {
    return fail(2, e.what());
  } catch (const std::bad_alloc&) {
    return fail(1, "error: out of memory");
  } catch (const std::exception& e) {
    return fail(1, std::string("error: ") + e.what());
  } catch (...) {
    return fail(1, "error: unknown exception");
  }
}

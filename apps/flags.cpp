// The flags `hsr render` and `hsr bench` share (flags.hpp) and the parsers of flag values: each
// parser throws InputError "--flag 'text': problem" (exit status 2). Called by the subcommands'
// setup functions (declare) and runners (prepare). Also cliMessage (commands.hpp): the library's
// keyed errors worded with the flags that set what they are about.
#include "flags.hpp"

#include "commands.hpp"

#include <fmt/core.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

namespace hsr::cli {
namespace {

constexpr int kMaxImageSide = 16384;

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

hsr::Rgba8 parseColor(const std::string& text) {
  std::vector<double> v = parseNumbers("--background", text, 3, 4, "r,g,b or r,g,b,a");
  for (double c : v)
    if (c < 0 || c > 255 || c != std::floor(c))
      throw InputError("--background '" + text + "': components are integers 0 to 255");
  return {uint8_t(v[0]), uint8_t(v[1]), uint8_t(v[2]), uint8_t(v.size() == 4 ? v[3] : 255)};
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

}  // namespace

ImageSize parseSize(const std::string& text, const std::string& what) {
  size_t x = text.find_first_of("xX");
  ImageSize size;
  auto side = [](std::string_view s, int& out) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size() && out >= 1 && out <= kMaxImageSide;
  };
  if (x == std::string::npos || !side(std::string_view(text).substr(0, x), size.width) ||
      !side(std::string_view(text).substr(x + 1), size.height))
    throw InputError(fmt::format("{} '{}': expected WIDTHxHEIGHT, each 1 to {}", what, text, kMaxImageSide));
  return size;
}

std::string readTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path + ": cannot read: " + std::strerror(errno));
  return text.str();
}

hsr::dvec3 parseVec3(const std::string& flag, const std::string& text) {
  std::vector<double> v = parseNumbers(flag, text, 3, 3, "x,y,z");
  return {v[0], v[1], v[2]};
}

std::string cullName(hsr::Cull cull) { return nameOf(kCullNames, cull); }

void ViewFlags::declare(CLI::App& cmd) {
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
  cmd.add_option("--switch-off", switchesOff,
                 "Turn off one of the tiled z-buffer's optimisations, repeatable: defer-back-faces, defer-clusters, "
                 "mesh-culling, background-pump. The image is the same bits either way: to measure what each saves")
      ->type_name("NAME")
      ->check(CLI::IsMember(std::vector<std::string>(std::begin(hsr::kTiledSwitchNames), std::end(hsr::kTiledSwitchNames))));
  CLI::Option* depthOnlyFlag = cmd.add_flag(
      "--depth-only", depthOnly,
      "z-buffer resolves only depth: no face ids or colour (depth is the same bits as with them)");
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

std::string cliMessage(const hsr::InputError& error) {
  const char* flag = "";
  switch (error.setting()) {
    case hsr::Setting::None: return error.what();
    case hsr::Setting::Algorithm: flag = "--algorithm"; break;
    case hsr::Setting::Param: flag = "--param"; break;
    case hsr::Setting::Size: flag = "--size"; break;
    case hsr::Setting::DepthFormat: flag = "--depth-format"; break;
    case hsr::Setting::Verify: flag = "--verify"; break;
    case hsr::Setting::SwitchOff: flag = "--switch-off"; break;
    case hsr::Setting::Svg: flag = "--svg"; break;
    case hsr::Setting::OverdrawImage: flag = "--overdraw-image"; break;
    case hsr::Setting::ShadowMapSize: flag = "--shadow-map-size"; break;
    case hsr::Setting::ShadowBias: flag = "--shadow-bias"; break;
    case hsr::Setting::MaxMemory: flag = "--max-memory"; break;
  }
  return error.worded(flag);
}

hsr::FrameOutputs ViewFlags::frameOutputs() const {
  if (depthOnly) return hsr::FrameOutputs::DepthOnly;
  return outputsFlag->count() ? hsr::parseFrameOutputs(outputs, "--outputs") : hsr::FrameOutputs::All;
}

std::map<std::string, std::string> ViewFlags::parsedParams() const {
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

bool ViewFlags::openGlFlagsGiven() const {
  return !eye.empty() || !target.empty() || !up.empty() || fovFlag->count() || orthoFlag->count();
}

Job ViewFlags::prepareOptions() const {
  Job job;
  job.sceneName = scene;
  parseSize(size);
  job.options = options;
  job.options.params = parsedParams();
  for (const std::string& name : switchesOff) hsr::switchOff(job.options.tiled, name);
  job.options.outputs = frameOutputs();
  job.options.cull = valueOf(kCullNames, cull);
  job.options.shading = valueOf(kShadingNames, shading);
  if (!depthFormat.empty()) job.options.depthFormat = hsr::DepthFormat::parse(depthFormat);
  if (!background.empty()) job.options.background = parseColor(background);
  const hsr::AlgorithmInfo* algorithm = hsr::findAlgorithm(options.algorithm);
  if (!algorithm)
    throw InputError(fmt::format("--algorithm '{}': unknown (known: {})", options.algorithm, algorithmNames()));
  hsr::resolveParams(*algorithm, job.options.params);  // a parameter typo fails before the scene loads
  return job;
}

ViewFlags::CameraFlags ViewFlags::cameraFlags() const {
  CameraFlags c;
  if (!cameraFile.empty()) c.file = hsr::parseCameraJson(readTextFile(cameraFile), cameraFile);
  if (!eye.empty()) c.eye = parseVec3("--eye", eye);
  if (!target.empty()) c.target = parseVec3("--target", target);
  if (!up.empty()) c.up = parseVec3("--up", up);
  return c;
}

void ViewFlags::placeCamera(Job& job, const CameraFlags& c, const hsr::Bounds3& bounds) const {
  ImageSize imageSize = parseSize(size);
  hsr::CameraSpec spec = c.file             ? *c.file
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
  if (!c.file && (c.eye || c.target || orthoFlag->count())) {
    spec.near.reset();
    spec.far.reset();
  }
  if (c.eye) spec.eye = *c.eye;
  if (c.target) spec.target = *c.target;
  if (c.up) spec.up = *c.up;
  if (fovFlag->count()) spec.fovyDeg = fov;
  if (orthoFlag->count()) spec.orthoHeight = ortho;
  if (nearFlag->count()) spec.near = near;
  if (farFlag->count()) spec.far = far;
  if (!sizeFlag->count() && spec.width && spec.height) imageSize = {*spec.width, *spec.height};
  warnPrincipalPointOutside(spec, imageSize, cameraName);
  job.camera = hsr::resolveCamera(spec, imageSize.width, imageSize.height, bounds, cameraName);
}

Job ViewFlags::prepare() const {
  Job job = prepareOptions();
  const CameraFlags camera = cameraFlags();
  job.scene = hsr::loadScene(scene);
  placeCamera(job, camera, job.scene.bounds());
  return job;
}

void ShadowFlags::declareShadows(CLI::App& cmd, const std::string& shadowsHelp) {
  const char* group = "Shadows (docs/shadows.md)";
  CLI::Option* shadowsFlag = cmd.add_flag("--shadows", shadows, shadowsHelp)->group(group);
  CLI::Option* lightDirFlag =
      cmd.add_option("--light-dir", lightDir,
                     "A directional light: the direction its light travels (overrides the scene's light; default: "
                     "the scene's, else a sun over the viewer's left shoulder)")
          ->type_name("X,Y,Z")
          ->needs(shadowsFlag)
          ->group(group);
  cmd.add_option("--light-pos", lightPos, "A point light at this position, outside the scene's bounds")
      ->type_name("X,Y,Z")
      ->needs(shadowsFlag)
      ->excludes(lightDirFlag)
      ->group(group);
  cmd.add_option("--shadow-method", shadowMethod,
                 "single: one map fitted to the whole scene; cascaded: the view's visible depth range split into "
                 "--shadow-cascades slices, one map fitted to each slice's receivers")
      ->type_name("single|cascaded")
      ->needs(shadowsFlag)
      ->capture_default_str()
      ->group(group);
  cascadesFlag = cmd.add_option("--shadow-cascades", shadowOptions.cascades,
                                fmt::format("Cascaded: the slices, one map each, 1 to {}", hsr::kMaxShadowCascades))
                     ->type_name("K")
                     ->needs(shadowsFlag)
                     ->check(CLI::Range(1, hsr::kMaxShadowCascades))
                     ->capture_default_str()
                     ->group(group);
  cmd.add_option("--shadow-map-size", shadowOptions.mapSize,
                 fmt::format("Each shadow map's side in texels, {} to {}", hsr::kMinShadowMapSize, hsr::kMaxShadowMapSize))
      ->type_name("N")
      ->needs(shadowsFlag)
      ->capture_default_str()
      ->group(group);
  cmd.add_option("--shadow-bias", shadowOptions.bias,
                 "Depth bias in texel widths at the receiver (besides the depth format's rounding): an occluder "
                 "nearer the light than the receiver's plane by less than this casts no shadow")
      ->type_name("TEXELS")
      ->needs(shadowsFlag)
      ->capture_default_str()
      ->group(group);
}

std::optional<hsr::Light> ShadowFlags::flagLight() const {
  if (lightDir.empty() && lightPos.empty()) return std::nullopt;
  hsr::Light light;
  light.kind = lightDir.empty() ? hsr::Light::Kind::Point : hsr::Light::Kind::Directional;
  const char* flag = lightDir.empty() ? "--light-pos" : "--light-dir";
  const std::string& text = lightDir.empty() ? lightPos : lightDir;
  light.vector = parseVec3(flag, text);
  hsr::checkLight(light, fmt::format("{} '{}'", flag, text));
  return light;
}

hsr::ShadowOptions ShadowFlags::checkedShadowOptions(const hsr::RenderOptions& view) const {
  hsr::ShadowOptions options = shadowOptions;
  options.method = hsr::parseShadowMethod(shadowMethod, "--shadow-method");
  if (options.method != hsr::ShadowMethod::Cascaded && cascadesFlag && cascadesFlag->count())
    throw InputError("--shadow-cascades: applies to --shadow-method cascaded only");
  options.depthFormat = view.depthFormat;
  options.threads = view.threads;
  hsr::checkShadowOptions(options);
  return options;
}

hsr::Light ShadowFlags::shadowLight(const Job& job) const {
  if (const std::optional<hsr::Light> light = flagLight()) return *light;
  return job.scene.light ? *job.scene.light : hsr::defaultLight(job.camera);
}

}  // namespace hsr::cli

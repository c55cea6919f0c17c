// The flags `hsr render` and `hsr bench` share: the scene, the image size, the camera and the
// algorithm settings, declared on a subcommand, checked, then turned into a loaded scene and a
// resolved camera (a Job). Used by apps/render_cmd.cpp and apps/bench_cmd.cpp; the size parser
// and the file reader also by apps/batch_cmd.cpp.
#pragma once
#include <hsr/hsr.hpp>

#include <CLI/CLI.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hsr::cli {

/// What render and bench share: the scene, the image size, the camera and the algorithm settings.
struct Job {
  std::string sceneName;
  hsr::Scene scene;
  hsr::Camera camera;
  hsr::RenderOptions options;
};

/// An image size in whole pixels.
struct ImageSize {
  int width = 0, height = 0;
};
/// "WxH" (each 1 to 16384); throws InputError "WHAT 'TEXT': expected WIDTHxHEIGHT, ...".
ImageSize parseSize(const std::string& text, const std::string& what = "--size");
/// The whole of a file; throws InputError "path: cannot open: ..." or "... cannot read".
std::string readTextFile(const std::string& path);
/// "x,y,z" as a vector; throws InputError "FLAG 'TEXT': expected x,y,z (finite numbers)".
hsr::dvec3 parseVec3(const std::string& flag, const std::string& text);
/// The name --cull takes for `cull`.
std::string cullName(hsr::Cull cull);

/// The view flags of one subcommand, bound to its CLI11 app by declare().
struct ViewFlags {
  std::string scene, cameraFile, size = "1280x720", depthFormat, background;
  std::string cull = "none", shading = "lambert";
  std::vector<std::string> params;  // --param KEY=VALUE, repeatable
  std::vector<std::string> switchesOff;  // --switch-off NAME, repeatable
  bool depthOnly = false;
  std::string outputs;  // --outputs (not given: all)
  std::string eye, target, up;
  double fov = 0, near = 0, far = 0, ortho = 0;
  CLI::Option *fovFlag = nullptr, *nearFlag = nullptr, *farFlag = nullptr, *orthoFlag = nullptr;
  CLI::Option* outputsFlag = nullptr;
  CLI::Option* sizeFlag = nullptr;
  hsr::RenderOptions options;  // algorithm and threads: set by CLI11 directly

  void declare(CLI::App& cmd);
  /// What the z-buffer resolves (checked before the scene is loaded).
  hsr::FrameOutputs frameOutputs() const;
  /// --param KEY=VALUE flags as a map (a key given twice is an error).
  std::map<std::string, std::string> parsedParams() const;
  bool openGlFlagsGiven() const;
  /// Checks every flag, then loads the scene and resolves the camera: bad flags fail before a
  /// possibly long scene load.
  Job prepare() const;

  // prepare()'s steps, for a caller that loads the scene its own way (hsr-mpi: a share per rank).
  /// The camera given by the flags, parsed.
  struct CameraFlags {
    std::optional<hsr::CameraSpec> file;
    std::optional<hsr::dvec3> eye, target, up;
  };
  /// Every flag but the camera's checked, and the options they give; no scene loaded.
  Job prepareOptions() const;
  CameraFlags cameraFlags() const;
  /// job.camera from `camera`, else the scene's own (job.scene.camera), else one framing `bounds`
  /// (the whole scene's), with the other camera flags applied.
  void placeCamera(Job& job, const CameraFlags& camera, const hsr::Bounds3& bounds) const;
};

/// The shadow flags `hsr render` and `hsr bench` share (docs/shadows.md), bound by declareShadows().
struct ShadowFlags {
  bool shadows = false;
  std::string lightDir, lightPos;
  std::string shadowMethod = hsr::shadowMethodName(hsr::ShadowOptions{}.method);
  hsr::ShadowOptions shadowOptions;
  CLI::Option* cascadesFlag = nullptr;

  /// Declares --shadows (`shadowsHelp`: what it does in this subcommand) and the flags it enables.
  void declareShadows(CLI::App& cmd, const std::string& shadowsHelp);
  /// The light --light-dir or --light-pos give (checked), if any.
  std::optional<hsr::Light> flagLight() const;
  /// The options the flags give, with the view's depth format and threads, checked (InputError).
  hsr::ShadowOptions checkedShadowOptions(const hsr::RenderOptions& view) const;
  /// The light: the flags', else the scene's, else the default for the job's camera.
  hsr::Light shadowLight(const Job& job) const;
};

}  // namespace hsr::cli

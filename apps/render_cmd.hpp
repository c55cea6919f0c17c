// The pieces of `hsr render` that `hsr-mpi render` (apps/mpi/) shares: its flags, their checks,
// the loading of the job, and what follows the frame (shadows, outputs written atomically, the
// summary). Defined in apps/render_cmd.cpp.
#pragma once
#include <hsr/hsr.hpp>

#include <CLI/CLI.hpp>

#include <chrono>
#include <string>
#include <vector>

#include "flags.hpp"
#include "output_set.hpp"

namespace hsr::cli {

// The shadow flags (ShadowFlags, flags.hpp): --shadows, the light from the flags (else the
// scene's, else the default) and the shadow options.
struct RenderFlags : ShadowFlags {
  ViewFlags view;
  std::string out, ids, depth, depthImage, overdrawImage, stats, svg;
  std::string instanceIds, barycentric;  // attributes resolved from the ids (hsr/views.hpp)
  std::string visibilityJson;            // per-mesh visible fractions (hsr/visibility.hpp)
  bool verify = false, quiet = false, json = false;
  std::vector<hsr::cli::OutputFlag> outputFlags;  // every output flag, checked as a set
};

/// Declares the flags of `hsr render` on `cmd`, bound to `f` (which must outlive parsing).
void declareRenderFlags(CLI::App& cmd, RenderFlags* f);
/// Checks the flags that need no scene (InputError); `writes`: also the output files' names and
/// places (false for a process that writes nothing).
void checkRenderFlags(const RenderFlags& f, bool writes);
/// Loads the scene and resolves the camera and the options (InputError).
Job prepareRender(const RenderFlags& f);
/// prepareRender's options alone, every flag checked: no scene, no camera (hsr-mpi loads a share
/// of the scene per rank and places the camera with ViewFlags::placeCamera).
Job prepareRenderOptions(const RenderFlags& f);
/// Shadows (with --shadows), the outputs (all or none) and the summary or JSON, for `frame`
/// rendered from `job` since `start`. Returns the exit status (0).
int finishRender(const RenderFlags& f, const Job& job, hsr::Frame& frame, std::chrono::steady_clock::time_point start);

}  // namespace hsr::cli

// `hsr render`: one frame of a scene, written to colour, face-id, depth and attribute files (all or
// none), with statistics as a summary or JSON; optionally shadowed and verified against the exact
// reference. Set up by the subcommand table in apps/main.cpp (docs/cli.md "hsr render"); its steps
// are shared with hsr-mpi (render_cmd.hpp, apps/mpi_main.cpp).
#include <hsr/hsr.hpp>
#include <hsr/threads.hpp>
#include <hsr/visibility.hpp>

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "render_cmd.hpp"

namespace hsr::cli {
namespace {

void printShadowSummary(const hsr::Stats& s) {
  auto count = [&s](std::string_view key) { return s.detailCount(key).value_or(0); };
  fmt::print("  shadows: {}, {}, {} map(s) of {}x{}, lit {} pixels, shadowed {} (of which facing away {})\n",
             s.detailText("shadow_light"), s.detailText("shadow_method"), count("shadow_maps"),
             count("shadow_map_size"), count("shadow_map_size"),
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
             cullName(job.options.cull));
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

// --instance-ids, --barycentric and --visibility-json: their file names, and the ids they are
// resolved from.
void checkAttributeOutputs(const RenderFlags& f, hsr::FrameOutputs kept) {
  if (!f.visibilityJson.empty() && !has(kept, hsr::FrameOutputs::FaceIds))
    throw InputError("--visibility-json: the outputs kept (" + hsr::frameOutputsName(kept) +
                     ") have no face ids (add face)");
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

// --visibility-json: per mesh (its instance id is its position among the scene's meshes), the
// pixels it covers alone, the pixels it shows and their ratio, with the BOP toolkit's names.
std::string visibilityJson(const Job& job, const hsr::Frame& frame) {
  const std::vector<hsr::InstanceVisibility> counts =
      hsr::instanceVisibility(job.scene, job.camera, job.options, frame, hsr::faceMeshIndices(job.scene));
  nlohmann::ordered_json instances = nlohmann::ordered_json::array();
  for (const hsr::InstanceVisibility& v : counts)
    instances.push_back({{"instance_id", v.instance},
                         {"mesh", job.scene.meshes[size_t(v.instance)].name},
                         {"px_count_all", v.pixelsAlone},
                         {"px_count_visib", v.pixelsVisible},
                         {"visib_fract", v.fraction()}});
  nlohmann::ordered_json out = {{"scene", job.sceneName},
                                {"width", frame.width},
                                {"height", frame.height},
                                {"algorithm", frame.stats.algorithm},
                                {"instances", std::move(instances)}};
  return out.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void writeAttributeOutputs(const RenderFlags& f, const Job& job, const hsr::Frame& frame,
                           const std::string& visibility, std::vector<std::string>& written) {
  if (!f.visibilityJson.empty()) {
    hsr::writeTextFile(visibility, f.visibilityJson);
    written.push_back(f.visibilityJson);
  }
  if (!f.instanceIds.empty()) {
    hsr::writeInstanceIds(frame, hsr::faceMeshIndices(job.scene), f.instanceIds);
    written.push_back(f.instanceIds);
  }
  if (!f.barycentric.empty()) {
    hsr::writeBarycentrics(job.scene, job.camera, frame, f.barycentric);
    written.push_back(f.barycentric);
  }
}

// The output files and their writers, in the order they are written.
struct Output {
  const std::string& path;  // empty: not requested
  hsr::OutputKind kind;
  void (*write)(const hsr::Frame&, const std::string&);
};
std::vector<Output> outputsOf(const RenderFlags& f) {
  return {{f.out, hsr::OutputKind::Color, hsr::writeColorPng},
          {f.ids, hsr::OutputKind::FaceIds, hsr::writeFaceIds},
          {f.depth, hsr::OutputKind::Depth, hsr::writeDepth},
          {f.depthImage, hsr::OutputKind::DepthImage, hsr::writeDepthImage},
          {f.overdrawImage, hsr::OutputKind::OverdrawImage, hsr::writeOverdrawImage}};
}

int runRender(const RenderFlags& f) {
  checkRenderFlags(f, true);
  Job job = prepareRender(f);
  auto start = std::chrono::steady_clock::now();
  hsr::Frame frame = hsr::render(job.scene, job.camera, job.options);
  return finishRender(f, job, frame, start);
}

}  // namespace

void checkRenderFlags(const RenderFlags& f, bool writes) {
  // Reject output names no writer knows, or that name no file, a special file or another
  // output's file, before any work is done.
  if (writes) {
    hsr::cli::checkOutputSet(f.outputFlags);
    for (const Output& o : outputsOf(f))
      if (!o.path.empty()) hsr::checkOutputPath(o.kind, o.path);
  }
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
  if (writes) checkAttributeOutputs(f, kept);
  if (f.shadows && !has(kept, hsr::FrameOutputs::TriangleIds))
    throw InputError("--shadows finds each pixel's point on its triangle: the outputs kept (" +
                     hsr::frameOutputsName(kept) + ") have no triangle ids (add triangle)");
  f.flagLight();  // its errors before the scene loads; finishRender uses the light
  if (f.shadows) f.checkedShadowOptions(hsr::RenderOptions{});
  if (writes && !f.svg.empty()) hsr::checkSvgPath(f.svg);
}

Job prepareRenderOptions(const RenderFlags& f) {
  Job job = f.view.prepareOptions();
  if (!f.svg.empty() && !hsr::paintsPolygons(job.options.algorithm))
    throw InputError("--svg: " + job.options.algorithm +
                     " paints no polygons (vector output needs --algorithm painter, newell or bsp)");
  job.options.verify = f.verify;
  job.options.countWrites = !f.overdrawImage.empty();
  return job;
}

Job prepareRender(const RenderFlags& f) {
  Job job = prepareRenderOptions(f);
  const ViewFlags::CameraFlags camera = f.view.cameraFlags();
  job.scene = hsr::loadScene(job.sceneName);
  f.view.placeCamera(job, camera, job.scene.bounds());
  return job;
}

int finishRender(const RenderFlags& f, const Job& job, hsr::Frame& frame,
                 std::chrono::steady_clock::time_point start) {
  if (f.shadows)
    hsr::addShadows(job.scene, job.camera, frame, f.shadowLight(job), f.checkedShadowOptions(job.options), f.verify);
  double wallMs = millisecondsSince(start);
  std::string visibility;  // counted before the statistics are written, which time it
  if (!f.visibilityJson.empty()) {
    const auto visibilityStart = std::chrono::steady_clock::now();
    visibility = visibilityJson(job, frame);
    frame.stats.addTime("visibility", millisecondsSince(visibilityStart));
  }

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
    for (const Output& o : outputsOf(f)) {
      if (o.path.empty()) continue;
      o.write(frame, o.path);
      written.push_back(o.path);
    }
    writeAttributeOutputs(f, job, frame, visibility, written);
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

void declareRenderFlags(CLI::App& cmd, RenderFlags* f) {
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
  cmd.add_option("--visibility-json", f->visibilityJson,
                 "Per mesh (instance id = its position, as for --instance-ids): px_count_all (pixels it covers "
                 "rendered alone), px_count_visib (pixels it shows) and visib_fract (their ratio, 0 when it covers "
                 "none), counted in one pass besides the render")
      ->type_name("VIS.json")
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
      {"--barycentric", &f->barycentric},      {"--visibility-json", &f->visibilityJson},
      {"--stats", &f->stats},                  {"--svg", &f->svg}};
  for (auto [flag, path] : outputFlags)
    f->outputFlags.push_back({flag, cmd.get_option(flag), path, std::string_view(flag) == "--stats"});
  cmd.add_flag("--verify", f->verify, "Also render the exact reference and count wrong/ambiguous pixels");
  f->declareShadows(cmd,
                    "Shadow-map the image: depth maps rendered by the z-buffer from the light, each visible pixel "
                    "tested against one, shadowed pixels darkened in the colour output (with --verify, also checked "
                    "against shadow rays)");
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
}

Runner setupRender(CLI::App& cmd) {
  auto f = std::make_shared<RenderFlags>();
  declareRenderFlags(cmd, f.get());
  return [f] { return runRender(*f); };
}

}  // namespace hsr::cli

// `hsr info`: loads one scene and describes it (counts, meshes, bounds, the problems the loader
// handled, its camera) as text or one JSON object. Set up by apps/main.cpp's table.
#include <hsr/hsr.hpp>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <memory>

#include "commands.hpp"

namespace hsr::cli {
namespace {

using Json = nlohmann::ordered_json;

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

}  // namespace

Runner setupInfo(CLI::App& cmd) {
  auto scene = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd.add_option("scene", *scene, "Mesh file, scene JSON or builtin:NAME")->type_name("SCENE")->required();
  cmd.add_flag("--json", *json, "Print one JSON object instead");
  return [scene, json] { return runInfo(*scene, *json); };
}

}  // namespace hsr::cli

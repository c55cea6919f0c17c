// The conformance harness: renders an algorithm on the built-in scenes under seeded camera poses,
// image sizes and depth formats, and checks it against the exact reference (raycast) by what its
// guarantee declares. Driven by the registry (conformance_test.cpp), so a new algorithm is
// checked with no new test code; conformance_toy_test.cpp shows a toy algorithm picked up.
#pragma once
#include <hsr/hsr.hpp>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hsr::conformance {

/// A camera pose for a scene (its JSON replays a failure with `hsr render --camera`).
struct Pose {
  CameraSpec spec;
  std::string describe() const { return cameraSpecToJson(spec); }
};

/// Seeded random poses around the scene: outside looking in, some close enough that geometry
/// crosses the near plane, some orthographic, random field of view and roll.
std::vector<Pose> posesAround(const Scene& scene, int count, uint64_t seed);

/// The scene's own camera, or a framing of its bounds.
Pose ownPose(const Scene& scene);

/// loadScene, plus the test scenes "test:boxes" and "test:soup".
Scene load(const std::string& name);

/// One way to run an algorithm: its parameters (the others at their defaults).
struct Variant {
  const AlgorithmInfo* algorithm = nullptr;
  std::map<std::string, std::string> params;
  std::string describe() const;  // "zbuffer raster=halfspace"
};
/// The algorithm at its defaults, then once for every other value of each choice and bool
/// parameter (the others at their defaults).
std::vector<Variant> variantsOf(const AlgorithmInfo& algorithm);

/// One variant's algorithm made for one scene and kept for many renders, as a Renderer keeps it
/// (what it builds for the scene is built once): through Renderer when the registry holds the
/// algorithm, else its object made directly, with the same set-up around it.
class VariantRenderer {
 public:
  VariantRenderer(const Variant& variant, const Scene& scene);
  /// A frame of the variant with `options` (its algorithm and parameters set from the variant).
  Frame render(const Camera& cam, RenderOptions options);
  const Variant& variant() const { return variant_; }

 private:
  const Variant& variant_;
  AlgorithmParams params_;
  std::optional<Renderer> registered_;
  std::unique_ptr<Algorithm> object_;
};

/// One rendering checked against the reference.
struct Outcome {
  uint64_t wrong = 0, ambiguous = 0, covered = 0;  // covered: pixels the reference covers
  std::string replay;                              // the command that replays it, and its camera
};
/// Renders `variant` (through render() when its algorithm is registered, else directly with the
/// same set-up), renders the reference and classifies every pixel (verifyAgainstReference).
Outcome run(const Variant& variant, const std::string& sceneName, const Scene& scene, const Pose& pose, int width,
            int height, DepthFormat format, int threads = 1);
/// The same with a variant already made for `scene`.
Outcome run(VariantRenderer& renderer, const std::string& sceneName, const Scene& scene, const Pose& pose, int width,
            int height, DepthFormat format, int threads = 1);

/// What the harness covers.
struct Plan {
  struct Case {
    std::string scene;
    int poses;
  };
  std::vector<Case> cases;                        // scenes x seeded poses, at 64x48
  std::vector<std::pair<int, int>> oddSizes;      // also each of these on the first poses of every case
  int oddSizePoses = 2;
  std::vector<std::string> formats;               // also each depth format on formatScenes
  std::vector<std::string> formatScenes;
  int formatPoses = 3;
  std::vector<std::string> determinismScenes;     // 1, 2 and 3 threads: the same bits
  int determinismPoses = 3;
  std::vector<std::string> scenes() const;       // every scene above, once, in order of first mention
};
/// The full plan of the conformance suite.
Plan fullPlan();
/// The plan the test suite runs: the full plan, or in a sanitized build a lighter one (the same
/// scenes, sizes and formats, fewer poses; docs/testing.md).
Plan suitePlan();

/// Every violation of `variant`'s guarantee on `plan`, one message each (empty: it conforms). The
/// plan's scenes with a CSG tree are checked only for algorithms that declare Capability::Csg.
std::vector<std::string> check(const Variant& variant, const Plan& plan);

}  // namespace hsr::conformance

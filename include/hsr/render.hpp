// The public entry point: render a scene with a camera and one of the visibility algorithms
// into a Frame (visibility buffer + statistics), and verify it against the exact reference.
//
// Conventions, stated once (details in docs/conventions.md):
//  - world space right-handed; camera space x right, y down, z forward; eye depth = camera z;
//  - pixel (x, y) centre at (x + .5, y + .5), row 0 at the top; a triangle covers a pixel when
//    the centre is inside, centres on an edge follow the top-left rule;
//  - vertices snap to 1/256 pixel (8 sub-pixel bits) before coverage is decided;
//  - depth test: strictly nearer wins, so on ties the triangle drawn first stays;
//  - faces are two-sided unless cull = back/front (front = counter-clockwise as seen).
#pragma once
#include <hsr/algorithm.hpp>
#include <hsr/camera.hpp>
#include <hsr/depth_format.hpp>
#include <hsr/frame.hpp>
#include <hsr/scene.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hsr {

enum class Cull : uint8_t { None, Back, Front };
enum class Shading : uint8_t { Flat, Lambert, FaceId };

/// The tiled z-buffer's and the occlusion buffer's optimisations, each of which leaves every image
/// and stored depth the same bits: all on by default, turned off to test that and to measure
/// what each saves (the command line's --switch-off NAME; docs/kernel.md).
struct TiledSwitches {
  bool deferBackFaces = true;  // defer-back-faces: with cull none, back faces set up after the front faces
  bool deferClusters = true;   // defer-clusters: whole clusters facing away deferred (with cull back: culled)
  bool meshCulling = true;     // mesh-culling: scenes of many meshes culled mesh by mesh (docs/occlusion.md)
  bool backgroundPump = true;  // background-pump: idle tiles' background streamed between the kernel's blocks
};
/// The switches' names, as --switch-off takes them.
inline constexpr const char* kTiledSwitchNames[] = {"defer-back-faces", "defer-clusters", "mesh-culling",
                                                    "background-pump"};
/// Turns off the switch `name` (kTiledSwitchNames); InputError for another name.
void switchOff(TiledSwitches& switches, const std::string& name);

struct RenderOptions {
  std::string algorithm = "zbuffer";
  /// The algorithm's own parameters, name -> value as text (`--param name=value`); those not
  /// given take their defaults (`hsr algorithms` lists them).
  std::map<std::string, std::string> params;
  DepthFormat depthFormat;                // default f32:reversed
  FrameOutputs outputs = FrameOutputs::All;  // what is resolved into the Frame (frame.hpp)
  Cull cull = Cull::None;
  Shading shading = Shading::Lambert;
  Rgba8 background{0, 0, 0, 255};
  int threads = 0;                        // 0: all cores
  bool verify = false;                    // also render the reference and count wrong pixels
  bool countWrites = false;               // fill Frame::writes: fragments written per pixel
  TiledSwitches tiled;                    // zbuffer raster=tiled: its optimisations, all on
};

/// One algorithm made for one scene, kept from view to view: "build once, view many". What the
/// algorithm makes for the scene (a BSP tree, the tiled z-buffer's bins and buffers, the
/// half-range depth buffer) is made at its first frame and kept by this object, never in a
/// hidden cache. The scene must outlive the Renderer; one thread renders with it at a time.
class Renderer {
 public:
  /// Checks options.algorithm and options.params (InputError) and makes the algorithm for `scene`.
  Renderer(const Scene& scene, const RenderOptions& options);
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;

  /// Renders the view with the constructor's options into `frame`, reusing its buffers.
  void render(const Camera& camera, Frame& frame);
  Frame render(const Camera& camera);
  /// The same with other options: anything may differ but the algorithm and its parameters
  /// (std::invalid_argument when they do; make another Renderer for another algorithm).
  void render(const Camera& camera, const RenderOptions& options, Frame& frame);

  const AlgorithmInfo& algorithm() const { return *info_; }
  const RenderOptions& options() const { return options_; }

 private:
  const Scene* scene_;
  RenderOptions options_;
  const AlgorithmInfo* info_;
  AlgorithmParams params_;
  std::unique_ptr<Algorithm> algorithm_;
};

/// Renders `scene` (finalized) seen by `camera` with options.algorithm and options.params: a
/// Renderer made for this one view (so an algorithm that builds for the scene builds each call).
/// Throws InputError for an unknown algorithm, parameter or bad options.
Frame render(const Scene& scene, const Camera& camera, const RenderOptions& options);
/// The same into `frame`, reusing its buffers.
void render(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame);

/// The instruction set the tiled rasterizer's SIMD kernel runs with on this machine, chosen at
/// run time (e.g. "AVX3" = AVX-512, "AVX2", "SSE4", "EMU128"): for benchmark records.
const char* kernelInstructionSet();

/// Result of comparing a frame with the exact reference.
struct VerifyResult {
  uint64_t wrong_pixels = 0;      // face id differs and the difference is not explained below
  uint64_t ambiguous_pixels = 0;  // face id differs, but the two surfaces are closer in depth
                                  // than the format separates there, or the pixel centre lies
                                  // within 1/128 pixel of an edge of either triangle
  std::vector<std::pair<int, int>> first_wrong;  // up to 16 wrong pixels (x, y), for messages
};
/// Compares `frame` (rendered with `options`) against `reference` (the raycast of the same
/// scene and camera) and classifies each differing pixel.
VerifyResult verifyAgainstReference(const Scene& scene, const Camera& camera,
                                    const RenderOptions& options, const Frame& frame,
                                    const Frame& reference);

}  // namespace hsr

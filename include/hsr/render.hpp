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
#include <hsr/options.hpp>
#include <hsr/scene.hpp>
#include <hsr/verify.hpp>

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace hsr {

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

/// What options.verify does after a render: `frame` (drawn with `options`) against the ray-cast
/// reference, into frame.stats (wrong_pixels, ambiguous_pixels; with transparency and colour,
/// the colours against the A-buffer's). For frames made otherwise, e.g. composited by hsr-mpi.
void verifyFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame);

/// The instruction set the tiled rasterizer's SIMD kernel runs with on this machine, chosen at
/// run time (e.g. "AVX3" = AVX-512, "AVX2", "SSE4", "EMU128"): for benchmark records.
const char* kernelInstructionSet();

}  // namespace hsr

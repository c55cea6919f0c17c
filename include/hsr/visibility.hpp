// Per-instance visibility of one view in one pass, as vision dataset tools need it (the BOP
// toolkit's px_count_all, px_count_visib and visib_fract): for each instance (a group of faces,
// e.g. an object's meshes), the pixels it would cover rendered alone and the pixels it shows in
// the rendered frame. Used by the CLI's --visibility-json and the Python module's "visibility".
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hsr {

/// One instance's counts in one view.
struct InstanceVisibility {
  int32_t instance = 0;
  uint64_t pixelsAlone = 0;    // pixels covered if rendered alone (px_count_all)
  uint64_t pixelsVisible = 0;  // pixels showing it in the frame (px_count_visib)
  /// pixelsVisible / pixelsAlone, 0 when it covers no pixel alone (visib_fract).
  double fraction() const { return pixelsAlone ? double(pixelsVisible) / double(pixelsAlone) : 0.0; }
};

/// The counts of every instance of `scene`, sorted by instance id (instances out of view too,
/// with 0 pixels). `faceInstance` holds one instance id per face; a negative id puts the face in
/// no instance. `frame` is the view of `scene` rendered from `camera` with `options`, with face ids.
///
/// pixelsAlone: the pixel centres any of the instance's triangles covers, each counted once, as
/// the rasterizing algorithms cover them (the same front end: clipping at near and far, culling
/// by options.cull, snapping to the sub-pixel grid; the same edge functions and top-left rule),
/// so it equals the covered pixels of a render of the instance's faces alone (extractFaces)
/// by the z-buffer. Counted in one pass over the set-up triangles grouped by instance, without
/// depth or shading: a pixel counts for an instance the first time one of its triangles covers it.
/// (bsp and newell draw split polygons, raycast tests rays: alone, their edge pixels may differ.)
/// pixelsVisible: the frame's pixels whose face is the instance's.
/// Runs on options.threads threads; the counts are the same for every thread count. Throws
/// std::invalid_argument when faceInstance or the frame does not fit the scene and camera.
/// (A VisibilityCounter made for this one view.)
std::vector<InstanceVisibility> instanceVisibility(const Scene& scene, const Camera& camera,
                                                   const RenderOptions& options, const Frame& frame,
                                                   std::span<const int32_t> faceInstance);

/// instanceVisibility made for one scene and its instance ids, kept from view to view: what a
/// view needs (the set-up triangles, their order, the bands of rows they are binned to) is kept
/// and reused, as a Renderer keeps its algorithm's, so warm views fault no fresh memory in. The
/// scene must outlive the counter; one thread counts with it at a time.
class VisibilityCounter {
 public:
  /// Throws std::invalid_argument when faceInstance does not hold one id per face of `scene`.
  VisibilityCounter(const Scene& scene, std::span<const int32_t> faceInstance);
  ~VisibilityCounter();
  VisibilityCounter(VisibilityCounter&&) noexcept;
  VisibilityCounter& operator=(VisibilityCounter&&) noexcept;

  /// instanceVisibility(scene, camera, options, frame, faceInstance) of the counter's scene and ids.
  std::vector<InstanceVisibility> count(const Camera& camera, const RenderOptions& options, const Frame& frame);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace hsr

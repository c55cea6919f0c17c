// Polygon triangulation for Scene::finalize(): one polygon at a time, in its best-fit (Newell)
// plane — a fan for convex polygons, ear clipping for concave ones — with the planarity and
// degeneracy findings the scene reports. Consumed by scene.cpp and the scene tests.
#pragma once
#include <hsr/scene.hpp>

#include <span>
#include <vector>

namespace hsr {

/// What triangulating one polygon found.
struct PolygonReport {
  bool degenerate = false;           // no area: no triangles were produced
  const char* degenerateReason = "";  // "fewer than 3 distinct vertices", "zero area", ...
  bool nonPlanar = false;            // a vertex lies off the Newell plane by > 1e-6 * size
  double planeDistance = 0;          // the largest such distance
  bool concave = false;              // not convex (or self-intersecting): ear clipped
  bool approximate = false;          // self-intersecting (or out of ear clipping's budget):
                                     // some triangles were cut without an ear test
};

/// Triangulates polygons. Holds scratch buffers, so one instance serves a whole scene without
/// allocating per polygon.
class Triangulator {
 public:
  /// Appends the triangles of polygon `poly` (valid indices into `positions`, in order) to
  /// `out`, each tagged with `face` and wound like the polygon. Triangles of zero area are left
  /// out. The triangles cover exactly the polygon's area when it is simple (non-self-
  /// intersecting); for non-planar polygons the area of its projection on the best-fit plane.
  PolygonReport run(const std::vector<dvec3>& positions, std::span<const uint32_t> poly,
                    uint32_t face, std::vector<Triangle>& out);

 private:
  void fan(std::span<const uint32_t> poly, uint32_t face, std::vector<Triangle>& out);
  void earClip(std::span<const uint32_t> poly, uint32_t face, std::vector<Triangle>& out);
  bool isEar(uint32_t a, uint32_t b, uint32_t c);
  bool blocksEar(uint32_t r, uint32_t a, uint32_t b, uint32_t c) const;
  void emit(std::span<const uint32_t> poly, uint32_t a, uint32_t b, uint32_t c, uint32_t face,
            std::vector<Triangle>& out) const;
  double orient(uint32_t a, uint32_t b, uint32_t c) const;
  // The |orient| at or below which the turn a, b, c counts as straight: relative to the
  // triangle's own longest side, so the fine turns of a polygon of many vertices still count.
  double flatTolerance(uint32_t a, uint32_t b, uint32_t c) const;
  void buildBlockerGrid();
  glm::ivec2 cell(const dvec2& p) const;  // grid cell of a projected point (clamped)

  double size2_ = 0;              // squared diagonal of the polygon's bounding box
  std::vector<dvec3> local_;      // vertices relative to the first one
  std::vector<dvec2> flat_;       // projected on the dominant plane, counter-clockwise
  // Ear clipping state: a doubly linked ring of the remaining vertices.
  std::vector<uint32_t> prev_, next_;
  std::vector<uint8_t> alive_;
  std::vector<uint8_t> blocker_;        // not strictly convex (reflex or straight)
  std::vector<uint32_t> lateBlockers_;  // vertices that became blockers after the grid was built
  // Uniform grid over the blockers, compressed by rows (cellStart_ indexes cellItems_).
  uint64_t workLeft_ = 0;  // ear clipping's remaining budget
  bool tangled_ = false;   // ear clipping found the polygon self-intersecting
  int gridSide_ = 1;
  dvec2 gridLo_{0.0}, gridScale_{0.0};
  std::vector<uint32_t> cellStart_, cellItems_, cellCursor_;
};

}  // namespace hsr

// The front end's vertex stage: homogeneous pixel coordinates of scene vertices, their clip
// outcodes, and the projected, shared vertices set-up reads (frontend.cpp one at a time,
// vertex_batch.cpp with SIMD). Used by the front end's passes on its worker threads, by the
// tiled rasterizer's late set-up (Bins::projected) and by the occlusion culler.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>

#include "setup/fixed_point.hpp"

namespace hsr {

/// Homogeneous pixel coordinates of a vertex: pixel = (hx / w, hy / w), eye depth d (w > 0).
struct HVertex {
  double hx, hy, d, w;
};

/// A vertex inside the clip volume, projected once and shared by all its triangles. 32 bytes (the
/// vertex pass writes one per scene vertex, set-up gathers them): the snapped position is not
/// stored but computed where it is needed, X() and Y().
struct ProjectedVertex {
  double sx, sy;   // pixel position (unsnapped)
  double num, den; // d/w and 1/w, both affine in screen space
  int64_t X() const { return snapCoordinate(sx); }  // snapped to 1/256 pixel
  int64_t Y() const { return snapCoordinate(sy); }
};
static_assert(sizeof(ProjectedVertex) == 32);

/// Projects and snaps a vertex that lies inside the clip volume.
ProjectedVertex projectVertex(const HVertex& v);

/// Homogeneous pixel coordinates of world point p: M (p, 1), each row summed as
/// ((m0 x + m1 y) + m2 z) + m3 (M column-major, as glm stores it).
HVertex transformVertex(const dvec3& p, const dmat4& M);

/// The clipping planes (near, far, guard band) vertex v lies outside of, one bit each.
uint32_t clipOutcode(const HVertex& v, const Camera& cam);

/// The vertex pass of vertices [0, count), with SIMD (frontend/vertex_batch.cpp): with h =
/// transformVertex(positions[i], M), outcodes[i] = clipOutcode(h) and, when that is 0,
/// projected[i] = projectVertex(h) — bit for bit those functions' results; `projected` null: the
/// outcodes only (a mesh's box corners: four divisions less per vertex). (The homogeneous
/// vertices themselves are not kept: the few triangles that need clipping transform theirs
/// again, to the same bits.)
void transformVertices(const dvec3* positions, size_t count, const dmat4& M, const Camera& cam, uint8_t* outcodes,
                       ProjectedVertex* projected);

/// The corners of `box` taken to homogeneous pixel coordinates by M (transformVertex's products
/// and sums, in its order), with SIMD (frontend/vertex_batch.cpp): false unless every corner lies
/// inside each clipping half-space by more than `margin`; then `extent` holds the least w - wRoom
/// and the greatest w + wRoom, then the least and greatest pixel positions hx / w and hy / w,
/// as hx (1 / w) (x0, y0, x1, y1).
bool boxCornersInView(const Bounds3& box, const dmat4& M, const Camera& cam, double margin, double wRoom,
                      double* extent);

}  // namespace hsr

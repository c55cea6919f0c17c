// Part of a scene as a scene of its own, with the way back to the whole scene's face and triangle
// ids: what one process of a sort-last composite renders (apps/mpi/, docs/distributed.md).
// Produced from a finalized Scene; consumed by the renderer (the part) and the compositor (the ids).
#pragma once
#include <hsr/scene.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hsr {

/// Faces [first, first + count) of a scene; a piece lies within one mesh.
struct FaceRange {
  uint32_t first = 0, count = 0;
};

/// Some faces of a scene as a finalized scene of their own. Faces keep their order (so a tie in
/// the depth test goes the same way as in the whole scene), their vertices' exact coordinates
/// and their colours, so each triangle is set up and shaded to the same bits as in the whole.
struct SceneRange {
  Scene scene;
  std::vector<uint32_t> globalFace;      // per face of `scene`: its index in the whole scene
  std::vector<uint32_t> globalTriangle;  // per triangle of `scene`: its index in the whole scene
};

/// The faces of `pieces` (each within one mesh of `whole`, in any order; taken in face order,
/// none twice) as a scene, one mesh per piece named after its mesh. `whole` must be finalized.
/// Throws std::invalid_argument for a piece outside the scene, across meshes, or overlapping another.
SceneRange extractFaces(const Scene& whole, std::span<const FaceRange> pieces);

/// The colour Shading::FaceId gives face `face` (a renderer of a SceneRange recolours its pixels
/// with the global ids).
Rgba8 faceIdColor(uint32_t face);

}  // namespace hsr

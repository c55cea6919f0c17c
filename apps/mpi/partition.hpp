// The spatial partition of a scene over the ranks of hsr-mpi: which faces each rank renders.
// Called by every rank with the same scene, so every rank computes the same partition.
#pragma once
#include <hsr/scene.hpp>
#include <hsr/subscene.hpp>

#include <vector>

namespace hsr::mpi {

/// `parts` groups of face ranges covering every face of `scene` once: the meshes (a mesh of more
/// than 1/(2 parts) of the triangles is cut into face ranges of about that many) ordered by the
/// Morton code of their bounds' centres within the scene's bounds, cut into `parts` contiguous
/// runs of about equal triangle counts. Nearby meshes go to the same rank, so each rank's image
/// covers a smaller screen rectangle; a scene of fewer pieces than parts leaves some groups empty.
std::vector<std::vector<FaceRange>> partitionFaces(const Scene& scene, int parts);

}  // namespace hsr::mpi

// The depth keys list-priority algorithms sort faces by (the painter's, the reverse painter's,
// the sorted z-buffer's), and the order of set-up triangles they give. One key per face, in eye
// depth (distance along the viewing axis), from the face's vertices in double precision.
#pragma once
#include <hsr/algorithm.hpp>
#include <hsr/camera.hpp>
#include <hsr/scene.hpp>

#include <vector>

#include "algorithms/draw.hpp"

namespace hsr::algo {

enum class SortKey : uint8_t {
  Centroid,    // the eye depth of the polygon's area centroid: the documents' "midpoint"
  Max,         // its farthest vertex (the KTH report's implementation compares by a max-z vertex)
  Min,         // its nearest vertex
  MeanVertex,  // the mean of its vertices' eye depths
};
/// The `sort-key` parameter (centroid, max, min, mean-vertex) and its value.
ParamSpec sortKeyParam(const char* defaultValue, const char* help);
SortKey sortKeyOf(const std::string& name);

/// Per face of `scene`, its key seen by `camera`.
std::vector<double> faceKeys(const Scene& scene, const Camera& camera, SortKey key);

/// Per face, its place in the drawing order: faces by key, farthest first (`backToFront`) or
/// nearest first. Equal keys keep the z-buffer's tie rule, the face submitted first winning: it
/// comes last back to front and first front to back.
std::vector<uint32_t> faceRanks(const std::vector<double>& keys, bool backToFront);

/// Whether every face lies between the clipping planes and no two faces whose screen boxes overlap
/// (a pixel of margin) overlap in eye depth: then any key orders every pair that can hide the
/// other, and the painter's order is exact.
bool depthRangesSeparate(const Scene& scene, const Camera& camera);

/// The ranks of the z-buffer family's transparent pass: the opaque faces first, in the order of
/// `opaqueRank`, then the transparent ones (alpha below 255) back to front by `key`.
std::vector<uint32_t> transparentLast(const Scene& scene, const Camera& camera, const std::vector<uint32_t>& opaqueRank,
                                      SortKey key);

/// Reorders set-up triangles by their face's rank (stable: a face's triangles keep their order),
/// in `scratch` when given (room kept from frame to frame, swapped with the triangles).
OrderFn byFaceRank(std::vector<uint32_t> rank, std::vector<SetupTriangle>* scratch = nullptr);

}  // namespace hsr::algo

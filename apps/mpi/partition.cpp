// partitionFaces (partition.hpp): meshes cut to size, ordered along a Morton curve, split into
// runs of equal triangle counts.
#include "partition.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace hsr::mpi {
namespace {

struct Piece {
  FaceRange faces;
  uint64_t triangles = 0;
  uint64_t morton = 0;
};

// The Morton code of a point's cell in a 2^21 grid over `box` (21 bits per axis, interleaved).
uint64_t mortonCode(const dvec3& p, const Bounds3& box) {
  auto cell = [](double v, double lo, double hi) {
    const double t = hi > lo ? (v - lo) / (hi - lo) : 0.0;
    return uint64_t(std::clamp(t, 0.0, 1.0) * double((1u << 21) - 1));
  };
  auto spread = [](uint64_t v) {  // bit i of v to bit 3 i
    uint64_t r = 0;
    for (int i = 0; i < 21; ++i) r |= ((v >> i) & 1u) << (3 * i);
    return r;
  };
  return spread(cell(p.x, box.lo.x, box.hi.x)) | spread(cell(p.y, box.lo.y, box.hi.y)) << 1 |
         spread(cell(p.z, box.lo.z, box.hi.z)) << 2;
}

}  // namespace

std::vector<std::vector<FaceRange>> partitionFaces(const Scene& scene, int parts) {
  const uint64_t total = scene.triangles.size();
  const uint64_t maxPiece = std::max<uint64_t>(1, total / (2 * uint64_t(parts)));
  const Bounds3 box = scene.bounds();
  // Triangles per face (a face's triangles are together, in face order).
  std::vector<uint32_t> faceTriangles(scene.faceCount(), 0);
  for (const Triangle& t : scene.triangles) ++faceTriangles[t.face];

  std::vector<Piece> pieces;
  for (const MeshRange& mesh : scene.meshes) {
    Piece piece{{mesh.firstFace, 0}, 0, 0};
    Bounds3 bounds;
    auto close = [&] {
      if (piece.faces.count == 0) return;
      piece.morton = bounds.empty() ? 0 : mortonCode(bounds.center(), box);
      pieces.push_back(piece);
      piece = {{piece.faces.first + piece.faces.count, 0}, 0, 0};
      bounds = {};
    };
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f) {
      ++piece.faces.count;
      piece.triangles += faceTriangles[f];
      for (uint32_t v : scene.face(f)) bounds.add(scene.positions[v]);
      if (piece.triangles >= maxPiece) close();
    }
    close();
  }
  std::stable_sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.morton < b.morton; });

  // Run r ends where the running triangle count first reaches total (r + 1) / parts.
  std::vector<std::vector<FaceRange>> groups(static_cast<size_t>(parts));
  uint64_t done = 0;
  size_t r = 0;
  for (const Piece& p : pieces) {
    while (r + 1 < groups.size() && done >= total * (r + 1) / uint64_t(parts)) ++r;
    groups[r].push_back(p.faces);
    done += p.triangles;
  }
  return groups;
}

}  // namespace hsr::mpi

// extractFaces (hsr/subscene.hpp): some faces of a finalized scene as a scene of their own, with
// their global ids. Called by hsr-mpi (apps/mpi/) on each rank, before it renders its share.
#include <hsr/subscene.hpp>

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace hsr {

SceneRange extractFaces(const Scene& whole, std::span<const FaceRange> pieces) {
  std::vector<FaceRange> sorted(pieces.begin(), pieces.end());
  std::erase_if(sorted, [](const FaceRange& p) { return p.count == 0; });
  std::sort(sorted.begin(), sorted.end(), [](const FaceRange& a, const FaceRange& b) { return a.first < b.first; });

  SceneRange out;
  Scene& part = out.scene;
  part.source = whole.source;
  part.camera = whole.camera;
  part.light = whole.light;
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> localVertex(whole.positions.size(), kUnused);
  std::vector<uint32_t> polygon;
  auto mesh = whole.meshes.begin();
  uint64_t end = 0;  // the end of the previous piece
  for (const FaceRange& p : sorted) {
    if (p.first < end || uint64_t(p.first) + p.count > whole.faceCount())
      throw std::invalid_argument("extractFaces: a piece overlaps another or lies outside the scene");
    while (mesh != whole.meshes.end() && mesh->firstFace + mesh->faceCount <= p.first) ++mesh;
    if (mesh == whole.meshes.end() || p.first < mesh->firstFace || p.first + p.count > mesh->firstFace + mesh->faceCount)
      throw std::invalid_argument("extractFaces: a piece crosses meshes");
    end = uint64_t(p.first) + p.count;
    part.beginMesh(mesh->name);
    for (uint32_t f = p.first; f < p.first + p.count; ++f) {
      polygon.clear();
      for (uint32_t v : whole.face(f)) {
        if (localVertex[v] == kUnused) {
          localVertex[v] = uint32_t(part.positions.size());
          part.positions.push_back(whole.positions[v]);
        }
        polygon.push_back(localVertex[v]);
      }
      part.addFace(polygon, whole.faceColors[f]);
      out.globalFace.push_back(f);
    }
  }
  part.finalize();

  // Triangles are in face order, each face's together, and a face triangulates the same way in
  // either scene: the part's triangles of face f are the whole's, in order.
  out.globalTriangle.reserve(part.triangles.size());
  size_t t = 0;
  for (const Triangle& tri : part.triangles) {
    const uint32_t global = out.globalFace[tri.face];
    if (t == 0 || out.globalFace[part.triangles[t - 1].face] != global) {
      auto first = std::lower_bound(whole.triangles.begin(), whole.triangles.end(), global,
                                    [](const Triangle& a, uint32_t face) { return a.face < face; });
      out.globalTriangle.push_back(uint32_t(first - whole.triangles.begin()));
    } else {
      out.globalTriangle.push_back(out.globalTriangle.back() + 1);
    }
    ++t;
  }
  return out;
}

}  // namespace hsr

// The scene model: building polygons, then finalize() — validation and the triangulation every
// rasterizer consumes (convex polygons as fans, concave ones by ear clipping in the polygon's
// best-fit plane). Called by the loaders and the built-in generators; runs on the caller's thread.
#include <hsr/scene.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <fmt/format.h>

#include "scene/triangulate.hpp"

namespace hsr {
namespace {

// Coordinates beyond this magnitude are refused: squared lengths and cross products of such
// values (taken by every algorithm) would overflow a double.
constexpr double kMaxCoordinate = 1e30;
// Notes kept per kind of problem; the rest are only counted.
constexpr uint64_t kMaxNotesPerKind = 5;

std::string faceLabel(size_t f) { return "face " + std::to_string(f); }

/// Adds the note made by `text()` while fewer than kMaxNotesPerKind of its kind were seen.
template <class MakeText>
void noteProblem(SceneProblems& problems, uint64_t count, MakeText&& text) {
  if (count <= kMaxNotesPerKind) problems.notes.push_back(text());
}

// Scene::clusters (see TriangleCluster).
void buildClusters(Scene& scene) {
  // A triangle is well shaped when twice its area is at least 1/50 of its longest edge squared
  // (its least height at least 1/50 of that edge): its normal is then accurate to a few ulps, and
  // its image under a camera that does not see it edge on is no sliver.
  constexpr double kMinShape = 0.02;
  std::vector<uint32_t> meshOfFace(scene.faceCount());
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const auto first = meshOfFace.begin() + scene.meshes[m].firstFace;
    std::fill(first, first + scene.meshes[m].faceCount, uint32_t(m));
  }
  scene.clusters.assign((scene.triangles.size() + kClusterTriangles - 1) / kClusterTriangles, TriangleCluster{});
  for (size_t c = 0; c < scene.clusters.size(); ++c) {
    TriangleCluster& cl = scene.clusters[c];
    const size_t first = c * kClusterTriangles, end = std::min(scene.triangles.size(), first + kClusterTriangles);
    dvec3 normals[kClusterTriangles];
    dvec3 sum{0.0};
    bool usable = end - first == kClusterTriangles &&
                  meshOfFace[scene.triangles[first].face] == meshOfFace[scene.triangles[end - 1].face];
    for (size_t t = first; t < end; ++t) {
      const uint32_t* v = scene.triangles[t].v;
      const dvec3 &a = scene.positions[v[0]], &b = scene.positions[v[1]], &p = scene.positions[v[2]];
      cl.bounds.add(a), cl.bounds.add(b), cl.bounds.add(p);
      const dvec3 n = glm::cross(b - a, p - a);
      const double len = glm::length(n);
      const double edge = std::max({glm::dot(b - a, b - a), glm::dot(p - b, p - b), glm::dot(a - p, a - p)});
      if (!(len >= kMinShape * edge) || !(len > 0) || !std::isfinite(len)) usable = false;
      cl.minArea = t == first ? 0.5 * len : std::min(cl.minArea, 0.5 * len);
      cl.maxEdge = std::max(cl.maxEdge, std::sqrt(edge));
      normals[t - first] = usable ? n / len : dvec3{0.0};
      sum += normals[t - first];
    }
    const double sumLen = glm::length(sum);
    if (!usable || !(sumLen > 0)) continue;
    cl.axis = sum / sumLen;
    cl.cosCone = 1;
    for (size_t t = first; t < end; ++t) cl.cosCone = std::min(cl.cosCone, glm::dot(normals[t - first], cl.axis));
    cl.usable = cl.cosCone >= 0.5;
  }
}

// MeshRange::firstTriangle, triangleCount, and the planes of each mesh (MeshPlane): triangles
// grouped by plane, a triangle joining the first group whose normal is within 1e-9 and offset
// within 1e-9 (relative) of its own (the two triangles of a box's face: equal up to rounding).
void buildMeshPlanes(Scene& scene) {
  constexpr double kMinShape = 0.02;  // well shaped, as for clusters (buildClusters)
  constexpr double kSame = 1e-9;
  scene.meshPlanes.clear();
  size_t t = 0;
  for (MeshRange& mesh : scene.meshes) {
    const uint32_t endFace = mesh.firstFace + mesh.faceCount;
    while (t < scene.triangles.size() && scene.triangles[t].face < mesh.firstFace) ++t;
    mesh.firstTriangle = uint32_t(t);
    while (t < scene.triangles.size() && scene.triangles[t].face < endFace) ++t;
    mesh.triangleCount = uint32_t(t - mesh.firstTriangle);
    mesh.firstPlane = uint32_t(scene.meshPlanes.size());
    mesh.planeCount = 0;
    bool usable = mesh.triangleCount > 0;
    for (size_t i = mesh.firstTriangle; usable && i < t; ++i) {
      const uint32_t* v = scene.triangles[i].v;
      const dvec3 &a = scene.positions[v[0]], &b = scene.positions[v[1]], &p = scene.positions[v[2]];
      const dvec3 cross = glm::cross(b - a, p - a);
      const double len = glm::length(cross);
      const double edge = std::max({glm::dot(b - a, b - a), glm::dot(p - b, p - b), glm::dot(a - p, a - p)});
      if (!(len >= kMinShape * edge) || !(len > 0) || !std::isfinite(len)) {
        usable = false;
        break;
      }
      const dvec3 n = cross / len;
      const double d = glm::dot(n, a);
      MeshPlane* group = nullptr;
      for (size_t g = mesh.firstPlane; g < scene.meshPlanes.size() && !group; ++g) {
        MeshPlane& mp = scene.meshPlanes[g];
        if (glm::length(n - mp.n) <= kSame && std::abs(d - mp.d) <= kSame * std::max(1.0, std::abs(mp.d))) group = &mp;
      }
      if (!group) {
        if (scene.meshPlanes.size() - mesh.firstPlane == kMaxMeshPlanes) {
          usable = false;
          break;
        }
        group = &scene.meshPlanes.emplace_back(MeshPlane{n, d, 0, 0});
      }
      group->nSlack = std::max(group->nSlack, glm::length(n - group->n));
      group->dSlack = std::max(group->dSlack, std::abs(d - group->d));
    }
    if (usable) mesh.planeCount = uint32_t(scene.meshPlanes.size() - mesh.firstPlane);
    else scene.meshPlanes.resize(mesh.firstPlane);
  }
}

}  // namespace

void Scene::addFace(std::span<const uint32_t> indices, Rgba8 color) {
  // Offsets are 32-bit: refuse a scene whose index list would overflow them.
  if (polygonIndices.size() + indices.size() > std::numeric_limits<uint32_t>::max())
    throw InputError(source + ": too many polygon vertices (more than 2^32)");
  polygonIndices.insert(polygonIndices.end(), indices.begin(), indices.end());
  polygonOffsets.push_back(uint32_t(polygonIndices.size()));
  faceColors.push_back(color);
}

void Scene::beginMesh(std::string name) {
  uint32_t first = uint32_t(faceCount());
  if (!meshes.empty()) meshes.back().faceCount = first - meshes.back().firstFace;
  meshes.push_back({std::move(name), first, 0, {}, 0, 0, 0, 0, 0, 0});
}

void Scene::finalize() {
  if (polygonOffsets.empty() || polygonOffsets.front() != 0 ||
      polygonOffsets.back() != polygonIndices.size() || faceColors.size() != faceCount())
    throw std::logic_error(source + ": Scene::finalize: polygon arrays are inconsistent");

  // Validation: every position finite and of sane magnitude.
  for (size_t i = 0; i < positions.size(); ++i) {
    const dvec3& p = positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError(source + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxCoordinate)
      throw InputError(source + ": vertex " + std::to_string(i) +
                       " has a coordinate beyond 1e30 in magnitude");
  }

  // Triangulation, face by face in order, so each face's triangles are together.
  triangles.clear();
  triangles.reserve(polygonIndices.size() > 2 * faceCount() ? polygonIndices.size() - 2 * faceCount() : 0);
  problems.degenerateFaces = problems.nonPlanarFaces = problems.concaveFaces = 0;
  Triangulator triangulator;
  uint64_t approximateFaces = 0;
  const size_t vertexCount = positions.size();
  for (size_t f = 0; f < faceCount(); ++f) {
    std::span<const uint32_t> poly = face(f);
    for (uint32_t v : poly)
      if (v >= vertexCount)
        throw InputError(source + ": " + faceLabel(f) + ": vertex index " + std::to_string(v) +
                         " out of range (" + std::to_string(vertexCount) + " vertices)");
    PolygonReport report = triangulator.run(positions, poly, uint32_t(f), triangles);
    if (report.degenerate) {
      ++problems.degenerateFaces;
      noteProblem(problems, problems.degenerateFaces,
                  [&] { return faceLabel(f) + ": degenerate (" + report.degenerateReason + "), not drawn"; });
      continue;
    }
    if (report.nonPlanar) {
      ++problems.nonPlanarFaces;
      noteProblem(problems, problems.nonPlanarFaces, [&] {
        return fmt::format("{}: non-planar (a vertex lies {:.3g} from the best-fit plane), triangulated anyway",
                           faceLabel(f), report.planeDistance);
      });
    }
    if (report.concave) ++problems.concaveFaces;
    if (report.approximate)
      noteProblem(problems, ++approximateFaces, [&] {
        return faceLabel(f) + ": too tangled to triangulate exactly (" + std::to_string(poly.size()) +
               " vertices, self-intersecting?): some of its triangles may overlap";
      });
  }
  for (auto [count, kind] : {std::pair{problems.degenerateFaces, "degenerate"},
                              std::pair{problems.nonPlanarFaces, "non-planar"}, std::pair{approximateFaces, "tangled"}})
    if (count > kMaxNotesPerKind) problems.notes.push_back(fmt::format("{} {} faces in all", count, kind));

  // Mesh ranges: a leading range for faces added before the first beginMesh() (or all faces
  // when none was begun), counts recomputed from the starts, empty ranges dropped.
  const uint32_t total = uint32_t(faceCount());
  if (meshes.empty() || meshes.front().firstFace != 0)
    meshes.insert(meshes.begin(), MeshRange{std::filesystem::path(source).stem().string(), 0, 0, {}, 0, 0, 0, 0, 0, 0});
  for (size_t m = 0; m < meshes.size(); ++m) {
    uint32_t end = m + 1 < meshes.size() ? meshes[m + 1].firstFace : total;
    if (end < meshes[m].firstFace || end > total)
      throw std::logic_error(source + ": Scene::finalize: mesh ranges out of order");
    meshes[m].faceCount = end - meshes[m].firstFace;
  }
  std::erase_if(meshes, [](const MeshRange& m) { return m.faceCount == 0; });
  for (MeshRange& mesh : meshes) {
    mesh.bounds = Bounds3{};
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f)
      for (uint32_t v : face(f)) mesh.bounds.add(positions[v]);
  }
  buildClusters(*this);
  buildMeshPlanes(*this);
  // Each mesh's vertex range, and whether the ranges are apart (ascending, not overlapping).
  meshVerticesApart = true;
  uint64_t end = 0;
  for (MeshRange& mesh : meshes) {
    uint32_t lo = std::numeric_limits<uint32_t>::max(), hi = 0;
    for (uint32_t f = mesh.firstFace; f < mesh.firstFace + mesh.faceCount; ++f)
      for (uint32_t v : face(f)) lo = std::min(lo, v), hi = std::max(hi, v);
    mesh.firstVertex = lo <= hi ? lo : uint32_t(end);
    mesh.vertexCount = lo <= hi ? hi - lo + 1 : 0;
    if (mesh.vertexCount && mesh.firstVertex < end) meshVerticesApart = false;
    if (mesh.vertexCount) end = uint64_t(mesh.firstVertex) + mesh.vertexCount;
  }
}


Bounds3 Scene::bounds() const {
  Bounds3 b;
  for (uint32_t v : polygonIndices)
    if (v < positions.size()) b.add(positions[v]);
  return b;
}

}  // namespace hsr

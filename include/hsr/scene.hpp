// Scenes: polygons in world space, kept as polygons (list-priority algorithms split polygons),
// with the triangulation every rasterizer consumes. Produced by the loaders (io.hpp) and the
// built-in generators (builtin.hpp); consumed by the front end and every algorithm.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/common.hpp>

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace hsr {

/// One triangle of the triangulation. `face` is the index of the polygon it came from
/// (docs/conventions.md: the face index is the polygon's position in file order).
struct Triangle {
  uint32_t v[3];
  uint32_t face;
};

/// A named group of consecutive faces (a mesh of the input file or of a scene JSON).
struct MeshRange {
  std::string name;
  uint32_t firstFace = 0;
  uint32_t faceCount = 0;
  Bounds3 bounds;  // of its faces' vertices; filled by Scene::finalize() (view culling per mesh)
  // Filled by Scene::finalize(): its triangles, Scene::triangles[firstTriangle, + triangleCount)
  // (faces in order, so a mesh's triangles are together), and the planes they lie in,
  // Scene::meshPlanes[firstPlane, + planeCount) — 0 planes when the mesh has more than
  // kMaxMeshPlanes or a triangle that is not well shaped: then a renderer cannot test it whole
  // for occlusion (the occlusion buffer's mesh culling, raster/tiled.hpp).
  uint32_t firstTriangle = 0, triangleCount = 0;
  uint32_t firstPlane = 0, planeCount = 0;
  // Filled by Scene::finalize(): the vertices its faces use lie in positions[firstVertex, +
  // vertexCount), a range no other mesh's faces use (Scene::meshVerticesApart), or nothing is said.
  uint32_t firstVertex = 0, vertexCount = 0;
};

/// A plane n . x = d that triangles of a mesh lie in, with room: each such triangle's own unit
/// normal n_t = normalize((v1 - v0) x (v2 - v0)) and offset d_t = n_t . v0, as computed in
/// double, are within nSlack of n (Euclidean) and dSlack of d, so a point e is at least
/// |d - n . e| - dSlack - nSlack |e| from the triangle's plane (up to the rounding of n_t, d_t).
struct MeshPlane {
  dvec3 n{0.0};
  double d = 0, nSlack = 0, dSlack = 0;
};
/// Planes kept per mesh, at most (a box has 6; a mesh with more is not tested whole).
inline constexpr uint32_t kMaxMeshPlanes = 16;

/// Triangles [kClusterTriangles i, kClusterTriangles (i + 1)) of a scene (Scene::clusters), with
/// what a renderer needs to decide about all of them at once from a camera: the tiled z-buffer
/// defers a cluster that faces away from the eye (raster/tiled.hpp: deferred clusters) and sets
/// its triangles up only if it may show. Filled by Scene::finalize().
struct TriangleCluster {
  Bounds3 bounds;        // of its triangles' vertices
  dvec3 axis{0.0};       // unit vector: the direction of the sum of its triangles' unit normals
  double cosCone = -1;   // every triangle's unit normal n has dot(n, axis) >= cosCone
  double minArea = 0;    // the least area of its triangles
  double maxEdge = 0;    // the longest edge of its triangles
  bool usable = false;   // full, in one mesh, every triangle well shaped, cosCone >= 1/2
};
// (32 rather than 64: tighter boxes, so fewer clusters set up in the tile pass near a
// silhouette; see docs/benchmarks.md.)
inline constexpr size_t kClusterTriangles = 32;

/// What the loader or finalize() found wrong and how it was handled. Counted, never fatal:
/// fatal problems (NaN, indices out of range, truncated files) throw InputError instead.
struct SceneProblems {
  uint64_t degenerateFaces = 0;    // fewer than 3 distinct vertices or zero area: not drawn
  uint64_t nonPlanarFaces = 0;     // polygons whose vertices leave their plane: triangulated anyway
  uint64_t concaveFaces = 0;       // triangulated by ear clipping
  std::vector<std::string> notes;  // first few human-readable notes ("face 12: degenerate")
};

/// A light for shadows (docs/shadows.md): a sun, by the direction its light travels, or a point.
struct Light {
  enum class Kind : uint8_t { Directional, Point };
  Kind kind = Kind::Directional;
  dvec3 vector{0, 0, 0};  // Directional: the direction the light travels (not zero); Point: its position
};

/// One node of a scene's CSG tree (Scene::csg; docs/scene-json.md "csg"): a solid, the closed
/// mesh made of faces [first, first + count), or a set operation of two earlier nodes.
struct CsgNode {
  enum class Op : uint8_t { Solid, Union, Intersection, Difference };
  Op op = Op::Solid;
  uint32_t first = 0, count = 0;  // Solid: its faces
  uint32_t left = 0, right = 0;   // an operation: its operands, indices of earlier nodes
};
/// Solids a CSG tree may hold, at most (the csg algorithm keeps a 64-bit mask of them per pixel).
inline constexpr size_t kMaxCsgSolids = 64;

struct Scene {
  std::string source;  // file name or "builtin:NAME"; used in error messages

  // Polygons. Face f has the vertex indices polygonIndices[polygonOffsets[f] .. polygonOffsets[f+1]).
  std::vector<dvec3> positions;
  std::vector<uint32_t> polygonIndices;
  std::vector<uint32_t> polygonOffsets{0};
  std::vector<Rgba8> faceColors;  // one per face; alpha = opacity
  std::vector<MeshRange> meshes;  // in file order, covering all faces

  // Filled by finalize(): the triangulation (faces in order, each face's triangles together;
  // degenerate faces have none) and the problems found.
  std::vector<Triangle> triangles;
  SceneProblems problems;
  // Filled by finalize(): one per kClusterTriangles triangles (the last one may be short; then it
  // is not usable). Normals are (v1 - v0) x (v2 - v0) of the triangles' vertices.
  std::vector<TriangleCluster> clusters;
  // Filled by finalize(): the planes of the meshes (MeshRange::firstPlane, planeCount).
  std::vector<MeshPlane> meshPlanes;
  // Filled by finalize(): whether each mesh's faces use vertices of its own range only
  // (MeshRange::firstVertex, vertexCount), so that a renderer may transform a mesh's vertices
  // only when it draws the mesh.
  bool meshVerticesApart = false;

  // A CSG tree over the scene's faces, its root last (empty: none). The algorithms that declare
  // Capability::Csg show the tree's result (faces outside its solids as plain surfaces); the
  // others draw every face as a plain surface.
  std::vector<CsgNode> csg;

  std::optional<CameraSpec> camera;  // a camera stored in the scene file, if any
  std::optional<Light> light;        // a light stored in the scene file, if any

  size_t faceCount() const { return polygonOffsets.size() - 1; }
  std::span<const uint32_t> face(size_t f) const {
    return {polygonIndices.data() + polygonOffsets[f], polygonOffsets[f + 1] - polygonOffsets[f]};
  }
  /// Appends a polygon (3+ vertex indices into positions) with its colour.
  void addFace(std::span<const uint32_t> indices, Rgba8 color);
  void addFace(std::initializer_list<uint32_t> indices, Rgba8 color) {
    addFace(std::span<const uint32_t>(indices.begin(), indices.size()), color);
  }
  /// Starts a new mesh range; faces added afterwards belong to it.
  void beginMesh(std::string name);

  /// Validates (finite coordinates, indices in range: throws InputError naming `source`) and
  /// triangulates every polygon (ear clipping in the polygon's best-fit plane, so concave
  /// polygons are correct). Must be called once all faces are added.
  void finalize();

  Bounds3 bounds() const;  // of the vertices used by faces
};

}  // namespace hsr

// A BSP tree of a scene's polygons [KTH report, KTH thesis]: built once in world space by
// auto-partition (every splitting plane is the plane of one of the scene's faces), traversed
// back to front from any viewpoint to give a painter's order that is right for every camera.
// Built by the `bsp` algorithm (src/algorithms/bsp.cpp) and by tests; any thread may traverse it.
#pragma once
#include <hsr/common.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hsr {

struct Scene;

/// How a node's splitting plane is chosen from the polygons that reach it.
enum class BspHeuristic : uint8_t {
  First,   // the first polygon of the node's list (face order)
  Scored,  // the best of up to kBspCandidates evenly spaced candidates (BspTree::build)
  Area,    // half Scored's candidates, half the largest polygons; splits weighted by area (the default)
};
inline constexpr int kBspCandidates = 8;
/// The scored heuristic counts a candidate's splits over at most this many polygons of the list,
/// evenly spaced (all of them when the list is no longer).
inline constexpr int kBspScoreSample = 1024;

struct BspBuildOptions {
  BspHeuristic heuristic = BspHeuristic::Area;
  uint64_t maxFragments = 4'000'000;  // build() throws InputError rather than make more
};

class BspTree {
 public:
  /// A convex planar piece of one of the scene's faces (the whole face when no plane cut it).
  struct Fragment {
    uint32_t firstVertex = 0, vertexCount = 0;  // into vertices()
    uint32_t face = 0;                          // the scene's face it is part of
    uint32_t triangle = 0;                      // a scene triangle of that face, with its normal
  };
  struct Node {
    dvec3 n{0.0};  // the splitting plane n . x = d (unit n): front is n . x > d
    double d = 0;
    uint32_t firstFragment = 0, fragmentCount = 0;  // the fragments in its plane, in drawing order
    int32_t front = -1, back = -1;                  // children, -1 for none
  };

  /// Builds the tree of a finalized scene's faces. A convex planar face is one polygon; a concave
  /// or non-planar one enters as its triangles. Faces of no area are left out. Throws InputError
  /// when the tree would hold more than options.maxFragments fragments.
  static BspTree build(const Scene& scene, const BspBuildOptions& options = {});

  /// The fragments back to front as seen from `eye`, homogeneous: (position, 1) for a
  /// perspective eye, (direction towards the eye, 0) for an orthographic one. Iterative.
  void backToFront(const dvec4& eye, std::vector<uint32_t>& order) const;

  std::span<const Node> nodes() const { return nodes_; }
  std::span<const Fragment> fragments() const { return fragments_; }
  std::span<const dvec3> vertices() const { return vertices_; }
  std::span<const dvec3> polygon(const Fragment& f) const { return {vertices_.data() + f.firstVertex, f.vertexCount}; }
  uint64_t inputPolygons() const { return inputPolygons_; }  // polygons before splitting
  uint64_t splits() const { return splits_; }                // polygons cut in two
  uint32_t depth() const { return depth_; }                  // nodes on the longest root-to-leaf path
  double epsilon() const { return epsilon_; }                // "on the plane" distance used

 private:
  std::vector<Node> nodes_;
  std::vector<Fragment> fragments_;
  std::vector<dvec3> vertices_;
  uint64_t inputPolygons_ = 0, splits_ = 0;
  uint32_t depth_ = 0;
  double epsilon_ = 0;
};

}  // namespace hsr

// The painter's algorithm [KTH report, KTH thesis, Java chapter]: sort the faces by one depth
// each and paint them back to front, each overwriting what is behind it, with no depth buffer.
// One point per polygon cannot represent the order of polygons that overlap in depth: it fails
// when a polygon's key is behind another's although part of it is in front (the midpoint
// failure), when polygons overlap in a cycle, and when they interpenetrate. Those failures are
// declared, per sort key, and checked by the conformance suite like any guarantee.
#include <algorithm>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

class Painter final : public SceneAlgorithm, public PaintsInOrder {
 public:
  using SceneAlgorithm::SceneAlgorithm;

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const SortKey key = sortKeyOf(params_.text("sort-key"));
    drawScene(scene_, camera, options, hasTransparency(scene_) ? WriteRule::Blend : WriteRule::Overwrite,
              drawRasterOf(params_), byFaceRank(faceRanks(faceKeys(scene_, camera, key), /*backToFront=*/true), &buffers_.frameScratch().reordered),
              buffers_, frame);
    frame.stats.setDetail("sort_key", params_.text("sort-key"));
  }

  // Each face as its polygon (its triangles when it is not convex and planar), faces by rank.
  void paintedPolygons(const Camera& camera, PaintedPolygons& out) override {
    const std::vector<uint32_t> rank =
        faceRanks(faceKeys(scene_, camera, sortKeyOf(params_.text("sort-key"))), /*backToFront=*/true);
    struct Entry {
      uint32_t rank;
      PolygonRef polygon;
      uint32_t triangle;
    };
    std::vector<Entry> entries;
    out.vertices.clear();
    forEachConvexPolygon(scene_, sceneEpsilon(scene_),
                         [&](std::span<const dvec3> vertices, const SplitPlane&, uint32_t face, uint32_t triangle) {
                           entries.push_back(
                               {rank[face], {uint32_t(out.vertices.size()), uint32_t(vertices.size()), face}, triangle});
                           out.vertices.insert(out.vertices.end(), vertices.begin(), vertices.end());
                         });
    std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.rank < b.rank; });
    out.polygons.clear();
    out.triangles.clear();
    for (const Entry& e : entries) {
      out.polygons.push_back(e.polygon);
      out.triangles.push_back(e.triangle);
    }
  }
};

}  // namespace

Guarantee listPriorityFailures(const std::string& key) {
  Guarantee g;
  g.kind = Guarantee::Kind::FailsByDesign;
  g.condition = "one depth per face misorders faces that overlap in depth; cycles and interpenetration need splits";
  g.failsOn = listPriorityFailureScenes(key);
  g.exactWhen = "no two faces that overlap on screen overlap in depth";
  g.holds = [](const Scene& scene, const Camera& camera, const RenderOptions&) {
    return depthRangesSeparate(scene, camera);
  };
  return g;
}

AlgorithmInfo painterAlgorithm() {
  AlgorithmInfo a;
  a.name = "painter";
  a.summary = "painter's algorithm: faces sorted by one depth each, painted back to front, no depth buffer";
  a.source = "KTH report, KTH thesis, Java chapter";
  a.params = {sortKeyParam("centroid",
                           "the depth a face is sorted by: its area centroid (the documents' midpoint), its farthest "
                           "vertex, its nearest vertex, or the mean of its vertices"),
              drawRasterParam("binned", /*kernel=*/true)};
  a.guaranteeFor = [](const AlgorithmParams& p) { return listPriorityFailures(p.text("sort-key")); };
  a.guarantee = listPriorityFailures("centroid");
  a.capability = Capability::PaintsInOrder;
  a.create = factoryOf<Painter>();
  return a;
}

}  // namespace hsr::algo

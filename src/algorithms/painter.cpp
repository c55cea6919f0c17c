// The painter's algorithm [KTH report, KTH thesis, Java chapter]: sort the faces by one depth
// each and paint them back to front, each overwriting what is behind it, with no depth buffer.
// One point per polygon cannot represent the order of polygons that overlap in depth: it fails
// when a polygon's key is behind another's although part of it is in front (the midpoint
// failure), when polygons overlap in a cycle, and when they interpenetrate. Those failures are
// declared, per sort key, and checked by the conformance suite like any guarantee.
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

void painter(const Scene& scene, const Camera& camera, const RenderOptions& options, const AlgorithmParams& params,
             Frame& frame) {
  const SortKey key = sortKeyOf(params.text("sort-key"));
  drawScene(scene, camera, options, WriteRule::Overwrite, drawRasterOf(params),
            byFaceRank(faceRanks(faceKeys(scene, camera, key), /*backToFront=*/true)), frame);
  frame.stats.setDetail("sort_key", params.text("sort-key"));
}

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
              drawRasterParam("binned")};
  a.guaranteeFor = [](const AlgorithmParams& p) { return listPriorityFailures(p.text("sort-key")); };
  a.guarantee = listPriorityFailures("centroid");
  a.run = painter;
  return a;
}

}  // namespace hsr::algo

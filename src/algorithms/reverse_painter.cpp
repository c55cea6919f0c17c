// The reverse painter's algorithm [Java chapter]: faces drawn front to back, each pixel written
// only once (a mask of written pixels, no depth buffer), stopping when the image is full. It
// never overdraws, but it needs an order that is right for every pair of overlapping faces: a
// sort key gives the painter's order reversed, with the painter's failures.
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

void reversePainter(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    const AlgorithmParams& params, Frame& frame) {
  const SortKey key = sortKeyOf(params.text("order"));
  drawScene(scene, camera, options, WriteRule::WhereUnwritten, drawRasterOf(params),
            byFaceRank(faceRanks(faceKeys(scene, camera, key), /*backToFront=*/false)), frame);
  frame.stats.setDetail("order", params.text("order"));
}

}  // namespace

AlgorithmInfo reversePainterAlgorithm() {
  AlgorithmInfo a;
  a.name = "reverse-painter";
  a.summary = "reverse painter's: faces front to back, each pixel written once, no depth buffer, stops when full";
  a.source = "Java chapter";
  a.params = {{"order", ParamType::Choice, "centroid", {"centroid", "max", "min", "mean-vertex"}, -1e300, 1e300,
               "the front-to-back order: faces sorted nearest first by their area centroid, farthest vertex, "
               "nearest vertex, or the mean of their vertices"},
              drawRasterParam("binned")};
  a.guaranteeFor = [](const AlgorithmParams& p) { return listPriorityFailures(p.text("order")); };
  a.guarantee = listPriorityFailures("centroid");
  a.run = reversePainter;
  return a;
}

}  // namespace hsr::algo

// The reverse painter's algorithm [Java chapter]: faces drawn front to back, each pixel written
// only once (a mask of written pixels, no depth buffer), stopping when the image is full. It
// never overdraws, but it needs an order that is right for every pair of overlapping faces: a
// sort key gives the painter's order reversed, with the painter's failures; the BSP tree's
// front-to-back order (the default) is exact. With transparent faces each pixel takes fragments
// until it is opaque, each composited under the nearer ones (the "under" operator), and the
// background under all: the order that blends right is then the same exact one.
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

class ReversePainter final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const WriteRule rule = hasTransparency(scene_) && has(options.outputs, FrameOutputs::Color)
                               ? WriteRule::BlendUnder
                               : WriteRule::WhereUnwritten;
    if (params_.text("order") == "bsp") {  // the BSP tree's exact order, reversed
      tree_.draw(scene_, camera, options, rule, drawRasterOf(params_), /*frontToBack=*/true, buffers_, frame);
    } else {
      const SortKey key = sortKeyOf(params_.text("order"));
      drawScene(scene_, camera, options, rule, drawRasterOf(params_),
                byFaceRank(faceRanks(faceKeys(scene_, camera, key), /*backToFront=*/false), &buffers_.frameScratch().reordered), buffers_, frame);
    }
    frame.stats.setDetail("order", params_.text("order"));
  }

 private:
  BspDrawing tree_{BspBuildOptions{}};  // order=bsp: the default heuristic's tree, built at the first frame
};

}  // namespace

AlgorithmInfo reversePainterAlgorithm() {
  AlgorithmInfo a;
  a.name = "reverse-painter";
  a.summary = "reverse painter's: faces front to back, each pixel written once, no depth buffer, stops when full";
  a.source = "Java chapter";
  a.params = {{"order", ParamType::Choice, "bsp", {"bsp", "centroid", "max", "min", "mean-vertex"}, -1e300, 1e300,
               "the front-to-back order: the BSP tree's (exact; the default heuristic, area, built once per scene), "
               "or faces sorted nearest first by their area centroid, farthest vertex, nearest vertex, or the mean "
               "of their vertices"},
              drawRasterParam("binned", /*kernel=*/true)};
  a.guaranteeFor = [](const AlgorithmParams& p) {
    if (p.text("order") != "bsp") return listPriorityFailures(p.text("order"));
    Guarantee exact;
    exact.condition = "the BSP tree's order is right for every pair of fragments";
    return exact;
  };
  a.guarantee = a.guaranteeFor(resolveParams(a, {}));
  a.create = factoryOf<ReversePainter>();
  return a;
}

}  // namespace hsr::algo

// The sorted z-buffer, the combination the KTH report and thesis propose: sort the faces front
// to back, then run the textbook z-buffer in that order. Nearer faces come first, so hidden ones
// mostly fail the depth test and a pixel is rarely written twice; but the sort must finish before
// the first face is drawn, so it is no longer online, and it pays for the sort.
#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"

namespace hsr::algo {
namespace {

class SortedZbuffer final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const SortKey key = sortKeyOf(params_.text("sort-key"));
    std::vector<uint32_t> rank = faceRanks(faceKeys(scene_, camera, key), /*backToFront=*/false);
    // With transparency: the opaque faces front to back, then the transparent ones back to front,
    // depth-tested without depth writes.
    const bool transparent = hasTransparency(scene_);
    if (transparent) rank = transparentLast(scene_, camera, rank, key);
    drawScene(scene_, camera, options, transparent ? WriteRule::DepthTestBlend : WriteRule::DepthTest,
              drawRasterOf(params_), byFaceRank(std::move(rank), &buffers_.frameScratch().reordered), buffers_, frame);
    frame.stats.setDetail("sort_key", params_.text("sort-key"));
  }
};

}  // namespace

AlgorithmInfo sortedZbufferAlgorithm() {
  AlgorithmInfo a;
  a.name = "sorted-zbuffer";
  a.summary = "front-to-back sort, then the textbook z-buffer in that order: little overdraw, not online";
  a.source = "KTH report, KTH thesis";
  a.params = {sortKeyParam("min", "the depth faces are sorted by, nearest first: their nearest vertex, area centroid, "
                                  "farthest vertex, or the mean of their vertices"),
              drawRasterParam("binned", /*kernel=*/true)};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "a z-buffer in any order; ties of equal depth are ambiguous";
  a.create = factoryOf<SortedZbuffer>();
  return a;
}

}  // namespace hsr::algo

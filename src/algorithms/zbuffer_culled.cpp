// The textbook z-buffer with occlusion culling: the scene's meshes drawn in batches nearest
// first, each mesh's screen box and nearest depth tested against a z-pyramid kept over the depth
// buffer before any of its triangles is set up; the triangles left drawn by the textbook loop (a
// depth test per fragment, the scalar half-space rasterizer). The object loop and the pyramid are
// the hierarchical z-buffer's (hzb.cpp), without its test per triangle.
#include "algorithms/algorithms.hpp"

namespace hsr::algo {
namespace {

// The pyramid is rebuilt over each frame's depth buffer; with temporal=on the object keeps the
// meshes the last frame showed.
class ZbufferCulled final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    const bool temporal = params_.flag("temporal");
    zbufferOcclusionCulled(scene_, camera, options, temporal ? &shown_ : nullptr, frame);
    frame.stats.setDetail("temporal", temporal ? "on" : "off");
  }

 private:
  MeshesShown shown_;
};

}  // namespace

AlgorithmInfo zbufferCulledAlgorithm() {
  AlgorithmInfo a;
  a.name = "zbuffer-culled";
  a.summary = "the textbook z-buffer with occlusion culling: meshes hidden behind what is drawn are dropped whole "
              "before set-up";
  a.source = "Ukrainian paper (occlusion culling on the hierarchical z-buffer's pyramid; temporal coherence)";
  a.params = {{"temporal", ParamType::Bool, "off", {}, -1e300, 1e300,
               "temporal coherence: the meshes that showed in the previous frame drawn first, untested, as occluders, "
               "and every other mesh tested against them (the first frame, or a new scene, has none)"}};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "up to the depth format's precision: z-fighting is counted as ambiguous";
  a.create = factoryOf<ZbufferCulled>();
  return a;
}

}  // namespace hsr::algo

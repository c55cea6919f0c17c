// The `bsp` algorithm [KTH report, KTH thesis]: the scene's BSP tree (bsp_tree.cpp) built at the
// first frame and kept by the algorithm object, its fragments a derived scene (draw.hpp,
// DerivedScene), each frame painted back to front from the eye with the drawing service's
// Overwrite rule, no depth buffer. BspDrawing is also the reverse painter's exact order.
#include <hsr/bsp.hpp>
#include <hsr/scene.hpp>

#include <memory>
#include <string>

#include "algorithms/algorithms.hpp"
#include "algorithms/sort_keys.hpp"
#include "algorithms/draw.hpp"
#include "core/timer.hpp"

namespace hsr::algo {

// A tree with its fragments as a scene the drawing service draws (DerivedScene).
struct BspDrawing::Built {
  BspTree tree;
  Scene scene;
  DerivedScene derived;
  std::vector<uint32_t> fragmentOf;  // per face of `scene`: the fragment it is part of
  double buildMs = 0;
};

namespace {

constexpr size_t kFragmentsPerMesh = 1024;

// The eye as BspTree::backToFront takes it: the camera centre, or for an orthographic camera
// the direction back along the view (a point at infinity).
dvec4 homogeneousEye(const Camera& camera) {
  if (!camera.orthographic) return dvec4(camera.eyeWorld(), 1.0);
  const dvec3 forward = dvec3(glm::inverse(camera.cameraFromWorld) * dvec4(0, 0, 1, 0));
  return dvec4(-forward, 0.0);
}

// The tree's fragments as scene faces: each fragment a fan of triangles around its centre (an
// added vertex), one face each. A convex fragment's vertices on one line (where a neighbour's cut
// ends, a T-junction) are then corners of non-degenerate triangles, so the snapped fragments meet
// without a crack. (Triangulated as one polygon, such a vertex would be dropped as a zero-area ear.)
void addFragmentFaces(const Scene& scene, BspDrawing::Built& built);

}  // namespace

BspDrawing::BspDrawing(const BspBuildOptions& build) : options_(build) {}
BspDrawing::~BspDrawing() = default;

bool BspDrawing::build(const Scene& scene) {
  if (built_) return false;
  Timer timer;
  auto built = std::make_unique<Built>();
  built->tree = BspTree::build(scene, options_);
  addFragmentFaces(scene, *built);
  built->buildMs = timer.ms();
  built_ = std::move(built);
  return true;
}

void BspDrawing::draw(const Scene& scene, const Camera& camera, const RenderOptions& options, WriteRule rule,
                      DrawRaster raster, bool frontToBack, DrawBuffers& buffers, Frame& frame) {
  const bool built = build(scene);
  const BspTree& tree = built_->tree;
  Timer timer;
  std::vector<uint32_t> order;
  tree.backToFront(homogeneousEye(camera), order);
  std::vector<uint32_t> rank(order.size());
  for (uint32_t i = 0; i < order.size(); ++i) rank[order[i]] = frontToBack ? uint32_t(order.size()) - 1 - i : i;
  const double traverseMs = timer.lap();

  // Set-up triangles in their fragment's rank (byFaceRank: a stable counting sort), each face of
  // the derived scene ranked as the fragment it is part of.
  const std::vector<uint32_t>& fragmentOf = built_->fragmentOf;
  std::vector<uint32_t> faceRank(fragmentOf.size());
  for (size_t f = 0; f < fragmentOf.size(); ++f) faceRank[f] = rank[fragmentOf[f]];
  const OrderFn byRank = byFaceRank(std::move(faceRank), &buffers.frameScratch().reordered);
  drawScene(scene, camera, options, rule, raster, byRank, buffers, frame, &built_->derived, /*exactOrder=*/true);

  Stats& st = frame.stats;
  if (built) st.addTime("build", built_->buildMs);
  st.addTime("traverse", traverseMs);
  st.setDetail("nodes", uint64_t(tree.nodes().size()));
  st.setDetail("fragments", uint64_t(tree.fragments().size()));
  st.setDetail("splits", tree.splits());
  st.setDetail("depth", uint64_t(tree.depth()));
  st.setDetail("built", uint64_t(built ? 1 : 0));
  if (built) st.setDetail("build_ms", built_->buildMs);
  st.addMemory("bsp_tree", tree.nodes().size() * sizeof(BspTree::Node) +
                               tree.fragments().size() * sizeof(BspTree::Fragment) +
                               tree.vertices().size() * sizeof(dvec3));
  st.addMemory("bsp_order", rank.size() * 2 * sizeof(uint32_t));
}

void BspDrawing::polygons(const Scene& scene, const Camera& camera, PaintedPolygons& out) {
  build(scene);
  const BspTree& tree = built_->tree;
  std::vector<uint32_t> order;
  tree.backToFront(homogeneousEye(camera), order);
  out.vertices.assign(tree.vertices().begin(), tree.vertices().end());
  out.polygons.clear();
  out.triangles.clear();
  for (uint32_t i : order) {
    const BspTree::Fragment& f = tree.fragments()[i];
    out.polygons.push_back({f.firstVertex, f.vertexCount, f.face});
    out.triangles.push_back(f.triangle);
  }
}

namespace {

void addFragmentFaces(const Scene& scene, BspDrawing::Built& built) {
  const BspTree& tree = built.tree;
  Scene& s = built.scene;
  s.source = scene.source + " (bsp fragments)";
  s.positions.assign(tree.vertices().begin(), tree.vertices().end());
  for (uint32_t i = 0; i < tree.fragments().size(); ++i) {
    const BspTree::Fragment& f = tree.fragments()[i];
    // Fragments are in node order, a subtree's together (a convex cell of space): meshes of
    // consecutive fragments are compact, so the front end culls those outside the view whole.
    if (i % kFragmentsPerMesh == 0) s.beginMesh("bsp");
    auto addFace = [&](std::initializer_list<uint32_t> corners) {
      s.addFace(corners, scene.faceColors[f.face]);
      built.fragmentOf.push_back(i);
    };
    if (f.vertexCount == 3) {
      addFace({f.firstVertex, f.firstVertex + 1, f.firstVertex + 2});
      continue;
    }
    dvec3 centre{0.0};
    for (uint32_t k = 0; k < f.vertexCount; ++k) centre += s.positions[f.firstVertex + k];
    const uint32_t c = uint32_t(s.positions.size());
    s.positions.push_back(centre / double(f.vertexCount));
    for (uint32_t k = 0; k < f.vertexCount; ++k)
      addFace({c, f.firstVertex + k, f.firstVertex + (k + 1) % f.vertexCount});
  }
  s.finalize();
  built.derived.scene = &s;
  for (uint32_t fragment : built.fragmentOf) built.derived.face.push_back(tree.fragments()[fragment].face);
  for (const Triangle& t : s.triangles) built.derived.triangle.push_back(tree.fragments()[built.fragmentOf[t.face]].triangle);
}

BspBuildOptions buildOptionsOf(const AlgorithmParams& params) {
  BspBuildOptions build;
  const std::string heuristic = params.text("heuristic");
  build.heuristic = heuristic == "first"   ? BspHeuristic::First
                    : heuristic == "scored" ? BspHeuristic::Scored
                                            : BspHeuristic::Area;
  build.maxFragments = uint64_t(params.integer("max-fragments"));
  return build;
}

class Bsp final : public SceneAlgorithm, public PaintsInOrder {
 public:
  Bsp(const Scene& scene, const AlgorithmParams& params)
      : SceneAlgorithm(scene, params), tree_(buildOptionsOf(params)) {}

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    tree_.draw(scene_, camera, options, hasTransparency(scene_) ? WriteRule::Blend : WriteRule::Overwrite,
               drawRasterOf(params_), /*frontToBack=*/false, buffers_, frame);
    frame.stats.setDetail("heuristic", params_.text("heuristic"));
  }

  void paintedPolygons(const Camera& camera, PaintedPolygons& out) override { tree_.polygons(scene_, camera, out); }

 private:
  BspDrawing tree_;
};

}  // namespace

AlgorithmInfo bspAlgorithm() {
  AlgorithmInfo a;
  a.name = "bsp";
  a.summary = "BSP tree: polygons split by their own planes once per scene, painted back to front from the eye";
  a.source = "KTH report, KTH thesis";
  a.params = {
      {"heuristic", ParamType::Choice, "area", {"area", "scored", "first"}, -1e300, 1e300,
       "the splitting plane of a node, through one of its polygons: first: the first polygon of its list (face "
       "order); scored: of c = min(m, 8) candidates at positions i*m/c of its m polygons, the one that splits "
       "the fewest of the polygons at positions j*m/s (s = min(m, 1024)), ties broken by the least "
       "|front - back| of those, then by the earliest position; area: as scored, but of h = ceil(c/2) candidates "
       "at positions i*m/h and the c - h largest polygons, each split of a polygon of area a by a candidate of "
       "area A counted 1 + 4a/A"},
      {"max-fragments", ParamType::Int, "4000000", {}, 1, 1e9,
       "the most fragments the tree may hold: a build that would make more stops with an error"},
      drawRasterParam("binned", /*kernel=*/true),
  };
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.capability = Capability::PaintsInOrder;
  a.create = factoryOf<Bsp>();
  return a;
}

}  // namespace hsr::algo

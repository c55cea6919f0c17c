// The BSP tree [KTH report, KTH thesis] (include/hsr/bsp.hpp) and the `bsp` algorithm: the tree
// is built once per scene by auto-partition in world space, its fragments become a derived scene
// (draw.hpp, DerivedScene), and each frame paints them back to front from the eye with the
// drawing service's Overwrite rule, no depth buffer. Build and traversal use explicit stacks: a
// convex mesh makes a chain as deep as its face count. Runs on the caller's thread.
#include <hsr/bsp.hpp>
#include <hsr/limits.hpp>
#include <hsr/scene.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/polygon_split.hpp"
#include "core/timer.hpp"

namespace hsr {
namespace {

using algo::classifyPolygon;
using algo::isPlanarConvex;
using algo::planeOfPolygon;
using algo::PolygonSide;
using algo::splitPolygon;
using algo::SplitPlane;

// A polygon while the tree is built: vertices in the builder's pool, its face's plane.
struct WorkPolygon {
  uint32_t first = 0, count = 0;
  uint32_t face = 0, triangle = 0;
  uint32_t plane = 0;  // index into Builder::planes: the plane of the input polygon it came from
};

// Bytes the builder holds per fragment (its polygon, vertices, plane and list entries), from the
// peak resident size of a build that reached 4 million fragments (1.48 GB).
constexpr double kBytesPerFragment = 384;

struct Job {
  int32_t node;
  uint32_t depth;
  std::vector<uint32_t> polygons;  // into Builder::polygons
};

class Builder {
 public:
  Builder(const Scene& scene, const BspBuildOptions& options)
      : scene_(scene), options_(options), memoryFragments_(double(memoryLimit()) / kBytesPerFragment) {}
  BspTree::Node& node(int32_t i) { return nodes_[size_t(i)]; }
  void addInputPolygons();
  uint32_t chooseSplitter(const std::vector<uint32_t>& list) const;
  void partition(Job& job, std::vector<Job>& stack);
  void closeTJunctions();
  void finish(std::vector<BspTree::Node>& nodes, std::vector<BspTree::Fragment>& fragments,
              std::vector<dvec3>& vertices);

  std::vector<BspTree::Node> nodes_;
  std::vector<WorkPolygon> polygons_;
  std::vector<SplitPlane> planes_;
  std::vector<dvec3> pool_;
  std::vector<uint32_t> placed_;  // polygons in node order, each node's in drawing order
  uint64_t inputs_ = 0, splits_ = 0;
  uint32_t depth_ = 0;
  double epsilon_ = 0;

 private:
  std::span<const dvec3> verticesOf(const WorkPolygon& p) const { return {pool_.data() + p.first, p.count}; }
  void addPolygon(std::span<const dvec3> vertices, const SplitPlane& plane, uint32_t face, uint32_t triangle);
  uint32_t addPiece(const std::vector<dvec3>& vertices, const WorkPolygon& from);
  /// Throws InputError when the tree would hold more fragments than the memory limit allows.
  void checkMemoryFor(uint64_t fragments) const {
    if (double(fragments) > memoryFragments_)
      checkMemory(double(fragments) * kBytesPerFragment,
                  "bsp: the tree of " + scene_.source + " (" + std::to_string(fragments) + " fragments so far)");
  }

  const Scene& scene_;
  const BspBuildOptions& options_;
  const double memoryFragments_;  // fragments that fit in the memory limit
};

void Builder::addPolygon(std::span<const dvec3> vertices, const SplitPlane& plane, uint32_t face, uint32_t triangle) {
  WorkPolygon p;
  p.first = uint32_t(pool_.size());
  p.count = uint32_t(vertices.size());
  p.face = face;
  p.triangle = triangle;
  p.plane = uint32_t(planes_.size());
  planes_.push_back(plane);
  pool_.insert(pool_.end(), vertices.begin(), vertices.end());
  polygons_.push_back(p);
}

// Every face with area as one polygon (convex and planar) or as its triangles (otherwise), in
// face order, with planes computed in double from the polygon's own vertices.
void Builder::addInputPolygons() {
  epsilon_ = algo::sceneEpsilon(scene_);
  algo::forEachConvexPolygon(scene_, epsilon_,
                             [&](std::span<const dvec3> vertices, const SplitPlane& plane, uint32_t face,
                                 uint32_t triangle) { addPolygon(vertices, plane, face, triangle); });
  inputs_ = polygons_.size();
  if (inputs_ > options_.maxFragments)
    throw InputError("bsp: " + scene_.source + " has " + std::to_string(inputs_) +
                     " polygons, more than max-fragments=" + std::to_string(options_.maxFragments));
  checkMemoryFor(inputs_);
}

// The position in `list` of the splitting polygon (BspHeuristic): for Scored, candidates at
// positions i m / c (c = min(m, kBspCandidates)), each scored against the polygons at positions
// j m / s (s = min(m, kBspScoreSample)): fewest splits, then least |front - back|, then earliest.
uint32_t Builder::chooseSplitter(const std::vector<uint32_t>& list) const {
  const size_t m = list.size();
  if (options_.heuristic == BspHeuristic::First || m <= 2) return 0;
  const size_t c = std::min<size_t>(m, kBspCandidates), s = std::min<size_t>(m, kBspScoreSample);
  uint32_t best = 0;
  uint64_t bestSplits = UINT64_MAX, bestImbalance = UINT64_MAX;
  for (size_t i = 0; i < c; ++i) {
    const size_t at = i * m / c;
    const SplitPlane& plane = planes_[polygons_[list[at]].plane];
    uint64_t splits = 0, front = 0, back = 0;
    for (size_t j = 0; j < s && splits <= bestSplits; ++j) {
      const size_t k = j * m / s;
      if (k == at) continue;
      switch (classifyPolygon(verticesOf(polygons_[list[k]]), plane, epsilon_)) {
        case PolygonSide::Front: ++front; break;
        case PolygonSide::Back: ++back; break;
        case PolygonSide::Spanning: ++splits; break;
        case PolygonSide::Coplanar: break;
      }
    }
    const uint64_t imbalance = front > back ? front - back : back - front;
    if (splits < bestSplits || (splits == bestSplits && imbalance < bestImbalance)) {
      best = uint32_t(at);
      bestSplits = splits;
      bestImbalance = imbalance;
    }
  }
  return best;
}

uint32_t Builder::addPiece(const std::vector<dvec3>& vertices, const WorkPolygon& from) {
  WorkPolygon p = from;
  p.first = uint32_t(pool_.size());
  p.count = uint32_t(vertices.size());
  pool_.insert(pool_.end(), vertices.begin(), vertices.end());
  polygons_.push_back(p);
  return uint32_t(polygons_.size() - 1);
}

// One node: its plane from the chosen polygon, the coplanar polygons kept in it (the face
// submitted first drawn last, so it wins as in the z-buffer), the others sent to new children.
void Builder::partition(Job& job, std::vector<Job>& stack) {
  const uint32_t chosen = chooseSplitter(job.polygons);
  const SplitPlane plane = planes_[polygons_[job.polygons[chosen]].plane];
  std::vector<uint32_t> on, front, back;
  std::vector<dvec3> frontPart, backPart;
  for (size_t i = 0; i < job.polygons.size(); ++i) {
    const uint32_t id = job.polygons[i];
    const PolygonSide side =
        i == chosen ? PolygonSide::Coplanar : classifyPolygon(verticesOf(polygons_[id]), plane, epsilon_);
    switch (side) {
      case PolygonSide::Coplanar: on.push_back(id); break;
      case PolygonSide::Front: front.push_back(id); break;
      case PolygonSide::Back: back.push_back(id); break;
      case PolygonSide::Spanning: {
        splitPolygon(verticesOf(polygons_[id]), plane, epsilon_, frontPart, backPart);
        const WorkPolygon from = polygons_[id];
        if (!frontPart.empty()) front.push_back(addPiece(frontPart, from));
        if (!backPart.empty()) back.push_back(addPiece(backPart, from));
        ++splits_;
        if (inputs_ + splits_ > options_.maxFragments)
          throw InputError("bsp: the tree of " + scene_.source + " would hold more than max-fragments=" +
                           std::to_string(options_.maxFragments) + " fragments (from " + std::to_string(inputs_) +
                           " polygons); raise --param max-fragments or try the other heuristic");
        checkMemoryFor(inputs_ + splits_);
        break;
      }
    }
  }
  std::stable_sort(on.begin(), on.end(),
                   [&](uint32_t a, uint32_t b) { return polygons_[a].face > polygons_[b].face; });
  BspTree::Node& n = node(job.node);
  n.n = plane.n;
  n.d = plane.d;
  n.firstFragment = uint32_t(placed_.size());
  n.fragmentCount = uint32_t(on.size());
  placed_.insert(placed_.end(), on.begin(), on.end());
  depth_ = std::max(depth_, job.depth);
  job.polygons.clear();
  job.polygons.shrink_to_fit();
  for (std::vector<uint32_t>* side : {&front, &back}) {
    if (side->empty()) continue;
    const int32_t child = int32_t(nodes_.size());
    nodes_.emplace_back();
    (side == &front ? node(job.node).front : node(job.node).back) = child;
    stack.push_back({child, job.depth + 1, std::move(*side)});
  }
}

// Fragments of one face meet along its cuts (algo::closeTJunctions).
void Builder::closeTJunctions() {
  std::vector<algo::PolygonRef> refs;
  refs.reserve(placed_.size());
  for (uint32_t id : placed_) refs.push_back({polygons_[id].first, polygons_[id].count, polygons_[id].face});
  algo::closeTJunctions(pool_, refs, epsilon_);
  for (size_t i = 0; i < placed_.size(); ++i) {
    polygons_[placed_[i]].first = refs[i].first;
    polygons_[placed_[i]].count = refs[i].count;
  }
}

// The tree's arrays: nodes as built, fragments in node order with their vertices packed.
void Builder::finish(std::vector<BspTree::Node>& nodes, std::vector<BspTree::Fragment>& fragments,
                     std::vector<dvec3>& vertices) {
  nodes = std::move(nodes_);
  fragments.reserve(placed_.size());
  size_t count = 0;
  for (uint32_t id : placed_) count += polygons_[id].count;
  vertices.reserve(count);
  for (uint32_t id : placed_) {
    const WorkPolygon& p = polygons_[id];
    fragments.push_back({uint32_t(vertices.size()), p.count, p.face, p.triangle});
    const auto v = verticesOf(p);
    vertices.insert(vertices.end(), v.begin(), v.end());
  }
}

}  // namespace

BspTree BspTree::build(const Scene& scene, const BspBuildOptions& options) {
  Builder b(scene, options);
  b.addInputPolygons();
  BspTree tree;
  tree.epsilon_ = b.epsilon_;
  tree.inputPolygons_ = b.inputs_;
  if (b.polygons_.empty()) return tree;
  std::vector<Job> stack;
  b.nodes_.emplace_back();
  stack.push_back({0, 1, {}});
  stack.back().polygons.resize(b.polygons_.size());
  for (uint32_t i = 0; i < b.polygons_.size(); ++i) stack.back().polygons[i] = i;
  while (!stack.empty()) {
    Job job = std::move(stack.back());
    stack.pop_back();
    b.partition(job, stack);
  }
  b.closeTJunctions();
  tree.splits_ = b.splits_;
  tree.depth_ = b.depth_;
  b.finish(tree.nodes_, tree.fragments_, tree.vertices_);
  return tree;
}

void BspTree::backToFront(const dvec4& eye, std::vector<uint32_t>& order) const {
  order.clear();
  if (nodes_.empty()) return;
  // Entries: 2 node (visit its subtree) or 2 node + 1 (emit its own fragments).
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t entry = stack.back();
    stack.pop_back();
    const Node& n = nodes_[entry >> 1];
    if (entry & 1) {
      for (uint32_t i = 0; i < n.fragmentCount; ++i) order.push_back(n.firstFragment + i);
      continue;
    }
    // The eye's side: the far side is painted first, then the plane, then the near side.
    const bool eyeInFront = glm::dot(n.n, dvec3(eye)) - n.d * eye.w >= 0;
    const int32_t nearSide = eyeInFront ? n.front : n.back, farSide = eyeInFront ? n.back : n.front;
    if (nearSide >= 0) stack.push_back(uint32_t(nearSide) << 1);
    stack.push_back(entry | 1);
    if (farSide >= 0) stack.push_back(uint32_t(farSide) << 1);
  }
}

namespace algo {
namespace {

// A tree with its fragments as a scene the drawing service draws (DerivedScene).
struct BuiltBsp {
  uint64_t key = 0;
  BspTree tree;
  Scene scene;
  DerivedScene derived;
  std::vector<uint32_t> fragmentOf;  // per face of `scene`: the fragment it is part of
};

constexpr size_t kFragmentsPerMesh = 1024;

uint64_t mixBytes(uint64_t h, const void* data, size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;  // FNV-1a
  return h;
}

// The scene's content (positions, faces, colours) and the build options: what the tree depends on.
uint64_t contentKey(const Scene& scene, const BspBuildOptions& options) {
  uint64_t h = 0xcbf29ce484222325ull;
  const uint64_t sizes[5] = {scene.positions.size(), scene.polygonIndices.size(), scene.faceColors.size(),
                             uint64_t(options.heuristic), options.maxFragments};
  h = mixBytes(h, sizes, sizeof sizes);
  h = mixBytes(h, scene.positions.data(), scene.positions.size() * sizeof(dvec3));
  h = mixBytes(h, scene.polygonIndices.data(), scene.polygonIndices.size() * sizeof(uint32_t));
  h = mixBytes(h, scene.polygonOffsets.data(), scene.polygonOffsets.size() * sizeof(uint32_t));
  return mixBytes(h, scene.faceColors.data(), scene.faceColors.size() * sizeof(Rgba8));
}

std::shared_ptr<const BuiltBsp> buildBsp(const Scene& scene, const BspBuildOptions& options, uint64_t key) {
  auto built = std::make_shared<BuiltBsp>();
  built->key = key;
  built->tree = BspTree::build(scene, options);
  const BspTree& tree = built->tree;
  Scene& s = built->scene;
  s.source = scene.source + " (bsp fragments)";
  s.positions.assign(tree.vertices().begin(), tree.vertices().end());
  // Each fragment as a fan of triangles around its centre (an added vertex), one face each: a
  // convex fragment's vertices on one line (where a neighbour's cut ends, a T-junction) are then
  // corners of non-degenerate triangles, so the snapped fragments meet without a crack.
  // (Triangulated as one polygon, such a vertex would be dropped as a zero-area ear.)
  for (uint32_t i = 0; i < tree.fragments().size(); ++i) {
    const BspTree::Fragment& f = tree.fragments()[i];
    // Fragments are in node order, a subtree's together (a convex cell of space): meshes of
    // consecutive fragments are compact, so the front end culls those outside the view whole.
    if (i % kFragmentsPerMesh == 0) s.beginMesh("bsp");
    auto addFace = [&](std::initializer_list<uint32_t> corners) {
      s.addFace(corners, scene.faceColors[f.face]);
      built->fragmentOf.push_back(i);
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
  built->derived.scene = &s;
  for (uint32_t fragment : built->fragmentOf) built->derived.face.push_back(tree.fragments()[fragment].face);
  for (const Triangle& t : s.triangles)
    built->derived.triangle.push_back(tree.fragments()[built->fragmentOf[t.face]].triangle);
  return built;
}

// The last few trees built, by content key: one scene rendered from many cameras builds once.
std::shared_ptr<const BuiltBsp> cachedBsp(const Scene& scene, const BspBuildOptions& options, bool& built) {
  static std::mutex mutex;
  static std::vector<std::shared_ptr<const BuiltBsp>> cache;  // most recent last
  constexpr size_t kCached = 4;
  const uint64_t key = contentKey(scene, options);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    for (size_t i = 0; i < cache.size(); ++i)
      if (cache[i]->key == key) {
        std::rotate(cache.begin() + ptrdiff_t(i), cache.begin() + ptrdiff_t(i) + 1, cache.end());
        built = false;
        return cache.back();
      }
  }
  auto tree = buildBsp(scene, options, key);
  const std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() == kCached) cache.erase(cache.begin());
  cache.push_back(tree);
  built = true;
  return tree;
}

// The eye as BspTree::backToFront takes it: the camera centre, or for an orthographic camera
// the direction back along the view (a point at infinity).
dvec4 homogeneousEye(const Camera& camera) {
  if (!camera.orthographic) return dvec4(camera.eyeWorld(), 1.0);
  const dvec3 forward = dvec3(glm::inverse(camera.cameraFromWorld) * dvec4(0, 0, 1, 0));
  return dvec4(-forward, 0.0);
}

void bsp(const Scene& scene, const Camera& camera, const RenderOptions& options, const AlgorithmParams& params,
         Frame& frame) {
  BspBuildOptions build;
  build.heuristic = params.text("heuristic") == "first" ? BspHeuristic::First : BspHeuristic::Scored;
  build.maxFragments = uint64_t(params.integer("max-fragments"));
  drawInBspOrder(scene, camera, options, build, hasTransparency(scene) ? WriteRule::Blend : WriteRule::Overwrite,
                 drawRasterOf(params), false, frame);
  frame.stats.setDetail("heuristic", params.text("heuristic"));
}

}  // namespace

void drawInBspOrder(const Scene& scene, const Camera& camera, const RenderOptions& options,
                    const BspBuildOptions& build, WriteRule rule, DrawRaster raster, bool frontToBack, Frame& frame) {
  Timer timer;
  bool built = false;
  const std::shared_ptr<const BuiltBsp> bsp = cachedBsp(scene, build, built);
  const double buildMs = timer.lap();
  const BspTree& tree = bsp->tree;

  std::vector<uint32_t> order;
  tree.backToFront(homogeneousEye(camera), order);
  std::vector<uint32_t> rank(order.size());
  for (uint32_t i = 0; i < order.size(); ++i) rank[order[i]] = frontToBack ? uint32_t(order.size()) - 1 - i : i;
  const double traverseMs = timer.lap();

  // Set-up triangles in their fragment's rank, stably: a counting sort, linear in the triangles.
  const std::vector<uint32_t>& fragmentOf = bsp->fragmentOf;
  const OrderFn byRank = [&](std::vector<SetupTriangle>& tris) {
    std::vector<uint32_t> start(rank.size() + 1, 0);
    for (const SetupTriangle& t : tris) ++start[rank[fragmentOf[t.face]] + 1];
    for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
    std::vector<SetupTriangle> sorted(tris.size());
    for (const SetupTriangle& t : tris) sorted[start[rank[fragmentOf[t.face]]]++] = t;
    tris.swap(sorted);
  };
  drawScene(scene, camera, options, rule, raster, byRank, frame, &bsp->derived);

  Stats& st = frame.stats;
  if (built) st.addTime("build", buildMs);
  st.addTime("traverse", traverseMs);
  st.setDetail("nodes", uint64_t(tree.nodes().size()));
  st.setDetail("fragments", uint64_t(tree.fragments().size()));
  st.setDetail("splits", tree.splits());
  st.setDetail("depth", uint64_t(tree.depth()));
  st.setDetail("built", uint64_t(built ? 1 : 0));
  if (built) st.setDetail("build_ms", buildMs);
  st.addMemory("bsp_tree", tree.nodes().size() * sizeof(BspTree::Node) +
                               tree.fragments().size() * sizeof(BspTree::Fragment) +
                               tree.vertices().size() * sizeof(dvec3));
  st.addMemory("bsp_order", rank.size() * 2 * sizeof(uint32_t));
}

void bspPolygons(const Scene& scene, const Camera& camera, const AlgorithmParams& params, PaintedPolygons& out) {
  BspBuildOptions build;
  build.heuristic = params.text("heuristic") == "first" ? BspHeuristic::First : BspHeuristic::Scored;
  build.maxFragments = uint64_t(params.integer("max-fragments"));
  bool built = false;
  const std::shared_ptr<const BuiltBsp> bsp = cachedBsp(scene, build, built);
  const BspTree& tree = bsp->tree;
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

AlgorithmInfo bspAlgorithm() {
  AlgorithmInfo a;
  a.name = "bsp";
  a.summary = "BSP tree: polygons split by their own planes once per scene, painted back to front from the eye";
  a.source = "KTH report, KTH thesis";
  a.params = {
      {"heuristic", ParamType::Choice, "scored", {"scored", "first"}, -1e300, 1e300,
       "the splitting plane of a node, through one of its polygons: first: the first polygon of its list (face "
       "order); scored: of 8 candidates at positions i*m/8 of its m polygons, the one that splits the fewest of "
       "the polygons at positions j*m/s (s = min(m, 1024)), ties broken by the least |front - back| of those, "
       "then by the earliest position"},
      {"max-fragments", ParamType::Int, "4000000", {}, 1, 1e9,
       "the most fragments the tree may hold: a build that would make more stops with an error"},
      drawRasterParam("binned"),
  };
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.run = bsp;
  return a;
}

}  // namespace algo
}  // namespace hsr

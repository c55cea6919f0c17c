// The BSP tree [KTH report, KTH thesis] (include/hsr/bsp.hpp): built by auto-partition in world
// space, traversed back to front from an eye. Used by the `bsp` and `reverse-painter` algorithms
// (bsp.cpp) and by embedders. Build and traversal use explicit stacks: a convex mesh makes a
// chain as deep as its face count. Runs on the caller's thread.
#include <hsr/bsp.hpp>
#include <hsr/limits.hpp>
#include <hsr/scene.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <tuple>

#include "algorithms/polygon_split.hpp"

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
  double area = 0;
};

double areaOf(std::span<const dvec3> v) {
  dvec3 sum{0.0};
  for (size_t i = 1; i + 1 < v.size(); ++i) sum += glm::cross(v[i] - v[0], v[i + 1] - v[0]);
  return 0.5 * glm::length(sum);
}

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
  p.area = areaOf(vertices);
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

// 64 a / A in whole units, bounded (A may be 0: a sliver the sampling met).
uint64_t splitWeight(double a, double A) {
  if (!(a > 0)) return 0;
  return A > 0 ? uint64_t(std::min(64.0 * a / A, 1e12)) : uint64_t(1e12);
}

// The position in `list` of the splitting polygon (BspHeuristic). Scored: candidates at positions
// i m / c (c = min(m, kBspCandidates)), each scored by the polygons it splits among those at
// positions j m / s (s = min(m, kBspScoreSample)). Area: half the candidates so spaced and half
// the largest polygons, each split weighted 1 + 4 a / A (a the split polygon's area, A the candidate's): a
// large polygon left for later is cut by many planes, and a split of a small one by a large
// one's plane costs little. Then the least |front - back|, then the earliest position.
uint32_t Builder::chooseSplitter(const std::vector<uint32_t>& list) const {
  const size_t m = list.size();
  if (options_.heuristic == BspHeuristic::First || m <= 2) return 0;
  const bool byArea = options_.heuristic == BspHeuristic::Area;
  const size_t c = std::min<size_t>(m, kBspCandidates), s = std::min<size_t>(m, kBspScoreSample);
  // Area: half the candidates evenly spaced, half the largest, so a node costs what Scored's does.
  const size_t spaced = byArea ? (c + 1) / 2 : c;
  std::vector<size_t> candidates;
  for (size_t i = 0; i < spaced; ++i) candidates.push_back(i * m / spaced);
  if (byArea) {
    std::vector<size_t> largest;  // positions, largest first (a linear scan keeping the top few)
    for (size_t i = 0; i < m; ++i) {
      const double area = polygons_[list[i]].area;
      if (largest.size() == c - spaced && !(area > polygons_[list[largest.back()]].area)) continue;
      auto at = largest.begin();
      while (at != largest.end() && polygons_[list[*at]].area >= area) ++at;
      largest.insert(at, i);
      if (largest.size() > c - spaced) largest.pop_back();
    }
    for (size_t i : largest)
      if (std::find(candidates.begin(), candidates.end(), i) == candidates.end()) candidates.push_back(i);
  }
  // A split's cost in 16ths, so that the weights compare as integers.
  uint32_t best = 0;
  uint64_t bestCost = UINT64_MAX, bestImbalance = UINT64_MAX;
  for (const size_t at : candidates) {
    const WorkPolygon& candidate = polygons_[list[at]];
    const SplitPlane& plane = planes_[candidate.plane];
    uint64_t cost = 0, front = 0, back = 0;
    for (size_t j = 0; j < s && cost <= bestCost; ++j) {
      const size_t k = j * m / s;
      if (k == at) continue;
      const WorkPolygon& other = polygons_[list[k]];
      switch (classifyPolygon(verticesOf(other), plane, epsilon_)) {
        case PolygonSide::Front: ++front; break;
        case PolygonSide::Back: ++back; break;
        case PolygonSide::Spanning:
          cost += byArea ? 16 + splitWeight(other.area, candidate.area) : 16;
          break;
        case PolygonSide::Coplanar: break;
      }
    }
    const uint64_t imbalance = front > back ? front - back : back - front;
    if (std::tie(cost, imbalance, at) < std::tie(bestCost, bestImbalance, best)) {
      best = uint32_t(at);
      bestCost = cost;
      bestImbalance = imbalance;
    }
  }
  return best;
}

uint32_t Builder::addPiece(const std::vector<dvec3>& vertices, const WorkPolygon& from) {
  WorkPolygon p = from;
  p.first = uint32_t(pool_.size());
  p.count = uint32_t(vertices.size());
  p.area = areaOf(vertices);
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
                           " polygons); raise the parameter max-fragments or try the other heuristic");
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

}  // namespace hsr

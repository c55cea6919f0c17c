// CSG by the z-buffer [KTH report]: the union, intersection and difference of closed meshes
// (Scene::csg) shown by depth peeling. The surfaces of all the solids are peeled front to back,
// one depth layer per pass of the drawing service (WriteRule::DepthPeel); at each layer a pixel's
// fragment enters (front face) or leaves (back face) its solid, and the first layer at which the
// tree's expression becomes true at the pixel is its visible surface. Also the exact reference of
// a CSG scene (CsgRays, used by raycast and --verify): per pixel ray, every hit of the scene's
// triangles with the reference's watertight test, sorted, the tree evaluated between them.
#include <algorithm>
#include <cmath>
#include <limits>

#include "algorithms/algorithms.hpp"
#include "algorithms/bvh.hpp"
#include "algorithms/draw.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "scene/shading.hpp"

namespace hsr::algo {

// ---- The tree -------------------------------------------------------------------------------

CsgTree::CsgTree(const Scene& scene) : nodes_(scene.csg), solidOfTriangle_(scene.triangles.size(), -1) {
  const std::string where = scene.source + ": csg: ";
  if (nodes_.size() >= 2 * kMaxCsgSolids)  // a tree of at most kMaxCsgSolids leaves has fewer nodes
    throw InputError(where + std::to_string(nodes_.size()) + " nodes (a tree of " + std::to_string(kMaxCsgSolids) +
                     " solids has fewer)");
  std::vector<int> solidOfFace(scene.faceCount(), -1);
  solidOfNode_.assign(nodes_.size(), 0);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const CsgNode& n = nodes_[i];
    if (n.op != CsgNode::Op::Solid) {
      if (n.left >= i || n.right >= i) throw InputError(where + "node " + std::to_string(i) + " names a later node");
      continue;
    }
    if (solids_ == kMaxCsgSolids) throw InputError(where + "more than " + std::to_string(kMaxCsgSolids) + " solids");
    if (n.count == 0 || uint64_t(n.first) + n.count > scene.faceCount())
      throw InputError(where + "solid " + std::to_string(solids_) + " has no faces or faces outside the scene");
    for (uint32_t f = n.first; f < n.first + n.count; ++f) {
      if (solidOfFace[f] >= 0) throw InputError(where + "face " + std::to_string(f) + " belongs to two solids");
      solidOfFace[f] = int(solids_);
    }
    solidOfNode_[i] = uint8_t(solids_++);
  }
  for (size_t t = 0; t < scene.triangles.size(); ++t) solidOfTriangle_[t] = int8_t(solidOfFace[scene.triangles[t].face]);
}

bool CsgTree::contains(uint64_t inside) const {
  bool value[2 * kMaxCsgSolids];  // (the constructor checked the count)
  const size_t count = nodes_.size();
  for (size_t i = 0; i < count; ++i) {
    const CsgNode& n = nodes_[i];
    switch (n.op) {
      case CsgNode::Op::Solid: value[i] = (inside >> solidOfNode_[i]) & 1; break;
      case CsgNode::Op::Union: value[i] = value[n.left] || value[n.right]; break;
      case CsgNode::Op::Intersection: value[i] = value[n.left] && value[n.right]; break;
      case CsgNode::Op::Difference: value[i] = value[n.left] && !value[n.right]; break;
    }
  }
  return count && value[count - 1];
}

bool csgSolidsWithinDepthRange(const Scene& scene, const Camera& camera) {
  for (const CsgNode& n : scene.csg) {
    if (n.op != CsgNode::Op::Solid) continue;
    for (uint32_t f = n.first; f < n.first + n.count && f < scene.faceCount(); ++f)
      for (uint32_t v : scene.face(f)) {
        const double z = camera.toCamera(scene.positions[v]).z;
        if (!(z > camera.near && z < camera.far)) return false;
      }
  }
  return true;
}

void checkCsgOptions(const Scene& scene, const RenderOptions& options) {
  if (!scene.csg.empty() && options.cull != Cull::None)
    throw InputError(scene.source + ": a CSG tree needs both sides of its solids: render it with culling off");
}

// ---- The reference: the tree along each pixel's ray -------------------------------------------

namespace {
// The camera the reference's hierarchy is built with: the same view, with no far plane, so that
// the hits beyond it tell whether the ray starts inside a solid.
Camera withoutFarPlane(const Camera& camera) {
  Camera c = camera;
  c.far = std::numeric_limits<double>::max();
  return c;
}
}  // namespace

CsgRays::CsgRays(const Scene& scene, const Camera& camera)
    : scene_(scene), camera_(camera), unbounded_(withoutFarPlane(camera)), bvh_(scene, unbounded_), tree_(scene) {}

RayHit CsgRays::tracePixel(double px, double py, Scratch& scratch, TraceCounters& counters) const {
  std::vector<RayHit>& hits = scratch.hits;
  hits.clear();
  bvh_.allPixelHits(px, py, Cull::None, hits, counters);
  std::sort(hits.begin(), hits.end(),
            [](const RayHit& a, const RayHit& b) { return a.t != b.t ? a.t < b.t : a.triangle < b.triangle; });
  // Each hit's solid (-1: a plain surface) and facing, by the same watertight test culling back
  // faces (a front face is still hit): +1 enters the solid, -1 leaves it.
  dvec3 origin, dir;
  unbounded_.cameraRay(px, py, origin, dir);
  const WatertightRay ray(origin, dir);
  std::vector<int>& solid = scratch.solid;
  std::vector<int>& facing = scratch.facing;
  solid.resize(hits.size());
  facing.resize(hits.size());
  for (size_t k = 0; k < hits.size(); ++k) {
    const Triangle& tri = scene_.triangles[size_t(hits[k].triangle)];
    solid[k] = tree_.solidOf(uint32_t(hits[k].triangle));
    facing[k] = std::isnan(ray.intersect(unbounded_.toCamera(scene_.positions[tri.v[0]]),
                                         unbounded_.toCamera(scene_.positions[tri.v[1]]),
                                         unbounded_.toCamera(scene_.positions[tri.v[2]]), Cull::Back))
                    ? -1
                    : 1;
  }
  // Hits at one distance are one event: a solid is entered (left) there when more of its hits
  // enter (leave) than leave (enter), so a ray through an edge two faces share counts once.
  auto groupEnd = [&](size_t begin) {
    size_t end = begin;
    while (end < hits.size() && hits[end].t == hits[begin].t) ++end;
    return end;
  };
  // The change of solid[k]'s count over group [begin, end), on the group's first hit of it (else 0).
  auto change = [&](size_t begin, size_t end, size_t k) {
    if (solid[k] < 0) return 0;
    for (size_t j = begin; j < k; ++j)
      if (solid[j] == solid[k]) return 0;
    int sum = 0;
    for (size_t j = k; j < end; ++j)
      if (solid[j] == solid[k]) sum += facing[j];
    return (sum > 0) - (sum < 0);
  };
  // Inside counts at the ray's start: a solid holds it when more of its crossings beyond leave
  // it than enter it.
  int count[kMaxCsgSolids] = {};
  for (size_t begin = 0, end; begin < hits.size(); begin = end) {
    end = groupEnd(begin);
    for (size_t k = begin; k < end; ++k)
      if (solid[k] >= 0) count[solid[k]] -= change(begin, end, k);
  }
  auto inside = [&] {
    uint64_t m = 0;
    for (size_t s = 0; s < tree_.solids(); ++s) m |= uint64_t(count[s] > 0) << s;
    return m;
  };
  // The visible surface: the first plain surface, or the first event where the tree's value
  // changes, within the far plane.
  bool value = tree_.contains(inside());
  for (size_t begin = 0, end; begin < hits.size() && hits[begin].t <= camera_.far; begin = end) {
    end = groupEnd(begin);
    bool plain = false;
    for (size_t k = begin; k < end; ++k) {
      plain |= solid[k] < 0;
      if (solid[k] >= 0) count[solid[k]] += change(begin, end, k);
    }
    const bool now = tree_.contains(inside());
    for (size_t k = begin; k < end && (plain || now != value); ++k)
      if (solid[k] < 0 || (now != value && change(begin, end, k) != 0)) return hits[k];
    value = now;
  }
  return {};
}

// ---- Depth peeling --------------------------------------------------------------------------

namespace {

// The algorithm object: the scene's tree, and the buffers it peels with, kept from one view to
// the next.
class CsgPeel final : public SceneAlgorithm {
 public:
  CsgPeel(const Scene& scene, const AlgorithmParams& params) : SceneAlgorithm(scene, params), tree_(scene) {}

  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    checkCsgOptions(scene_, options);
    const int maxLayers = int(params_.integer("max-layers"));
    const DrawRaster raster = drawRasterOf(params_);
    const int threads = resolveThreads(options.threads);
    const size_t pixels = size_t(camera.width) * size_t(camera.height);
    frame.clear(options.background, threads);

    // Each layer keeps the ids and exact depth of its fragments (no colour: only the visible
    // fragment is shaded).
    RenderOptions layerOptions = options;
    layerOptions.outputs = FrameOutputs::IdsAndDepth;
    layer_.allocate(camera.width, camera.height, FrameOutputs::IdsAndDepth);
    if (frame.writes.empty()) layer_.writes.clear();
    else layer_.writes.assign(pixels, 0);
    const size_t solids = tree_.solids();
    inside_.assign(pixels, 0);
    crossings_.assign(pixels * solids, 0);
    open_.assign(pixels, 1);
    frontFacing_.assign(scene_.triangles.size(), 0);
    buffers_.forgetPeeledLayer();
    const OrderFn noteFacing = [&](std::vector<SetupTriangle>& tris) {  // submission order kept
      for (const SetupTriangle& t : tris) frontFacing_[t.triangle] = t.frontFacing;
    };

    const Stats begun = frame.stats;
    Stats total;
    const TriangleShader shade(scene_, camera, options.shading);
    struct RowCounts {
      uint64_t visible = 0, open = 0;
    };
    std::vector<RowCounts> rows(size_t(camera.height));
    int layers = 0;
    uint64_t open = pixels;
    Timer timer;
    double decideMs = 0;
    while (open > 0 && layers < maxLayers) {
      ++layers;
      layer_.stats = begun;
      drawScene(scene_, camera, layerOptions, WriteRule::DepthPeel, raster, noteFacing, buffers_, layer_);
      if (layers == 1) total = layer_.stats;
      else total.addCounts(layer_.stats);
      buffers_.keepPeeledLayer();
      timer.lap();
      // Per open pixel, its fragment of this layer enters or leaves its solid (or is a plain
      // surface); the first at which the tree holds is the visible one. A pixel with no
      // fragment has no surface left: background.
      parallelFor(0, size_t(camera.height), threads, [&](size_t y) {
        RowCounts& row = rows[y];
        row.open = 0;
        for (int x = 0; x < camera.width; ++x) {
          const size_t i = frame.index(x, int(y));
          if (!layer_.writes.empty()) frame.writes[i] += layer_.writes[i];
          if (!open_[i]) continue;
          const int32_t tri = layer_.triangleId[i];
          if (tri < 0) {
            open_[i] = 0;
            continue;
          }
          const int solid = tree_.solidOf(uint32_t(tri));
          bool shows = solid < 0;
          if (!shows) {
            int8_t& count = crossings_[i * solids + size_t(solid)];
            count = int8_t(std::clamp(count + (frontFacing_[size_t(tri)] ? 1 : -1), -100, 100));
            const uint64_t bit = uint64_t(1) << solid;
            inside_[i] = count > 0 ? inside_[i] | bit : inside_[i] & ~bit;
            shows = tree_.contains(inside_[i]);
          }
          if (!shows) {
            ++row.open;
            continue;
          }
          open_[i] = 0;
          ++row.visible;
          if (!frame.faceId.empty()) frame.faceId[i] = layer_.faceId[i];
          if (!frame.triangleId.empty()) frame.triangleId[i] = tri;
          frame.depth[i] = layer_.depth[i];
          if (!frame.color.empty()) frame.color[i] = shade(uint32_t(tri));
        }
      });
      open = 0;
      for (const RowCounts& row : rows) open += row.open;
      decideMs += timer.lap();
    }

    uint64_t visible = 0;
    for (const RowCounts& row : rows) visible += row.visible;
    total.covered_pixels = visible;
    total.color_writes = frame.color.empty() ? 0 : visible;
    total.addTime("decide", decideMs);
    Stats frameMemory;
    addFrameMemory(frameMemory, frame);
    total.addMemory("csg_frame", frameMemory.memory_bytes);  // (the layers' frame is in frame.*)
    total.addMemory("peeled_layer", buffers_.peeledWinner().capacity() * (sizeof(uint32_t) + sizeof(float)));
    total.addMemory("csg_inside", inside_.capacity() * sizeof(uint64_t) + crossings_.capacity() + open_.capacity());
    total.addMemory("csg_facing", frontFacing_.capacity());
    total.setDetail("solids", uint64_t(tree_.solids()));
    total.setDetail("layers", uint64_t(layers));
    total.setDetail("undecided_pixels", open);
    frame.stats = std::move(total);
  }

 private:
  CsgTree tree_;
  Frame layer_;                        // the layer just peeled: ids and exact depth
  std::vector<uint64_t> inside_;       // per pixel: bit s set while the ray is inside solid s
  std::vector<int8_t> crossings_;      // per pixel and solid: entries less exits so far
  std::vector<uint8_t> open_;          // per pixel: 1 until its visible surface (or none) is found
  std::vector<uint8_t> frontFacing_;   // per scene triangle: front-facing from this camera
};

}  // namespace

AlgorithmInfo csgAlgorithm() {
  AlgorithmInfo a;
  a.name = "csg";
  a.summary = "CSG by depth peeling: the solids' surfaces peeled front to back with the z-buffer, each pixel's "
              "tree evaluated layer by layer";
  a.source = "KTH report";
  a.params = {{"max-layers", ParamType::Int, "64", {}, 1, 4096,
               "depth layers peeled at most; a pixel still undecided then shows the background "
               "(details: undecided_pixels)"},
              drawRasterParam("binned")};
  a.guarantee.kind = Guarantee::Kind::ExactWhen;
  a.guarantee.condition =
      "the tree's solids are closed, consistently oriented meshes between the near and far planes (each ray "
      "starts outside them) and no pixel needs more than max-layers layers";
  a.guarantee.holds = [](const Scene& scene, const Camera& camera, const RenderOptions&) {
    return csgSolidsWithinDepthRange(scene, camera);
  };
  a.capability = Capability::Csg;
  a.create = factoryOf<CsgPeel>();
  return a;
}

}  // namespace hsr::algo

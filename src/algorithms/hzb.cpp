// The hierarchical z-buffer of Greene, Kass and Miller (1993), written to be read: a z-buffer
// with a z-pyramid over it, so that a triangle hidden behind what is already drawn is rejected
// with a few comparisons instead of one per pixel.
//
//   the z-pyramid: level 0 has one entry per 8x8 tile of the image; each level above has one
//   entry per 2x2 entries of the level below (the last row or column of an odd-sized level
//   folds one entry, not two), up to a single entry; every entry holds the FARTHEST stored
//   depth of the pixels below it.
//
//   for each triangle (nearest faces first, by default):
//     find the smallest entry whose region contains the triangle's screen box
//     visit(entry):
//       if the triangle's nearest depth within the entry is not nearer than the entry: rejected
//       (every pixel below holds something at least as near, and the test keeps ties)
//       else, on level 0: draw the triangle's pixels in the tile with the per-pixel depth test;
//             above: visit each child entry that the screen box meets (descended)
//     after a tile's pixels changed, its entry and those above it are made exact again
//
// Updates are exact: when a write replaced a pixel that held the tile's farthest value, the
// tile's entry is recomputed from its 64 pixels and each entry above from its children, up to
// the first that does not change. An entry is never nearer than a pixel below it, so a rejection
// is never wrong: the image is the z-buffer's, bit for bit, except where two fragments tie in
// depth (the order decides which stays: ambiguous, as for every reordering z-buffer).
//
// The triangle's nearest depth within an entry is the farther of two conservative bounds: its
// nearest over the whole triangle (Greene's polygon z), and its depth plane's nearest over the
// part of its screen box inside the entry (a large triangle, a floor or a wall, is far nearer at
// one end than where it passes behind an occluder).
#include <array>
#include <cstdio>
#include <string>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/sort_keys.hpp"
#include "algorithms/zbuffer_pixels.hpp"
#include "scene/shading.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "frontend/mesh_bounds.hpp"
#include "raster/halfspace.hpp"

namespace hsr::algo {
namespace {

constexpr int kTileShift = 3;  // level 0's entries are 8x8 pixel tiles
constexpr int kMaxLevels = 16;  // 16384 pixels / 8 = 2^11: 12 levels at most

// The pyramid of farthest depths (see the top of the file), for stored values of type T and the
// depth test's order.
template <DepthStorage S, DepthMapping M>
class ZPyramid {
 public:
  using Pixels = ZBufferPixels<S, M>;
  using T = typename Pixels::T;

  ZPyramid(int width, int height, T clear) {
    int w = (width + (1 << kTileShift) - 1) >> kTileShift, h = (height + (1 << kTileShift) - 1) >> kTileShift;
    for (;;) {
      levels_.push_back({w, h, std::vector<T>(size_t(w) * size_t(h), clear)});
      if (w == 1 && h == 1) break;
      w = (w + 1) / 2;
      h = (h + 1) / 2;
    }
  }

  int levels() const { return int(levels_.size()); }
  int width(int k) const { return levels_[size_t(k)].width; }
  int height(int k) const { return levels_[size_t(k)].height; }
  /// The side in pixels of level k's entries' regions: 8, 16, 32, ...
  static int shift(int k) { return kTileShift + k; }
  T at(int k, int x, int y) const { return levels_[size_t(k)].farthest[size_t(y) * size_t(width(k)) + size_t(x)]; }

  /// Tile (tx, ty)'s entry set to `farthest` (its pixels' farthest value), and every entry above
  /// it recomputed from its children, up to the first that does not change.
  void update(int tx, int ty, T farthest) {
    set(0, tx, ty, farthest);
    for (int k = 1; k < levels(); ++k) {
      tx /= 2;
      ty /= 2;
      T f = at(k - 1, 2 * tx, 2 * ty);
      const int cx1 = std::min(2 * tx + 1, width(k - 1) - 1), cy1 = std::min(2 * ty + 1, height(k - 1) - 1);
      for (int cy = 2 * ty; cy <= cy1; ++cy)
        for (int cx = 2 * tx; cx <= cx1; ++cx) f = Pixels::farthest(f, at(k - 1, cx, cy));
      if (f == at(k, tx, ty)) return;
      set(k, tx, ty, f);
    }
  }

  uint64_t bytes() const {
    uint64_t b = 0;
    for (const Level& l : levels_) b += l.farthest.size() * sizeof(T);
    return b;
  }

 private:
  struct Level {
    int width, height;
    std::vector<T> farthest;
  };
  void set(int k, int x, int y, T v) { levels_[size_t(k)].farthest[size_t(y) * size_t(width(k)) + size_t(x)] = v; }
  std::vector<Level> levels_;
};

/// What happened at the entries of one level of the pyramid.
struct LevelCounts {
  uint64_t tested = 0;     // entries a triangle was tested against
  uint64_t rejected = 0;   // ... where it was hidden
  uint64_t descended = 0;  // ... where it was not: its children visited (level 0: its pixels drawn)
};

// An inclusive pixel rectangle.
struct Rect {
  int x0, y0, x1, y1;
};

// The z-buffer, its pyramid and the triangles drawn through them, for one depth format.
template <DepthStorage S, DepthMapping M>
class HierarchicalZBuffer {
 public:
  using Pixels = ZBufferPixels<S, M>;
  using T = typename Pixels::T;

  // `tris` may grow between calls of drawFrom (objects set up batch by batch). With
  // `testTriangles` false the pyramid only serves the object test: every triangle is drawn over
  // all its tiles, the textbook z-buffer's loop.
  HierarchicalZBuffer(const std::vector<SetupTriangle>& tris, const Camera& camera, const RenderOptions& options,
                      Frame& frame, bool testTriangles)
      : tris_(tris), camera_(camera), pixels_(camera, options, frame),
        pyramid_(camera.width, camera.height, pixels_.clearValue()), depth_(pixels_.depthSetup()),
        testTriangles_(testTriangles) {}

  /// Triangles [first, end) of the list, in its order.
  void drawFrom(size_t first, DrawCounters& n) {
    for (size_t i = first; i < tris_.size(); ++i) draw(uint32_t(i), n);
  }

  /// The object test of occlusion culling: whether every pixel of the box [x0, x1] x [y0, y1]
  /// (in the image) already holds a value at least as near as `nearest` (a stored value none of
  /// the object's fragments is nearer than), so that none of them could win the depth test. From
  /// the smallest entry containing the box down, as for a triangle; exact at the tiles' pixels.
  bool boxHidden(int x0, int y0, int x1, int y1, double nearest) const {
    const Rect box{x0, y0, x1, y1};
    int k = 0;
    while (k + 1 < pyramid_.levels() && !inOneEntry(box, k)) ++k;
    return hiddenIn(k, x0 >> ZPyramid<S, M>::shift(k), y0 >> ZPyramid<S, M>::shift(k), box, nearest);
  }
  DepthSetup depthSetup() const { return depth_; }
  void resolve(const TriangleShader& shade, DrawCounters& n) { pixels_.resolve(tris_, shade, n); }
  /// Per mesh of `scene`, 1 when some pixel's winner is one of its triangles: the triangles that
  /// won a pixel, then each one's mesh (meshes hold ascending runs of triangles).
  void meshesShown(const Scene& scene, std::vector<uint8_t>& shown) const {
    std::vector<uint8_t> won(tris_.size(), 0);
    for (uint32_t w : pixels_.winners())
      if (w) won[w - 1] = 1;
    shown.assign(scene.meshes.size(), 0);
    const auto firstOf = [](uint32_t triangle, const MeshRange& m) { return triangle < m.firstTriangle; };
    for (size_t i = 0; i < won.size(); ++i)
      if (won[i]) {
        const auto after = std::upper_bound(scene.meshes.begin(), scene.meshes.end(), tris_[i].triangle, firstOf);
        shown[size_t(after - scene.meshes.begin()) - 1] = 1;
      }
  }
  const std::array<LevelCounts, kMaxLevels>& counts() const { return counts_; }
  int levels() const { return pyramid_.levels(); }
  uint64_t trianglesRejected() const { return hidden_; }
  void addMemory(Stats& st) const {
    pixels_.addMemory(st);
    st.addMemory("z_pyramid", pyramid_.bytes());
  }

 private:
  bool hiddenIn(int k, int x, int y, const Rect& box, double nearest) const {
    if (!storedNearer<M>(nearest, double(pyramid_.at(k, x, y)))) return true;
    const int s = ZPyramid<S, M>::shift(k);
    const Rect part{std::max(x << s, box.x0), std::max(y << s, box.y0), std::min(((x + 1) << s) - 1, box.x1),
                    std::min(((y + 1) << s) - 1, box.y1)};
    if (k == 0) {
      for (int py = part.y0; py <= part.y1; ++py)
        for (int px = part.x0; px <= part.x1; ++px)
          if (storedNearer<M>(nearest, double(pixels_.at(size_t(py) * size_t(camera_.width) + size_t(px))))) return false;
      return true;
    }
    const int cs = ZPyramid<S, M>::shift(k - 1);
    for (int cy = part.y0 >> cs; cy <= part.y1 >> cs; ++cy)
      for (int cx = part.x0 >> cs; cx <= part.x1 >> cs; ++cx)
        if (!hiddenIn(k - 1, cx, cy, box, nearest)) return false;
    return true;
  }

  // Triangle i, from the smallest entry that contains its screen box (without triangle tests:
  // over every tile its box meets).
  void draw(uint32_t i, DrawCounters& n) {
    const SetupTriangle& t = tris_[i];
    current_ = {i, pixels_.planes(t), nearestStored<S, M>(t, depth_), 0, 0, {t.minX, t.minY, t.maxX, t.maxY}};
    if (!testTriangles_) {
      const Rect& b = current_.box;
      for (int ty = b.y0 >> kTileShift; ty <= b.y1 >> kTileShift; ++ty)
        for (int tx = b.x0 >> kTileShift; tx <= b.x1 >> kTileShift; ++tx)
          drawTile(tx, ty,
                   {std::max(tx << kTileShift, b.x0), std::max(ty << kTileShift, b.y0),
                    std::min(((tx + 1) << kTileShift) - 1, b.x1), std::min(((ty + 1) << kTileShift) - 1, b.y1)},
                   n);
      return;
    }
    current_.pErr = planeError(current_.m.p, camera_.width, camera_.height);
    current_.qErr = planeError(current_.m.q, camera_.width, camera_.height);
    int k = 0;
    while (k + 1 < pyramid_.levels() && !inOneEntry(current_.box, k)) ++k;
    const uint64_t tilesBefore = counts_[0].descended;
    visit(k, current_.box.x0 >> ZPyramid<S, M>::shift(k), current_.box.y0 >> ZPyramid<S, M>::shift(k), n);
    hidden_ += counts_[0].descended == tilesBefore;  // no pixel of it tested
  }

  static bool inOneEntry(const Rect& r, int k) {
    const int s = ZPyramid<S, M>::shift(k);
    return (r.x0 >> s) == (r.x1 >> s) && (r.y0 >> s) == (r.y1 >> s);
  }

  // The current triangle against entry (x, y) of level k (its region meets the screen box).
  void visit(int k, int x, int y, DrawCounters& n) {
    const int s = ZPyramid<S, M>::shift(k);
    const Rect part{std::max(x << s, current_.box.x0), std::max(y << s, current_.box.y0),
                    std::min(((x + 1) << s) - 1, current_.box.x1), std::min(((y + 1) << s) - 1, current_.box.y1)};
    LevelCounts& c = counts_[size_t(k)];
    ++c.tested;
    if (!storedNearer<M>(nearestWithin(part), double(pyramid_.at(k, x, y)))) {
      ++c.rejected;
      return;
    }
    ++c.descended;
    if (k == 0) return drawTile(x, y, part, n);
    const int cx1 = std::min(2 * x + 1, pyramid_.width(k - 1) - 1), cy1 = std::min(2 * y + 1, pyramid_.height(k - 1) - 1);
    const int cs = ZPyramid<S, M>::shift(k - 1);
    for (int cy = 2 * y; cy <= cy1; ++cy)
      for (int cx = 2 * x; cx <= cx1; ++cx)
        if ((cx << cs) <= part.x1 && ((cx + 1) << cs) > part.x0 && (cy << cs) <= part.y1 && ((cy + 1) << cs) > part.y0)
          visit(k - 1, cx, cy, n);
  }

  // A stored value no fragment of the current triangle inside `part` is nearer than.
  double nearestWithin(const Rect& part) const {
    const StoredRange plane = storedRangeOverRect<S, M>(current_.m, current_.pErr, current_.qErr, part.x0 + 0.5,
                                                        part.x1 + 0.5, part.y0 + 0.5, part.y1 + 0.5);
    return storedNearer<M>(plane.nearest, current_.nearest) ? current_.nearest : plane.nearest;
  }

  // The current triangle's pixels in tile (tx, ty), clipped to `part`, through the depth test;
  // the tile's entry made exact again if a pixel that held its farthest value was replaced.
  void drawTile(int tx, int ty, const Rect& part, DrawCounters& n) {
    SetupTriangle clipped = tris_[current_.i];
    clipped.minX = int16_t(part.x0);
    clipped.minY = int16_t(part.y0);
    clipped.maxX = int16_t(part.x1);
    clipped.maxY = int16_t(part.y1);
    const T tileFarthest = pyramid_.at(0, tx, ty);
    bool stale = false;
    rasterizeHalfSpace(clipped, [&](int x, int y, double) {
      const size_t idx = size_t(y) * size_t(camera_.width) + size_t(x);
      const T before = pixels_.at(idx);
      if (pixels_.test(idx, Pixels::fragment(current_.m, x, y), current_.i, n)) stale |= before == tileFarthest;
    });
    if (stale) pyramid_.update(tx, ty, farthestOfTile(tx, ty));
  }

  T farthestOfTile(int tx, int ty) const {
    constexpr int side = 1 << kTileShift;
    const int x1 = std::min((tx + 1) * side, camera_.width), y1 = std::min((ty + 1) * side, camera_.height);
    T f = pixels_.at(size_t(ty * side) * size_t(camera_.width) + size_t(tx * side));
    for (int y = ty * side; y < y1; ++y)
      for (int x = tx * side; x < x1; ++x) f = Pixels::farthest(f, pixels_.at(size_t(y) * size_t(camera_.width) + size_t(x)));
    return f;
  }

  // The triangle being drawn: its index, depth planes, nearest stored value over the whole
  // triangle, the planes' evaluation errors, its screen box.
  struct Current {
    uint32_t i;
    MappedPlanes m;
    double nearest;
    double pErr, qErr;
    Rect box;
  };

  const std::vector<SetupTriangle>& tris_;
  const Camera& camera_;
  Pixels pixels_;
  ZPyramid<S, M> pyramid_;
  const DepthSetup depth_;
  const bool testTriangles_;
  Current current_{};
  std::array<LevelCounts, kMaxLevels> counts_{};
  uint64_t hidden_ = 0;  // triangles rejected in every tile they meet
};

// "level0_tested", "level0_rejected", "level0_descended", ...: the details' keys, interned
// (formatted on the stack: a warm frame allocates nothing for them).
StaticName levelKey(int k, int what) {
  char text[32];
  const int n = std::snprintf(text, sizeof text, "level%d_%s", k,
                              what == 0 ? "tested" : what == 1 ? "rejected" : "descended");
  return StaticName::interned(std::string_view(text, size_t(n)));
}

// Occlusion culling (occlusion-cull=on): the scene's meshes are the objects, drawn in kBatches
// batches by the least depth of their boxes, nearest first. Before a batch is set up, each of its
// meshes' bound (the occlusion buffer's: meshBound, frontend/mesh_bounds.cpp: a pixel box and a
// stored value none of its fragments is nearer than) is tested against the pyramid; a mesh hidden
// there is dropped whole, none of its triangles set up. Hidden now, hidden at the end: stored
// values only come nearer. Meshes without a bound are drawn in the first batch.
constexpr size_t kBatches = 32;

// What occlusion culling counted.
struct ObjectCounts {
  uint64_t objects = 0, objectsCulled = 0, trianglesCulled = 0, batches = 0;
  uint64_t objectsCarried = 0;  // with temporal coherence: drawn first, untested, as shown in the last frame
};



// The scene's triangles drawn object by object into `hz` (see kBatches), each batch's set-up
// triangles appended to `triangles` (nearest faces first when `frontToBack`); front-end counts
// summed into `counters`, the front end's memory into `frontEndBytes`.
// With `carried` (temporal coherence), the meshes it marks go in the first batch, untested.
template <class HZ>
ObjectCounts drawByObjects(const Scene& scene, const Camera& camera, const RenderOptions& options, bool frontToBack,
                           const std::vector<uint8_t>* carried, HZ& hz, std::vector<SetupTriangle>& triangles,
                           FrontEndCounters& counters, uint64_t& frontEndBytes, DrawCounters& n) {
  const size_t meshCount = scene.meshes.size();
  std::vector<MeshTest> tests(meshCount);
  std::vector<MeshBound> bounds(meshCount);
  const MeshView view = meshView(camera, hz.depthSetup());
  FrontEndOutput vertices, fe;
  runVertexPass(scene, camera, options, vertices, [&](size_t first, size_t last) {
    meshBounds(scene, first, last, view, tests.data() + first, bounds.data() + first);
    for (size_t m = first; m < last; ++m)
      if (vertices.meshCulled[m]) tests[m] = MeshTest::Outside;
  });
  std::vector<uint32_t> unbounded, bounded;
  ObjectCounts c;
  for (uint32_t m = 0; m < meshCount; ++m) {
    const bool carry = carried && !carried->empty() && (*carried)[m];
    if (tests[m] == MeshTest::Outside) counters.culledFrustum += scene.meshes[m].triangleCount;
    else (tests[m] == MeshTest::None || carry ? unbounded : bounded).push_back(m);
    c.objectsCarried += carry && tests[m] == MeshTest::Bounded;
  }
  std::stable_sort(bounded.begin(), bounded.end(), [&](uint32_t a, uint32_t b) { return bounds[a].zMin < bounds[b].zMin; });
  const std::vector<uint32_t> ranks =
      frontToBack ? faceRanks(faceKeys(scene, camera, SortKey::Min), /*backToFront=*/false) : std::vector<uint32_t>{};
  c.objects = unbounded.size() + bounded.size();
  const size_t perBatch = std::max<size_t>(1, (bounded.size() + kBatches - 1) / kBatches);
  std::vector<uint32_t> batch;
  std::vector<TriangleRange> ranges;
  for (size_t start = 0; start < bounded.size() || c.batches == 0; start += perBatch) {
    batch.clear();
    if (c.batches == 0) batch = unbounded;
    for (size_t i = start; i < std::min(bounded.size(), start + perBatch); ++i) {
      const MeshBound& b = bounds[bounded[i]];
      if (hz.boxHidden(b.minX, b.minY, b.maxX, b.maxY, b.nearest)) {
        ++c.objectsCulled;
        c.trianglesCulled += scene.meshes[bounded[i]].triangleCount;
      } else {
        batch.push_back(bounded[i]);
      }
    }
    ++c.batches;
    if (batch.empty()) continue;
    std::sort(batch.begin(), batch.end());  // set-up takes sorted ranges
    ranges.clear();
    for (uint32_t m : batch) ranges.push_back({scene.meshes[m].firstTriangle, scene.meshes[m].firstTriangle + scene.meshes[m].triangleCount});
    FrontEndOptions only;
    only.only = &ranges;
    runSetUp(scene, camera, options, vertices, fe, {}, only);
    counters.add(fe);
    frontEndBytes = std::max(frontEndBytes, fe.memoryBytes() + vertices.memoryBytes());
    std::vector<SetupTriangle> set = fe.flatten();
    if (frontToBack) byFaceRank(ranks)(set);
    const size_t first = triangles.size();
    triangles.insert(triangles.end(), set.begin(), set.end());
    hz.drawFrom(first, n);
  }
  return c;
}

// What a frame on the pyramid does.
struct PyramidUse {
  bool frontToBack = false;   // faces nearest first (by their nearest vertex), else as submitted
  bool testTriangles = true;  // the hierarchical z-buffer: each triangle tested against the pyramid
  bool cull = false;          // occlusion culling: meshes tested against the pyramid before set-up
  std::vector<uint8_t>* shown = nullptr;  // with cull: temporal coherence (MeshesShown), its meshes drawn first
};

// A frame of the hierarchical z-buffer (use.testTriangles) or of the textbook z-buffer on its
// pyramid (occlusion culling only), with or without occlusion culling.
void pyramidFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, PyramidUse use,
                  Frame& frame) {
  Stats& st = frame.stats;
  FrameSteps steps;
  steps.setUp = !use.cull;  // occlusion culling sets triangles up batch by batch, between draws
  if (!use.cull && use.frontToBack)
    steps.order = byFaceRank(faceRanks(faceKeys(scene, camera, SortKey::Min), /*backToFront=*/false));
  drawFrame(scene, camera, options, steps, [&](FrameWork& work, const TriangleShader& shade) {
    DrawCounters& n = work.counters;
    visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
      HierarchicalZBuffer<S, M> hz(work.triangles, camera, options, frame, use.testTriangles);
      if (use.cull) {
        Timer timer;
        const ObjectCounts c = drawByObjects(scene, camera, options, use.frontToBack,
                                             use.shown, hz, work.triangles,
                                             work.frontEnd, work.frontEndBytes, n);
        st.addTime("frontend+raster", timer.lap());
        st.culled_occlusion = c.trianglesCulled;
        st.setDetail("objects", c.objects);
        st.setDetail("objects_culled", c.objectsCulled);
        st.setDetail("triangles_culled", c.trianglesCulled);
        st.setDetail("batches", c.batches);
        if (use.shown) st.setDetail("objects_carried", c.objectsCarried);
      } else {
        hz.drawFrom(0, n);
      }
      if (use.shown) hz.meshesShown(scene, *use.shown);
      hz.resolve(shade, n);
      hz.addMemory(st);
      if (!use.testTriangles) return;
      st.setDetail("levels", uint64_t(hz.levels()));
      st.setDetail("triangles_drawn", uint64_t(work.triangles.size()));
      st.setDetail("triangles_rejected", hz.trianglesRejected());
      for (int k = 0; k < hz.levels(); ++k) {
        const LevelCounts& c = hz.counts()[size_t(k)];
        st.setDetail(levelKey(k, 0), c.tested);
        st.setDetail(levelKey(k, 1), c.rejected);
        st.setDetail(levelKey(k, 2), c.descended);
      }
    });
  }, frame);
}

// The pyramid is rebuilt over each frame's depth buffer: the object keeps nothing between views.
class Hzb final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    pyramidFrame(scene_, camera, options,
                 {.frontToBack = params_.text("order") == "front-to-back",
               .testTriangles = true,
               .cull = params_.flag("occlusion-cull")},
              frame);
    frame.stats.setDetail("order", params_.text("order"));
    frame.stats.setDetail("pyramid_updates", "exact");
  }
};

}  // namespace

void zbufferOcclusionCulled(const Scene& scene, const Camera& camera, const RenderOptions& options,
                            MeshesShown* coherence, Frame& frame) {
  pyramidFrame(scene, camera, options,
               {.frontToBack = false, .testTriangles = false, .cull = true, .shown = coherence ? &coherence->shown : nullptr},
               frame);
}

AlgorithmInfo hzbAlgorithm() {
  AlgorithmInfo a;
  a.name = "hzb";
  a.summary = "hierarchical z-buffer: a z-pyramid of farthest depths rejects hidden triangles before their pixels";
  a.source = "Ukrainian paper (the hierarchical z-buffer of Greene, Kass and Miller, 1993)";
  a.params = {{"order", ParamType::Choice, "front-to-back", {"front-to-back", "submission"}, -1e300, 1e300,
               "the order triangles are drawn in: faces by their nearest vertex, nearest first (what the pyramid "
               "rejects most with), or as submitted"},
              {"occlusion-cull", ParamType::Bool, "off", {}, -1e300, 1e300,
               "occlusion culling: meshes in batches nearest first, each mesh's screen box and nearest depth tested "
               "against the pyramid before any of its triangles is set up"}};
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "a z-buffer in any order; ties of equal depth are ambiguous";
  a.create = factoryOf<Hzb>();
  return a;
}

}  // namespace hsr::algo

// The z-buffer with hierarchical subdivision of polygons at their midpoint, as the Ukrainian
// paper proposes it:
//
//   for each triangle, in submission order:
//     split it `initial-splits` times (each split: three triangles, from the midpoint to each edge)
//     for each part:
//       (1) its midpoint: the mean of its three vertices
//       (2) the depth of its vertices and midpoint compared with the z-buffer at their pixels
//       (3) all behind: invisible, dropped; all in front: drawn, every pixel written untested;
//       (4) otherwise split into three at the midpoint and go to (1); a part split `max-depth`
//           times is drawn with the depth test at every pixel instead
//
// Counted as the paper counts: one z comparison per vertex or midpoint tested, plus one per pixel
// tested at the limit (depth_tests). A point is tested as the z-buffer would test its pixel: the
// triangle's depth at the centre of the pixel the point lies in against the value stored there,
// when the triangle covers that centre. A point outside the image, or in a pixel the triangle
// does not cover (a vertex on an edge shared with a neighbour), has no value of its own to
// compare: it is not tested, and a part with no tested point (a sliver, or one off the image)
// is left to the z-buffer: drawn with the depth test at every pixel.
//
// Approximate, as the paper says: a nearer edge, or a gap between farther surfaces, that passes
// between the tested points is not seen, so a part is dropped or drawn over where it should not be.
//
// The parts partition the triangle's pixels exactly: their vertices are kept as exact rationals
// (a part split d times has its coordinates scaled by 3^d, the midpoint being the sum of the three
// vertices over 3), and each part's coverage is decided by the integer edge functions with the
// top-left rule, the parent's edges being the triangle's own. So every pixel the triangle covers
// belongs to exactly one part, the pixels of a part drawn are those the z-buffer would draw.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "algorithms/algorithms.hpp"
#include "algorithms/draw.hpp"
#include "algorithms/zbuffer_pixels.hpp"
#include "scene/shading.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "setup/edge.hpp"
#include "raster/halfspace.hpp"

namespace hsr::algo {
namespace {

// The deepest split allowed: a part's coordinates are 1/256 pixel times 3^depth (below 2^50 at
// 3^16 within the guard band), its edge functions' products below 2^102 in 128-bit integers.
constexpr int kMaxSplitDepth = 16;

using Wide = __int128;

// A part of a triangle: its vertices in units of 1/(256 3^depth) pixel, ordered as the set-up
// triangle's (edge functions positive inside).
struct Part {
  int64_t x[3], y[3];
  int depth;
  int64_t scale;  // 3^depth
};

// What the tests decided, counted.
struct MidpointCounts {
  uint64_t pointComparisons = 0;  // vertices and midpoints compared with the z-buffer
  uint64_t pixelTests = 0;        // per-pixel depth tests (parts at the limit or with no point tested)
  uint64_t parts = 0;             // parts tested
  uint64_t invisible = 0;         // ... all behind: dropped
  uint64_t drawnUntested = 0;     // ... all in front: drawn without per-pixel tests
  uint64_t split = 0;             // ... mixed: split into three
  uint64_t perPixel = 0;          // ... mixed at the limit, or with no point tested: drawn with the depth test
};

template <DepthStorage S, DepthMapping M>
class MidpointZBuffer {
 public:
  using Pixels = ZBufferPixels<S, M>;
  using T = typename Pixels::T;

  MidpointZBuffer(std::span<const SetupTriangle> tris, const Camera& camera, const RenderOptions& options,
                  Frame& frame, int initialSplits, int maxDepth)
      : tris_(tris), camera_(camera), pixels_(camera, options, frame), initialSplits_(initialSplits),
        maxDepth_(std::max(maxDepth, initialSplits)) {}

  void drawAll(DrawCounters& n) {
    for (uint32_t i = 0; i < tris_.size(); ++i) draw(i, n);
  }
  void resolve(const TriangleShader& shade, DrawCounters& n) { pixels_.resolve(tris_, shade, n); }
  const MidpointCounts& counts() const { return counts_; }
  void addMemory(Stats& st) const {
    pixels_.addMemory(st);
    st.addMemory("midpoint_parts", stack_.capacity() * sizeof(Part));
  }

 private:
  enum class Verdict { Behind, InFront, Mixed, Untested };

  // Triangle i: its parts processed from a stack (the paper's store of child polygons).
  void draw(uint32_t i, DrawCounters& n) {
    const SetupTriangle& t = tris_[i];
    i_ = i;
    m_ = pixels_.planes(t);
    for (int e = 0; e < 3; ++e) edges_[e] = makeEdge(t, e);
    stack_.clear();
    stack_.push_back({{t.x[0], t.x[1], t.x[2]}, {t.y[0], t.y[1], t.y[2]}, 0, 1});
    while (!stack_.empty()) {
      const Part part = stack_.back();
      stack_.pop_back();
      if (part.depth < initialSplits_) {
        split(part);
        continue;
      }
      ++counts_.parts;
      const Verdict verdict = test(part);
      switch (verdict) {
        case Verdict::Behind: ++counts_.invisible; break;
        case Verdict::InFront:
          ++counts_.drawnUntested;
          rasterize(part, [&](size_t idx, T z) { pixels_.write(idx, z, i_, n); });
          break;
        case Verdict::Mixed:
        case Verdict::Untested:
          if (verdict == Verdict::Mixed && part.depth < maxDepth_) {
            ++counts_.split;
            split(part);
          } else {
            ++counts_.perPixel;
            rasterize(part, [&](size_t idx, T z) {
              ++counts_.pixelTests;
              pixels_.test(idx, z, i_, n);
            });
          }
          break;
      }
    }
  }

  // The three parts from the midpoint to each edge, at 3 times the scale; those whose box holds
  // no pixel centre of the triangle's box are left out.
  void split(const Part& p) {
    const int64_t mx = p.x[0] + p.x[1] + p.x[2], my = p.y[0] + p.y[1] + p.y[2];
    for (int e = 0; e < 3; ++e) {
      const int f = (e + 1) % 3;
      Part c{{3 * p.x[e], 3 * p.x[f], mx}, {3 * p.y[e], 3 * p.y[f], my}, p.depth + 1, 3 * p.scale};
      Box b = boxOf(c);
      if (b.x0 <= b.x1 && b.y0 <= b.y1) stack_.push_back(c);
    }
  }

  // The depth of the part's vertices and midpoint against the z-buffer at their pixels.
  Verdict test(const Part& p) {
    int front = 0, behind = 0, tested = 0;
    auto point = [&](int64_t X, int64_t Y, int64_t unit) {  // (X, Y) / unit pixels
      const int64_t px = floorDiv(X, unit), py = floorDiv(Y, unit);
      if (px < 0 || py < 0 || px >= camera_.width || py >= camera_.height || !covers(int(px), int(py))) return;
      const T z = Pixels::fragment(m_, int(px), int(py));
      const T stored = pixels_.at(size_t(py) * size_t(camera_.width) + size_t(px));
      ++counts_.pointComparisons;
      ++tested;
      front += Pixels::nearer(z, stored);
      behind += Pixels::nearer(stored, z);
    };
    const int64_t unit = kSubpixelOne * p.scale;
    for (int v = 0; v < 3; ++v) point(p.x[v], p.y[v], unit);
    point(p.x[0] + p.x[1] + p.x[2], p.y[0] + p.y[1] + p.y[2], 3 * unit);
    // (A point at the stored depth, e.g. on the edge shared with a coplanar neighbour, is
    // neither: the part is split.)
    return tested == 0 ? Verdict::Untested : front == tested ? Verdict::InFront : behind == tested ? Verdict::Behind : Verdict::Mixed;
  }

  // Whether the triangle covers pixel (x, y)'s centre (its own edge functions).
  bool covers(int x, int y) const {
    const int64_t cx = centerFixed(x), cy = centerFixed(y);
    for (const Edge& e : edges_)
      if (e.at(cx, cy) < e.bias) return false;
    return true;
  }

  struct Box {
    int x0, y0, x1, y1;
  };
  // The pixels whose centres may lie in the part, within the triangle's box.
  Box boxOf(const Part& p) const {
    const SetupTriangle& t = tris_[i_];
    const int64_t unit = kSubpixelOne * p.scale, half = kSubpixelOne / 2 * p.scale;
    const int64_t lx = std::min({p.x[0], p.x[1], p.x[2]}), hx = std::max({p.x[0], p.x[1], p.x[2]});
    const int64_t ly = std::min({p.y[0], p.y[1], p.y[2]}), hy = std::max({p.y[0], p.y[1], p.y[2]});
    return {int(std::max<int64_t>(ceilDiv(lx - half, unit), t.minX)), int(std::max<int64_t>(ceilDiv(ly - half, unit), t.minY)),
            int(std::min<int64_t>(floorDiv(hx - half, unit), t.maxX)), int(std::min<int64_t>(floorDiv(hy - half, unit), t.maxY))};
  }

  // Every pixel centre the part covers, with the triangle's stored value there: the triangle's
  // own rasterizer for the whole triangle; for a part, each row's span from its exact 128-bit edge
  // functions.
  template <class Visit>
  void rasterize(const Part& p, Visit&& visit) {
    const size_t w = size_t(camera_.width);
    if (p.depth == 0) {
      rasterizeHalfSpace(tris_[i_], [&](int x, int y, double) { visit(size_t(y) * w + size_t(x), Pixels::fragment(m_, x, y)); });
      return;
    }
    const Box b = boxOf(p);
    const Wide unit = Wide(kSubpixelOne) * p.scale, half = Wide(kSubpixelOne / 2) * p.scale;
    // Edge i at pixel column x of row y: E = A + B x, inside where E >= bias (the top-left rule).
    Wide dx[3], dy[3];
    int bias[3];
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      dx[i] = Wide(p.x[j]) - p.x[i];
      dy[i] = Wide(p.y[j]) - p.y[i];
      bias[i] = (dy[i] < 0 || (dy[i] == 0 && dx[i] > 0)) ? 0 : 1;
    }
    for (int y = b.y0; y <= b.y1; ++y) {
      // The row's span: the columns inside all three edges, solved exactly.
      Wide first = b.x0, last = b.x1;
      const Wide cy = Wide(y) * unit + half;
      for (int i = 0; i < 3; ++i) {
        const Wide A = dx[i] * (cy - p.y[i]) - dy[i] * (half - p.x[i]), B = -dy[i] * unit;
        if (B > 0) first = std::max(first, firstInside(A, B, bias[i], b.x0 - 1, b.x1 + 1));
        else if (B < 0) last = std::min(last, -firstInside(A, -B, bias[i], -(b.x1 + 1), -(b.x0 - 1)));  // x = -u
        else if (A < bias[i]) last = first - 1;
      }
      for (int x = int(first); x <= int(last) && first <= last; ++x) visit(size_t(y) * w + size_t(x), Pixels::fragment(m_, x, y));
    }
  }

  // The least x in [lo, hi] with A + B x >= bias (B > 0), hi when there is none below it: a
  // double estimate of (bias - A) / B corrected by exact steps (128-bit division is slow).
  static Wide firstInside(Wide A, Wide B, Wide bias, int64_t lo, int64_t hi) {
    const double estimate = std::ceil(double(bias - A) / double(B));
    Wide x = Wide(int64_t(std::clamp(estimate, double(lo), double(hi))));
    while (x < hi && A + B * x < bias) ++x;
    while (x > lo && A + B * (x - 1) >= bias) --x;
    return x;
  }

  std::span<const SetupTriangle> tris_;
  const Camera& camera_;
  Pixels pixels_;
  const int initialSplits_, maxDepth_;
  uint32_t i_ = 0;   // the triangle being drawn
  MappedPlanes m_;   // its depth planes
  Edge edges_[3];    // its edge functions
  std::vector<Part> stack_;
  MidpointCounts counts_;
};

void midpoint(const Scene& scene, const Camera& camera, const RenderOptions& options, const AlgorithmParams& params,
              Frame& frame) {
  Stats& st = frame.stats;
  drawFrame(scene, camera, options, {}, [&](FrameWork& work, const TriangleShader& shade) {
    DrawCounters& n = work.counters;
    visitDepthFormat(options.depthFormat, [&]<DepthStorage S, DepthMapping M>() {
      MidpointZBuffer<S, M> mz(work.triangles, camera, options, frame, int(params.integer("initial-splits")),
                               int(params.integer("max-depth")));
      mz.drawAll(n);
      mz.resolve(shade, n);
      const MidpointCounts& c = mz.counts();
      n.depthTests = c.pointComparisons + c.pixelTests;  // the paper's z comparisons
      mz.addMemory(st);
      st.setDetail("point_comparisons", c.pointComparisons);
      st.setDetail("pixel_tests", c.pixelTests);
      st.setDetail("parts_tested", c.parts);
      st.setDetail("parts_invisible", c.invisible);
      st.setDetail("parts_drawn_untested", c.drawnUntested);
      st.setDetail("parts_split", c.split);
      st.setDetail("parts_per_pixel", c.perPixel);
    });
  }, frame);
}

// Each frame subdivides anew: the object keeps nothing between views.
class Midpoint final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    midpoint(scene_, camera, options, params_, frame);
  }
};

}  // namespace

AlgorithmInfo midpointAlgorithm() {
  AlgorithmInfo a;
  a.name = "midpoint";
  a.summary = "z-buffer with hierarchical subdivision at the midpoint: a triangle's vertices and midpoint tested, "
              "then drawn untested, dropped or split in three";
  a.source = "Ukrainian paper";
  a.params = {{"initial-splits", ParamType::Int, "2", {}, 0, 8,
               "times every triangle is split in three before its parts are first tested (the paper: 2)"},
              {"max-depth", ParamType::Int, "4", {}, 0, kMaxSplitDepth,
               "splits after which an undecided part is drawn with a depth test at every pixel (at least "
               "initial-splits)"}};
  a.guarantee.kind = Guarantee::Kind::Approximate;
  a.guarantee.condition = "a nearer edge or a gap between the tested vertices and midpoint is not seen";
  a.guarantee.maxWrongFraction = 0.25;
  a.create = factoryOf<Midpoint>();
  return a;
}

}  // namespace hsr::algo

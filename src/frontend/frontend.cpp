// The front end's passes (frontend.hpp): the vertex pass, then set-up chunk by chunk — clipping,
// the scalar set-up of one triangle (the reference setupBatch matches), batches for setupBatch,
// clusters culled or deferred whole. runFrontEnd is called from one thread; each chunk is set up
// by one worker of the pool, which then hands it to the consumer.
#include "frontend/frontend.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/depth_map.hpp"
#include "core/parallel.hpp"
#include "scene/shading.hpp"
#include "frontend/clusters.hpp"
#include "frontend/triangle_setup.hpp"
#include "frontend/vertices.hpp"
#include "setup/edge.hpp"
#include "setup/fixed_point.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr {
namespace {

// The six clipping half-spaces, each "value >= 0": d >= near, d <= far, and the guard band.
constexpr int kPlanes = 6;
double planeDistance(const HVertex& v, int plane, const Camera& cam) {
  const double gx0 = -kGuardBandPixels, gx1 = cam.width + kGuardBandPixels;
  const double gy0 = -kGuardBandPixels, gy1 = cam.height + kGuardBandPixels;
  switch (plane) {
    case 0: return v.d - cam.near;
    case 1: return cam.far - v.d;
    case 2: return v.hx - gx0 * v.w;
    case 3: return gx1 * v.w - v.hx;
    case 4: return v.hy - gy0 * v.w;
    default: return gy1 * v.w - v.hy;
  }
}


// Sutherland–Hodgman in homogeneous coordinates: every coordinate is linear in the world point,
// so interpolating all four along an edge is exact.
int clipPolygon(HVertex* poly, int count, uint32_t planes, const Camera& cam, HVertex* scratch) {
  for (int p = 0; p < kPlanes && count > 0; ++p) {
    if (!(planes & (1u << p))) continue;
    int outCount = 0;
    for (int i = 0; i < count; ++i) {
      const HVertex& a = poly[i];
      const HVertex& b = poly[(i + 1) % count];
      double da = planeDistance(a, p, cam), db = planeDistance(b, p, cam);
      if (da >= 0) scratch[outCount++] = a;
      if ((da >= 0) != (db >= 0)) {
        double t = da / (da - db);
        scratch[outCount++] = {a.hx + (b.hx - a.hx) * t, a.hy + (b.hy - a.hy) * t, a.d + (b.d - a.d) * t,
                               a.w + (b.w - a.w) * t};
      }
    }
    for (int i = 0; i < outCount; ++i) poly[i] = scratch[i];
    count = outCount;
  }
  return count;
}

// Affine functions through three (x, y, value) points, for two values at once (they share the
// points, so one reciprocal of the determinant serves both).
void planesThrough(const double* x, const double* y, const double* v, const double* w, Plane& pv, Plane& pw) {
  const double x1 = x[1] - x[0], y1 = y[1] - y[0], x2 = x[2] - x[0], y2 = y[2] - y[0];
  const double inv = 1.0 / (x1 * y2 - x2 * y1);
  auto through = [&](const double* val, Plane& p) {
    const double v1 = val[1] - val[0], v2 = val[2] - val[0];
    p.a = (v1 * y2 - v2 * y1) * inv;
    p.b = (x1 * v2 - x2 * v1) * inv;
    p.c = val[0] - p.a * x[0] - p.b * y[0];
  };
  through(v, pv);
  through(w, pw);
}

}  // namespace

uint32_t clipOutcode(const HVertex& v, const Camera& cam) {
  uint32_t code = 0;
  for (int p = 0; p < kPlanes; ++p)
    if (planeDistance(v, p, cam) < 0) code |= 1u << p;
  return code;
}

HVertex transformVertex(const dvec3& p, const dmat4& M) {
  auto row = [&](int r) { return ((M[0][r] * p.x + M[1][r] * p.y) + M[2][r] * p.z) + M[3][r]; };
  return {row(0), row(1), row(2), row(3)};
}

ProjectedVertex projectVertex(const HVertex& v) {
  ProjectedVertex p;
  p.sx = v.hx / v.w;
  p.sy = v.hy / v.w;
  p.num = v.d / v.w;  // d/w and 1/w are affine in screen space
  p.den = 1.0 / v.w;
  return p;
}

bool setupTriangle(const HVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t) {
  const ProjectedVertex p[3] = {projectVertex(v[0]), projectVertex(v[1]), projectVertex(v[2])};
  return setupTriangle(p, triIndex, face, cam, cull, counters, t);
}

bool setupTriangle(const ProjectedVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t) {
  // A vertex off the grid's range has no place on it: a NaN in the scene (it survives clipping,
  // being inside every plane), or a coordinate near the double range that clipping's arithmetic
  // could not bring in (clipping leaves |s| < 2^15 pixels). Its triangle is counted degenerate.
  constexpr double kGridLimit = 0x1p20;
  for (int i = 0; i < 3; ++i)
    if (!(std::abs(v[i].sx) < kGridLimit && std::abs(v[i].sy) < kGridLimit)) {
      ++counters.degenerate;
      return false;
    }
  const int64_t X[3] = {v[0].X(), v[1].X(), v[2].X()}, Y[3] = {v[0].Y(), v[1].Y(), v[2].Y()};
  // Twice the signed area on the snapped grid, y down: negative = counter-clockwise as seen.
  const int64_t area = (X[1] - X[0]) * (Y[2] - Y[0]) - (Y[1] - Y[0]) * (X[2] - X[0]);
  if (area == 0) {
    ++counters.degenerate;
    return false;
  }
  t.frontFacing = area < 0;
  if ((cull == Cull::Back && !t.frontFacing) || (cull == Cull::Front && t.frontFacing)) {
    ++counters.culledBackface;
    return false;
  }
  int order[3] = {0, 1, 2};
  if (area < 0) std::swap(order[1], order[2]);  // make the edge functions positive inside
  double px[3], py[3], ux[3], uy[3], num[3], den[3];
  for (int i = 0; i < 3; ++i) {
    const ProjectedVertex& q = v[order[i]];
    t.x[i] = int32_t(X[order[i]]);
    t.y[i] = int32_t(Y[order[i]]);
    px[i] = double(X[order[i]]) / kSubpixelOne;
    py[i] = double(Y[order[i]]) / kSubpixelOne;
    ux[i] = q.sx;
    uy[i] = q.sy;
    num[i] = q.num;
    den[i] = q.den;
  }
  // Pixels whose centres (x + 1/2) can lie in the box: x in [ceil(min - 1/2), floor(max - 1/2)].
  const int64_t half = kSubpixelOne / 2;
  const int64_t minX = std::min({X[0], X[1], X[2]}), maxX = std::max({X[0], X[1], X[2]});
  const int64_t minY = std::min({Y[0], Y[1], Y[2]}), maxY = std::max({Y[0], Y[1], Y[2]});
  const int64_t boxX0 = std::max<int64_t>(0, ceilDiv(minX - half, kSubpixelOne));
  const int64_t boxX1 = std::min<int64_t>(cam.width - 1, floorDiv(maxX - half, kSubpixelOne));
  const int64_t boxY0 = std::max<int64_t>(0, ceilDiv(minY - half, kSubpixelOne));
  const int64_t boxY1 = std::min<int64_t>(cam.height - 1, floorDiv(maxY - half, kSubpixelOne));
  if (boxX0 > boxX1 || boxY0 > boxY1) {
    // Off screen (inside the guard band) or too small to contain a pixel centre.
    if (maxX < 0 || maxY < 0 || minX > int64_t(cam.width) * kSubpixelOne || minY > int64_t(cam.height) * kSubpixelOne)
      ++counters.culledFrustum;
    return false;
  }
  // In the image (< kMaxImageSize = 2^14): the box fits int16.
  t.minX = int16_t(boxX0);
  t.maxX = int16_t(boxX1);
  t.minY = int16_t(boxY0);
  t.maxY = int16_t(boxY1);
  // A small box (at most kCoverageBox pixels each way; most triangles of a dense mesh): the
  // pixel centres the triangle covers, one bit each (SetupTriangle::coverage). None: it draws
  // nothing, so it is dropped here rather than planed, binned and rasterized (in a dense mesh,
  // many are).
  t.coverage = 0;
  if (boxX1 - boxX0 < kCoverageBox && boxY1 - boxY0 < kCoverageBox) {
    const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
    for (int64_t y = boxY0; y <= boxY1; ++y)
      for (int64_t x = boxX0; x <= boxX1; ++x) {
        bool inside = true;
        for (const Edge& edge : e) inside &= edge.at(centerFixed(int(x)), centerFixed(int(y))) >= edge.bias;
        t.coverage |= uint16_t(inside) << ((y - boxY0) * kCoverageBox + (x - boxX0));
      }
    if (!t.coverage) {
      ++counters.empty;
      return false;
    }
  }
  // Depth planes through the unsnapped positions: snapping decides coverage only, so depth stays
  // exact for the true triangle. Fall back to the snapped positions when the unsnapped triangle is
  // (nearly) degenerate and its plane would be ill-conditioned.
  const double exactArea = (ux[1] - ux[0]) * (uy[2] - uy[0]) - (uy[1] - uy[0]) * (ux[2] - ux[0]);
  const bool useExact = exactArea > 0.5 * double(std::abs(area)) / double(kSubpixelOne * kSubpixelOne);
  if (useExact) planesThrough(ux, uy, num, den, t.depthNum, t.depthDen);
  else planesThrough(px, py, num, den, t.depthNum, t.depthDen);
  t.triangle = triIndex;
  t.face = face;
  counters.large += boxX1 - boxX0 + 1 >= kLargeBoxPixels && boxY1 - boxY0 + 1 >= kLargeBoxPixels;
  return true;
}

size_t FrontEndOutput::triangleCount() const {
  size_t n = 0;
  for (size_t c = 0; c < chunkCount; ++c) n += chunks[c].triangles.size();
  return n;
}

std::vector<SetupTriangle> FrontEndOutput::flatten() const {
  std::vector<SetupTriangle> all;
  flattenInto(all);
  return all;
}

void FrontEndOutput::flattenInto(std::vector<SetupTriangle>& all) const {
  all.clear();
  all.reserve(triangleCount());
  for (size_t c = 0; c < chunkCount; ++c) all.insert(all.end(), chunks[c].triangles.begin(), chunks[c].triangles.end());
}

uint64_t FrontEndOutput::memoryBytes() const {
  uint64_t bytes = outcodes.capacity() +
                   projected.capacity() * sizeof(ProjectedVertex) + faceVisible.capacity() + meshCulled.capacity() +
                   meshUnclipped.capacity();
  for (const auto& c : chunks)
    bytes += c.triangles.capacity() * sizeof(SetupTriangle) + c.nearest.capacity() * sizeof(double) +
             c.deferred.capacity() * sizeof(DeferredFace) + c.clusters.capacity() * sizeof(DeferredCluster);
  return bytes;
}

namespace {

// What the set-up of every chunk reads (runSetUp): the frame, its vertex pass, and what
// runSetUp decided for all chunks.
struct SetUpInputs {
  const Scene& scene;
  const Camera& cam;
  const RenderOptions& options;
  const TriangleShader& shade;
  const FrontEndOutput& fe;     // the vertex pass (outcodes, projected vertices, meshes in view)
  const uint8_t* unclipped;     // per mesh, 1 when none of its vertices is outside the clip volume
  const DepthSetup* depth;      // the nearest bounds' depth setup (null: none)
  bool defer;                   // back faces and clusters deferred (FrontEndOptions::deferBackFaces)
  const ClusterView* clusters;  // clusters culled or deferred whole with this view (null: none)
  bool color;                   // front faces shaded
};

// Sets up the triangles of one chunk [begin, end) into `out` in order, clipping where needed,
// with their nearest bounds in `depth` (when given) in out.nearest. Colour is shaded here, for
// the triangles that survive set-up, while the scene's data for them is in cache (the resolve
// would read it back in pixel order, scattered). Triangles inside the clip volume are set up in
// batches with SIMD (setupBatch); a clipped one flushes the batch first, so the output stays in
// submission order.
class ChunkSetUp {
 public:
  ChunkSetUp(const SetUpInputs& in, FrontEndChunk& out) : in_(in), out_(out), counters_(out.counters) {
    out.triangles.clear();
    out.nearest.clear();
    out.deferred.clear();
    out.clusters.clear();
  }

  // The chunk's triangles [chunkBegin, chunkEnd), or those of `only` in it.
  void run(size_t chunkBegin, size_t chunkEnd, const std::vector<TriangleRange>* only) {
    if (!only) {
      segment(chunkBegin, chunkEnd);
    } else {
      for (auto r = std::lower_bound(only->begin(), only->end(), chunkBegin,
                                     [](const TriangleRange& range, size_t t) { return range.end <= t; });
           r != only->end() && r->first < chunkEnd; ++r)
        segment(std::max<size_t>(chunkBegin, r->first), std::min<size_t>(chunkEnd, r->end));
    }
    if (batched_) flush();
  }

 private:
  static constexpr size_t kBatch = 64;
  static_assert(kChunkTriangles % kClusterTriangles == 0, "a cluster lies in one chunk");

  // The run of triangles the loop in segment() is in: one mesh's, or those between meshes.
  struct MeshRun {
    size_t mesh;             // the first mesh not wholly before the run
    size_t end;              // the run ends before this triangle
    bool unclipped = false;  // a mesh whose vertices are all inside the clip volume
  };

  // The triangles [begin, end), in order, in runs of one mesh (or none). Those of a mesh whose
  // vertices are all inside the clip volume go to the batch a cluster at a time, without their
  // vertices' outcodes read one by one.
  void segment(const size_t begin, const size_t end) {
    const std::vector<MeshRange>& meshes = in_.scene.meshes;
    // The first mesh not wholly before `begin` (meshes are in triangle order).
    const auto firstMesh = std::partition_point(meshes.begin(), meshes.end(), [&](const MeshRange& m) {
      return size_t(m.firstTriangle) + m.triangleCount <= begin;
    });
    MeshRun run{size_t(firstMesh - meshes.begin()), begin};
    for (size_t ti = begin; ti < end; ++ti) {
      if (ti >= run.end) nextRun(ti, end, run);
      const Triangle& tri = in_.scene.triangles[ti];
      if (in_.clusters && ti % kClusterTriangles == 0 && in_.fe.meshInView(tri.face) &&  // (a cluster is in one mesh)
          takeCluster(ti, end)) {
        ti += kClusterTriangles - 1;
        continue;
      }
      if (run.unclipped) {  // (a mesh in view: none of its vertices is outside)
        ti = batchRun(ti, std::min(run.end, end)) - 1;
        continue;
      }
      setUpTriangle(ti, tri);
    }
  }

  // The run triangle `ti` starts: its mesh's (ti is in it), or up to the next mesh.
  void nextRun(size_t ti, size_t end, MeshRun& run) const {
    const std::vector<MeshRange>& meshes = in_.scene.meshes;
    while (run.mesh < meshes.size() && size_t(meshes[run.mesh].firstTriangle) + meshes[run.mesh].triangleCount <= ti)
      ++run.mesh;
    if (run.mesh < meshes.size() && meshes[run.mesh].firstTriangle <= ti) {
      run.unclipped = in_.unclipped && in_.unclipped[run.mesh];
      run.end = size_t(meshes[run.mesh].firstTriangle) + meshes[run.mesh].triangleCount;
    } else {  // between meshes (or after the last)
      run.unclipped = false;
      run.end = run.mesh < meshes.size() ? meshes[run.mesh].firstTriangle : end;
    }
  }

  // The cluster starting at triangle `ti` culled whole (with Cull::Back: each of its triangles a
  // back face, counted as set-up would) or deferred whole; false when it is neither.
  bool takeCluster(size_t ti, size_t end) {
    const TriangleCluster& cluster = in_.scene.clusters[ti / kClusterTriangles];
    if (ti + kClusterTriangles < end) {  // the next cluster (a culled or deferred one is skipped: no stream to follow)
      __builtin_prefetch(&cluster + 1);
      __builtin_prefetch(&in_.scene.triangles[ti + kClusterTriangles]);
    }
    if (in_.options.cull == Cull::Back) {
      if (!cullCluster(cluster, *in_.clusters, in_.cam, in_.fe.pixelFromWorld)) return false;
      counters_.culledBackface += kClusterTriangles;
      return true;
    }
    if (!in_.defer) return false;
    DeferredCluster dc;
    if (!deferCluster(cluster, *in_.clusters, in_.cam, in_.fe.pixelFromWorld, *in_.depth, dc)) return false;
    dc.cluster = uint32_t(ti / kClusterTriangles);
    out_.clusters.push_back(dc);
    return true;
  }

  // The triangles [ti, runEnd) of an unclipped mesh up to the next cluster, into the batch
  // (flushed as it fills); returns where it stopped.
  size_t batchRun(size_t ti, size_t runEnd) {
    const size_t stop = std::min(runEnd, in_.clusters ? (ti / kClusterTriangles + 1) * kClusterTriangles : runEnd);
    const Triangle* from = in_.scene.triangles.data();
    const ProjectedVertex* projected = in_.fe.projected.data();
    for (size_t t = ti; t < stop;) {
      const size_t take = std::min(stop - t, kBatch - batched_);
      for (size_t i = 0; i < take; ++i) {
        const Triangle& tr = from[t + i];
        for (int k = 0; k < 3; ++k) {
          batchVertex_[k][batched_ + i] = tr.v[k];
          __builtin_prefetch(projected + tr.v[k]);  // (setupBatch reads it a batch later)
        }
        batchTriangle_[batched_ + i] = uint32_t(t + i);
        batchFace_[batched_ + i] = tr.face;
      }
      t += take;
      batched_ += take;
      if (batched_ == kBatch) flush();
    }
    return stop;
  }

  // One triangle of no unclipped mesh: culled whole when its mesh or all three vertices are
  // outside, batched when all three are inside, else clipped.
  void setUpTriangle(size_t ti, const Triangle& tri) {
    const FrontEndOutput& fe = in_.fe;
    if (!fe.meshInView(tri.face)) {
      ++counters_.culledFrustum;
      return;
    }
    const uint32_t c0 = fe.outcodes[tri.v[0]], c1 = fe.outcodes[tri.v[1]], c2 = fe.outcodes[tri.v[2]];
    if (c0 & c1 & c2) {
      ++counters_.culledFrustum;
      return;
    }
    if ((c0 | c1 | c2) == 0) {
      for (int k = 0; k < 3; ++k) {
        batchVertex_[k][batched_] = tri.v[k];
        __builtin_prefetch(fe.projected.data() + tri.v[k]);  // (setupBatch reads it a batch later)
      }
      batchTriangle_[batched_] = uint32_t(ti);
      batchFace_[batched_] = tri.face;
      if (++batched_ == kBatch) flush();
      return;
    }
    if (batched_) flush();
    setUpClipped(ti, tri, c0 | c1 | c2);
  }

  // A triangle crossing the clipping planes `planes`: clipped, and the pieces (the clipped
  // polygon is convex: a fan) set up one by one, each keeping the triangle's and face's index.
  void setUpClipped(size_t ti, const Triangle& tri, uint32_t planes) {
    ++counters_.clipped;
    for (int k = 0; k < 3; ++k) poly_[k] = transformVertex(in_.scene.positions[tri.v[k]], in_.fe.pixelFromWorld);
    const int n = clipPolygon(poly_, 3, planes, in_.cam, scratch_);
    for (int i = 1; i + 1 < n; ++i) {
      HVertex piece[3] = {poly_[0], poly_[i], poly_[i + 1]};
      if (setupTriangle(piece, uint32_t(ti), tri.face, in_.cam, in_.options.cull, counters_, piece_)) {
        piece_.color = in_.color && piece_.frontFacing ? in_.shade(piece_.triangle) : Rgba8{};
        keep(piece_, in_.depth ? nearestStored(piece_, *in_.depth) : 0.0);
      }
    }
  }

  void keep(const SetupTriangle& t, double nearest) {
    SetupTriangles& list = out_.triangles;
    if (list.size() + 48 < list.capacity()) __builtin_prefetch(list.data() + list.size() + 48, 1, 3);
    list.push_back(t);
    if (in_.depth) out_.nearest.push_back(nearest);
  }

  // The batch set up (setupBatch) straight into the chunk's list, its front faces shaded.
  void flush() {
    const uint32_t* vertex[3] = {batchVertex_[0], batchVertex_[1], batchVertex_[2]};
    size_t deferred = 0;
    // Room for the whole batch first (resize writes nothing, UnwrittenAllocator), then cut to
    // the triangles kept.
    const size_t first = out_.triangles.size();
    out_.triangles.resize(first + batched_);
    SetupTriangle* kept = out_.triangles.data() + first;
    const uint64_t culledBefore = counters_.culledBackface;
    const size_t n = setupBatch(in_.fe.projected.data(), vertex, batchTriangle_, batchFace_, batched_, in_.cam,
                                in_.options.cull, counters_, kept,
                                {.depth = in_.depth,
                                 .nearest = batchNearest_,
                                 .deferred = in_.defer ? batchDeferred_ : nullptr,
                                 .deferredCount = &deferred,
                                 .cullFirst = cullFirst_});
    // With a cull, the facing test first for the next batch when at least a quarter of this one
    // was culled: neighbouring triangles mostly face alike, and the test first pays only when
    // many are culled.
    cullFirst_ = (counters_.culledBackface - culledBefore) * 4 >= batched_;
    out_.triangles.resize(first + n);
    // The next batch's lines, for writing (cold: last written a frame ago).
    if (first + n + 2 * kBatch <= out_.triangles.capacity()) prefetchForWriting(kept + n, kBatch);
    shadeFronts(kept, n);
    if (in_.depth) out_.nearest.insert(out_.nearest.end(), batchNearest_, batchNearest_ + n);
    out_.deferred.insert(out_.deferred.end(), batchDeferred_, batchDeferred_ + deferred);
    batched_ = 0;
  }

  // The colours of set-up triangles kept[0, n): front faces shaded (see triangleColor), many at
  // once; back faces none. (Inlined: part of flush, once a batch.)
  [[gnu::always_inline]] void shadeFronts(SetupTriangle* kept, size_t n) const {
    uint32_t front[kBatch], at[kBatch];
    size_t fronts = 0;
    for (size_t i = 0; i < n; ++i) {
      kept[i].color = Rgba8{};
      if (in_.color && kept[i].frontFacing) front[fronts] = kept[i].triangle, at[fronts++] = uint32_t(i);
    }
    Rgba8 colors[kBatch];
    in_.shade.shadeMany(front, fronts, colors);
    for (size_t j = 0; j < fronts; ++j) kept[at[j]].color = colors[j];
  }

  const SetUpInputs& in_;
  FrontEndChunk& out_;
  FrontEndCounters& counters_;
  // The batch: triangle i has vertices batchVertex_[0..2][i], scene index batchTriangle_[i].
  uint32_t batchVertex_[3][kBatch], batchTriangle_[kBatch], batchFace_[kBatch];
  size_t batched_ = 0;
  bool cullFirst_ = false;  // see flush
  double batchNearest_[kBatch];
  DeferredFace batchDeferred_[kBatch];
  HVertex poly_[3 + kPlanes], scratch_[3 + kPlanes];  // a clipped triangle's polygon
  SetupTriangle piece_;                                // and the set-up of one piece of it
};

// FrontEndOutput::meshUnclipped: of the meshes set-up meets (those of `only`, or all), those
// whose vertices all have outcode 0 in the vertex pass.
void findUnclippedMeshes(const Scene& scene, const FrontEndOutput& vertices, const std::vector<TriangleRange>* only,
                         std::vector<uint8_t>& unclipped) {
  const size_t meshCount = scene.meshes.size();
  unclipped.assign(meshCount, 0);
  auto test = [&](size_t m) {
    const MeshRange& mesh = scene.meshes[m];
    if (mesh.vertexCount == 0 || (m < vertices.meshCulled.size() && vertices.meshCulled[m])) return;
    const uint8_t* code = vertices.outcodes.data() + mesh.firstVertex;
    uint8_t any = 0;
    for (uint32_t v = 0; v < mesh.vertexCount; ++v) any |= code[v];
    unclipped[m] = any == 0;
  };
  if (!only) {
    for (size_t m = 0; m < meshCount; ++m) test(m);
    return;
  }
  auto r = only->begin();
  for (size_t m = 0; m < meshCount && r != only->end(); ++m) {
    const size_t first = scene.meshes[m].firstTriangle, last = first + scene.meshes[m].triangleCount;
    while (r != only->end() && r->end <= first) ++r;
    if (r != only->end() && r->first < last) test(m);
  }
}

}  // namespace

void runVertexPass(const Scene& scene, const Camera& cam, const RenderOptions& options, FrontEndOutput& out,
                   const MeshConsumer& meshConsumer, bool vertices) {
  const int threads = resolveThreads(options.threads);

  // Every vertex once, in double, straight from world to homogeneous pixel coordinates; those
  // inside the clip volume are projected and snapped here, shared by all their triangles.
  const size_t nv = scene.positions.size();
  out.outcodes.resize(nv);
  out.projected.resize(nv);
  out.pixelFromWorld = cam.pixelFromCamera * cam.cameraFromWorld;
  const dmat4& pixelFromWorld = out.pixelFromWorld;

  // Object-level view culling: a mesh whose bounding box lies wholly outside one clipping plane
  // is skipped without touching its triangles. Its eight corners go through the vertex pass's
  // SIMD transform (the same matrix as its vertices), a run of meshes per item beside the vertex
  // pass's items (the city has 3601 meshes: as many corners as vertices); faceVisible stays
  // empty unless a mesh is culled: then a byte per face.
  const size_t meshCount = scene.meshes.size();
  out.meshCulled.resize(meshCount);
  auto testMeshes = [&](size_t first, size_t last) {  // meshCulled[first, last)
    constexpr size_t kGroup = 32;  // meshes whose corners are transformed together
    dvec3 corners[8 * kGroup];
    uint8_t codes[8 * kGroup];
    for (size_t g = first; g < last; g += kGroup) {
      const size_t n = std::min(last - g, kGroup);
      for (size_t m = 0; m < n; ++m) {
        const Bounds3& b = scene.meshes[g + m].bounds;  // computed once, by Scene::finalize()
        for (int c = 0; c < 8; ++c)
          corners[8 * m + c] = {c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z};
      }
      transformVertices(corners, 8 * n, pixelFromWorld, cam, codes, nullptr);  // (outcodes only)
      for (size_t m = 0; m < n; ++m) {
        uint8_t all = codes[8 * m];
        for (int c = 1; c < 8; ++c) all &= codes[8 * m + c];
        out.meshCulled[g + m] = !scene.meshes[g + m].bounds.empty() && all != 0;
      }
    }
  };

  // The vertex pass's chunks, then the mesh tests' runs, as items of one parallel loop — on one
  // thread when there are no more vertices and mesh corners than one item holds: handing a few
  // microseconds of work to a second thread costs more than it saves.
  const size_t vertexChunks = vertices ? (nv + kChunkTriangles - 1) / kChunkTriangles : 0;
  constexpr size_t kMeshesPerItem = 512;
  const size_t meshItems = (meshCount + kMeshesPerItem - 1) / kMeshesPerItem;
  const size_t work = (vertices ? nv : 0) + 8 * meshCount;  // vertices and corners to transform
  parallelFor(0, vertexChunks + meshItems, work <= kChunkTriangles ? 1 : threads, [&](size_t c) {
    if (c >= vertexChunks) {
      const size_t first = (c - vertexChunks) * kMeshesPerItem, last = std::min(meshCount, first + kMeshesPerItem);
      testMeshes(first, last);
      if (meshConsumer) meshConsumer(first, last);
      return;
    }
    const size_t first = c * kChunkTriangles, count = std::min(nv, first + kChunkTriangles) - first;
    transformVertices(scene.positions.data() + first, count, pixelFromWorld, cam, out.outcodes.data() + first,
                      out.projected.data() + first);
  });
  out.faceVisible.clear();
  for (size_t m = 0; m < meshCount; ++m) {
    if (!out.meshCulled[m]) continue;
    const MeshRange& mesh = scene.meshes[m];
    if (out.faceVisible.empty()) out.faceVisible.assign(scene.faceCount(), 1);
    std::fill(out.faceVisible.begin() + mesh.firstFace, out.faceVisible.begin() + mesh.firstFace + mesh.faceCount, 0);
  }

}

void runSetUp(const Scene& scene, const Camera& cam, const RenderOptions& options, const FrontEndOutput& vertices,
              FrontEndOutput& out, const ChunkConsumer& consumer, const FrontEndOptions& frontEnd) {
  static_cast<FrontEndCounters&>(out) = FrontEndCounters{};
  const int threads = resolveThreads(options.threads);
  // Triangles in fixed chunks, each into its own list (read in chunk order, they are the
  // submission order), each handed to the consumer by the worker that set it up.
  const size_t nt = scene.triangles.size();
  const TriangleShader shade(scene, cam, options.shading);
  const bool defer = frontEnd.deferBackFaces && frontEnd.nearestFor;
  const bool clusters = (defer || options.cull == Cull::Back) && frontEnd.deferClusters &&
                        scene.clusters.size() == (nt + kClusterTriangles - 1) / kClusterTriangles;
  const ClusterView view = clusters ? clusterView(cam) : ClusterView{};
  findUnclippedMeshes(scene, vertices, frontEnd.only, out.meshUnclipped);
  out.chunkTriangles = chunkTrianglesFor(nt);
  const size_t per = out.chunkTriangles;
  out.chunkCount = (nt + per - 1) / per;
  if (out.chunks.size() < out.chunkCount) out.chunks.resize(out.chunkCount);
  const SetUpInputs in{scene, cam, options, shade, vertices, out.meshUnclipped.data(), frontEnd.nearestFor, defer,
                       view.enabled ? &view : nullptr, has(options.outputs, FrameOutputs::Color)};
  parallelFor(0, out.chunkCount, threads, [&](size_t c) {
    FrontEndChunk& chunk = out.chunks[c];
    chunk.counters = FrontEndCounters{};
    chunk.firstTriangle = uint32_t(c * per);
    ChunkSetUp(in, chunk).run(c * per, std::min(nt, (c + 1) * per), frontEnd.only);
    if (consumer) consumer(c);
  });
  for (size_t c = 0; c < out.chunkCount; ++c) out.add(out.chunks[c].counters);
}

void runFrontEnd(const Scene& scene, const Camera& cam, const RenderOptions& options, FrontEndOutput& out,
                 const ChunkConsumer& consumer, const FrontEndOptions& frontEnd) {
  runVertexPass(scene, cam, options, out);
  runSetUp(scene, cam, options, out, out, consumer, frontEnd);
}

}  // namespace hsr

// The A-buffer, the exact colour reference for transparency [KTH report, lecture notes]: every
// fragment of every pixel kept — each face the pixel centre's ray meets, in double precision with
// the reference's watertight test (bvh.hpp) — sorted by exact depth and blended front to back in
// double, then rounded once to 8 bits. Face id, triangle and depth are the nearest fragment's, as
// raycast's. Rows run in parallel; any thread count gives the same bits.
#include <algorithm>
#include <cmath>

#include "algorithms/algorithms.hpp"
#include "algorithms/bvh.hpp"
#include "core/parallel.hpp"
#include "scene/shading.hpp"
#include "core/timer.hpp"

namespace hsr::algo {

bool hasTransparency(const Scene& scene) {
  for (const Rgba8& c : scene.faceColors)
    if (c.a < 255) return true;
  return false;
}

namespace {

// The fragments of one pixel, nearest first, one per face (a ray through an edge the face's
// triangles share meets both), blended front to back over the background.
Rgba8 blendFragments(std::vector<RayHit>& hits, const Scene& scene, const TriangleShader& shade, Rgba8 background,
                     uint64_t& fragments) {
  std::sort(hits.begin(), hits.end(),
            [](const RayHit& a, const RayHit& b) { return a.t != b.t ? a.t < b.t : a.triangle < b.triangle; });
  double r = 0, g = 0, b = 0, a = 0, through = 1;  // premultiplied colour so far, and what shows through
  for (size_t i = 0; i < hits.size() && through > 0; ++i) {
    const uint32_t face = scene.triangles[size_t(hits[i].triangle)].face;
    bool seen = false;
    for (size_t k = 0; k < i && !seen; ++k) seen = scene.triangles[size_t(hits[k].triangle)].face == face;
    if (seen) continue;
    ++fragments;
    const Rgba8 c = shade(uint32_t(hits[i].triangle));
    const double alpha = c.a / 255.0, w = through * alpha;
    r += w * c.r;
    g += w * c.g;
    b += w * c.b;
    a += w;
    through *= 1 - alpha;
  }
  const double bgAlpha = background.a / 255.0;
  r += through * bgAlpha * background.r;
  g += through * bgAlpha * background.g;
  b += through * bgAlpha * background.b;
  a += through * bgAlpha;
  // Colour channels as the 8-bit "over" stores them: not divided by alpha (an opaque background
  // makes a = 1).
  auto byte = [](double v) { return uint8_t(std::clamp(std::lround(v), 0l, 255l)); };
  return {byte(r), byte(g), byte(b), byte(255 * a)};
}

// Whether the pixel's fragments (sorted by depth) may blend in another order or another set in
// a rasterizer (with facesChangeNearby below): two faces at one depth (within 1e-9 of it), or whose order changes within 1/128
// pixel of the centre (they cross there), or the centre within 1/128 pixel of an edge of a
// fragment's triangle as projected (each edge clipped to the near plane first), where snapped
// coverage may take or leave it — as --verify's ambiguous pixels.
bool nearAnEdge(const Scene& scene, const Camera& camera, const std::vector<RayHit>& hits, double px, double py) {
  constexpr double kEdge = 1.0 / 128;
  // Fragments of different faces at one depth (coplanar faces, or a shared edge): either order.
  for (size_t i = 1; i < hits.size(); ++i)
    if (hits[i].t - hits[i - 1].t <= 1e-9 * hits[i].t &&
        scene.triangles[size_t(hits[i].triangle)].face != scene.triangles[size_t(hits[i - 1].triangle)].face)
      return true;
  // Two fragments whose depth order changes within 1/128 pixel of the centre (the line where two
  // faces cross passes there): a rasterizer's snapped pieces may order them either way.
  if (hits.size() >= 2) {
    const dvec2 offsets[4] = {{kEdge, kEdge}, {-kEdge, kEdge}, {kEdge, -kEdge}, {-kEdge, -kEdge}};
    std::vector<dvec4> planes;  // camera space: n . x = w
    for (const RayHit& hit : hits) {
      const Triangle& tri = scene.triangles[size_t(hit.triangle)];
      const dvec3 a = camera.toCamera(scene.positions[tri.v[0]]), b = camera.toCamera(scene.positions[tri.v[1]]),
                  c = camera.toCamera(scene.positions[tri.v[2]]);
      const dvec3 n = glm::cross(b - a, c - a);
      planes.emplace_back(n, glm::dot(n, a));
    }
    auto depthAt = [&](const dvec4& plane, dvec2 p) {
      dvec3 origin, dir;
      camera.cameraRay(p.x, p.y, origin, dir);
      return (plane.w - glm::dot(dvec3(plane), origin)) / glm::dot(dvec3(plane), dir);
    };
    for (const dvec2& o : offsets) {
      const dvec2 p = dvec2(px, py) + o;
      for (size_t i = 1; i < hits.size(); ++i)
        if (depthAt(planes[i], p) < depthAt(planes[i - 1], p) &&
            scene.triangles[size_t(hits[i].triangle)].face != scene.triangles[size_t(hits[i - 1].triangle)].face)
          return true;
    }
  }
  for (const RayHit& hit : hits) {
    const Triangle& tri = scene.triangles[size_t(hit.triangle)];
    dvec3 c[3];
    for (int k = 0; k < 3; ++k) c[k] = camera.toCamera(scene.positions[tri.v[k]]);
    for (int k = 0; k < 3; ++k) {
      dvec3 a = c[k], b = c[(k + 1) % 3];
      if (!camera.orthographic) {
        if (a.z < camera.near && b.z < camera.near) continue;
        if (a.z < camera.near) a += (b - a) * ((camera.near - a.z) / (b.z - a.z));
        if (b.z < camera.near) b += (a - b) * ((camera.near - b.z) / (a.z - b.z));
      }
      const dvec4 ha = camera.pixelFromCamera * dvec4(a, 1.0), hb = camera.pixelFromCamera * dvec4(b, 1.0);
      const dvec2 pa = dvec2(ha) / ha.w, pb = dvec2(hb) / hb.w, p(px, py), e = pb - pa;
      const double length2 = glm::dot(e, e);
      const double t = length2 > 0 ? std::clamp(glm::dot(p - pa, e) / length2, 0.0, 1.0) : 0.0;
      if (glm::length(p - (pa + t * e)) <= kEdge) return true;
    }
  }
  return false;
}

// Whether the faces met by the rays through the four points 1/128 pixel diagonally off the
// centre are not the centre's: a face's edge passes that close, hit or not at the centre (a
// rasterizer's snapped coverage may then take or leave it).
bool facesChangeNearby(const CameraSpaceBvh& bvh, const Scene& scene, Cull cull, const std::vector<RayHit>& hits,
                       double px, double py, TraceCounters& counters) {
  constexpr double kEdge = 1.0 / 128;
  auto facesOf = [&](const std::vector<RayHit>& h) {
    std::vector<uint32_t> faces;
    for (const RayHit& hit : h) faces.push_back(scene.triangles[size_t(hit.triangle)].face);
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    return faces;
  };
  const std::vector<uint32_t> centre = facesOf(hits);
  std::vector<RayHit> near;
  for (const dvec2 o : {dvec2(kEdge, kEdge), dvec2(-kEdge, kEdge), dvec2(kEdge, -kEdge), dvec2(-kEdge, -kEdge)}) {
    near.clear();
    bvh.allPixelHits(px + o.x, py + o.y, cull, near, counters);
    if (facesOf(near) != centre) return true;
  }
  return false;
}

class ABuffer final : public SceneAlgorithm {
 public:
  using SceneAlgorithm::SceneAlgorithm;
  void render(const Camera& camera, const RenderOptions& options, Frame& frame) override {
    abufferFrame(scene_, camera, options, frame, nullptr);
  }
};

}  // namespace

void abufferFrame(const Scene& scene, const Camera& camera, const RenderOptions& options, Frame& frame,
                  std::vector<uint8_t>* nearEdge) {
  if (nearEdge) nearEdge->assign(size_t(camera.width) * size_t(camera.height), 0);
  Timer timer;
  frame.resize(camera.width, camera.height, options.background, resolveThreads(options.threads));
  const CameraSpaceBvh bvh(scene, camera);
  Stats& st = frame.stats;
  st.addTime("build", timer.lap());
  struct RowCounters {
    TraceCounters trace;
    uint64_t covered = 0, fragments = 0, deepest = 0;
  };
  std::vector<RowCounters> rows(size_t(camera.height));
  const TriangleShader shade(scene, camera, options.shading);
  parallelFor(0, size_t(camera.height), resolveThreads(options.threads), [&](size_t y) {
    RowCounters& row = rows[y];
    std::vector<RayHit> hits;
    for (int x = 0; x < camera.width; ++x) {
      hits.clear();
      bvh.allPixelHits(x + 0.5, double(y) + 0.5, options.cull, hits, row.trace);
      if (hits.empty()) continue;
      const size_t idx = frame.index(x, int(y));
      const uint64_t before = row.fragments;
      frame.color[idx] = blendFragments(hits, scene, shade, options.background, row.fragments);  // sorts hits
      if (nearEdge)
        (*nearEdge)[idx] = nearAnEdge(scene, camera, hits, x + 0.5, double(y) + 0.5) ||
                           facesChangeNearby(bvh, scene, options.cull, hits, x + 0.5, double(y) + 0.5, row.trace);
      row.deepest = std::max(row.deepest, row.fragments - before);
      const RayHit& nearest = hits.front();
      frame.faceId[idx] = int32_t(scene.triangles[size_t(nearest.triangle)].face);
      frame.triangleId[idx] = nearest.triangle;
      frame.depth[idx] = float(nearest.t);
      if (!frame.writes.empty()) frame.writes[idx] = 1;
      ++row.covered;
    }
  });
  st.addTime("trace", timer.lap());
  st.triangles_degenerate = bvh.degenerateTriangles();
  uint64_t fragments = 0, deepest = 0;
  for (const RowCounters& row : rows) {
    st.depth_tests += row.trace.tests;
    st.covered_pixels += row.covered;
    fragments += row.fragments;
    deepest = std::max(deepest, row.deepest);
  }
  st.color_writes = st.covered_pixels;
  st.setDetail("fragments", fragments);
  st.setDetail("deepest_pixel", deepest);
  st.addMemory("bvh", bvh.memoryBytes());
  // One pixel's fragments at a time per thread: a list as long as the deepest pixel's, at most.
  st.addMemory("pixel_fragments", deepest * sizeof(RayHit) * uint64_t(resolveThreads(options.threads)));
  addFrameMemory(st, frame);
}

AlgorithmInfo abufferAlgorithm() {
  AlgorithmInfo a;
  a.name = "abuffer";
  a.summary = "A-buffer: every fragment of every pixel, sorted by exact depth, blended front to back in double; "
              "the exact colour reference for transparency";
  a.source = "KTH report, lecture notes";
  a.guarantee.kind = Guarantee::Kind::Exact;
  a.guarantee.condition = "its ids are the reference's nearest fragments";
  a.create = factoryOf<ABuffer>();
  return a;
}

}  // namespace hsr::algo

// Sort keys of faces (sort_keys.hpp).
#include "algorithms/sort_keys.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace hsr::algo {

ParamSpec sortKeyParam(const char* defaultValue, const char* help) {
  return {"sort-key", ParamType::Choice, defaultValue, {"centroid", "max", "min", "mean-vertex"}, -1e300, 1e300, help};
}

SortKey sortKeyOf(const std::string& name) {
  if (name == "max") return SortKey::Max;
  if (name == "min") return SortKey::Min;
  if (name == "mean-vertex") return SortKey::MeanVertex;
  return SortKey::Centroid;
}

namespace {

// The eye depth of a polygon's area centroid: the fan's triangle centroids weighted by their
// areas (in world space); the vertex mean for a polygon of no area.
double centroidDepth(const Scene& scene, const Camera& camera, std::span<const uint32_t> polygon) {
  const dvec3 origin = scene.positions[polygon[0]];
  dvec3 weighted{0.0};
  double total = 0;
  for (size_t i = 1; i + 1 < polygon.size(); ++i) {
    const dvec3 a = scene.positions[polygon[i]] - origin, b = scene.positions[polygon[i + 1]] - origin;
    const double area = glm::length(glm::cross(a, b));
    weighted += area * (a + b) / 3.0;
    total += area;
  }
  dvec3 centre{0.0};
  if (total > 0) {
    centre = origin + weighted / total;
  } else {
    for (uint32_t v : polygon) centre += scene.positions[v];
    centre /= double(polygon.size());
  }
  return camera.toCamera(centre).z;
}

}  // namespace

std::vector<double> faceKeys(const Scene& scene, const Camera& camera, SortKey key) {
  std::vector<double> keys(scene.faceCount());
  for (size_t f = 0; f < keys.size(); ++f) {
    const std::span<const uint32_t> polygon = scene.face(f);
    if (polygon.empty()) continue;
    if (key == SortKey::Centroid) {
      keys[f] = centroidDepth(scene, camera, polygon);
      continue;
    }
    double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
    for (uint32_t v : polygon) {
      const double z = camera.toCamera(scene.positions[v]).z;
      lo = std::min(lo, z);
      hi = std::max(hi, z);
      sum += z;
    }
    keys[f] = key == SortKey::Max ? hi : key == SortKey::Min ? lo : sum / double(polygon.size());
  }
  return keys;
}

std::vector<uint32_t> faceRanks(const std::vector<double>& keys, bool backToFront) {
  // The faces sorted as (key, face) pairs side by side, not as indices reading their keys: the
  // same order, without a cache miss per comparison. NaN keys (a face through the eye's plane in
  // an orthographic view cannot give one; a degenerate face can) sort last either way.
  struct Keyed {
    double key;
    uint32_t face;
  };
  std::vector<Keyed> faces(keys.size());
  for (uint32_t f = 0; f < faces.size(); ++f) faces[f] = {keys[f], f};
  auto before = [backToFront](const Keyed& a, const Keyed& b) {
    if (std::isnan(a.key) || std::isnan(b.key)) return !std::isnan(a.key) && std::isnan(b.key);
    if (a.key != b.key) return backToFront ? a.key > b.key : a.key < b.key;
    return backToFront ? a.face > b.face : a.face < b.face;  // the face submitted first wins a tie
  };
  std::sort(faces.begin(), faces.end(), before);
  std::vector<uint32_t> rank(keys.size());
  for (uint32_t i = 0; i < faces.size(); ++i) rank[faces[i].face] = i;
  return rank;
}

bool depthRangesSeparate(const Scene& scene, const Camera& camera) {
  struct Extent {
    double zMin, zMax, x0, y0, x1, y1;
  };
  const dmat4 pixelFromWorld = camera.pixelFromCamera * camera.cameraFromWorld;
  std::vector<Extent> faces;
  for (size_t f = 0; f < scene.faceCount(); ++f) {
    const std::span<const uint32_t> polygon = scene.face(f);
    if (polygon.size() < 3) continue;
    Extent e{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    for (uint32_t v : polygon) {
      const dvec4 h = pixelFromWorld * dvec4(scene.positions[v], 1.0);  // (hx, hy, d, w)
      if (!(h.z > camera.near && h.z < camera.far && h.w > 0)) return false;  // clipped: not one polygon
      e.zMin = std::min(e.zMin, h.z);
      e.zMax = std::max(e.zMax, h.z);
      e.x0 = std::min(e.x0, h.x / h.w - 1);
      e.y0 = std::min(e.y0, h.y / h.w - 1);
      e.x1 = std::max(e.x1, h.x / h.w + 1);
      e.y1 = std::max(e.y1, h.y / h.w + 1);
    }
    faces.push_back(e);
  }
  std::sort(faces.begin(), faces.end(), [](const Extent& a, const Extent& b) { return a.zMin < b.zMin; });
  for (size_t i = 0; i < faces.size(); ++i)
    for (size_t j = i + 1; j < faces.size() && faces[j].zMin <= faces[i].zMax; ++j)
      if (faces[i].x0 <= faces[j].x1 && faces[j].x0 <= faces[i].x1 && faces[i].y0 <= faces[j].y1 &&
          faces[j].y0 <= faces[i].y1)
        return false;
  return true;
}

std::vector<uint32_t> transparentLast(const Scene& scene, const Camera& camera, const std::vector<uint32_t>& opaqueRank,
                                      SortKey key) {
  const std::vector<uint32_t> backToFront = faceRanks(faceKeys(scene, camera, key), /*backToFront=*/true);
  const uint32_t faces = uint32_t(scene.faceCount());
  std::vector<uint32_t> rank(faces);
  for (uint32_t f = 0; f < faces; ++f) rank[f] = scene.faceColors[f].a == 255 ? opaqueRank[f] : faces + backToFront[f];
  return rank;
}

OrderFn byFaceRank(std::vector<uint32_t> rank, std::vector<SetupTriangle>* scratch) {
  return [rank = std::move(rank), scratch](std::vector<SetupTriangle>& tris) {
    // A stable counting sort by rank: linear, each record moved once.
    std::vector<uint32_t> start(rank.empty() ? 1 : *std::max_element(rank.begin(), rank.end()) + 2, 0);
    for (const SetupTriangle& t : tris) ++start[rank[t.face] + 1];
    for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
    std::vector<SetupTriangle> local;
    std::vector<SetupTriangle>& sorted = scratch ? *scratch : local;
    sorted.resize(tris.size());
    for (const SetupTriangle& t : tris) sorted[start[rank[t.face]]++] = t;
    tris.swap(sorted);
  };
}

}  // namespace hsr::algo

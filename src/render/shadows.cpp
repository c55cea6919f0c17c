// Shadow mapping and its exact reference (include/hsr/shadows.hpp, docs/shadows.md): the light's
// cameras (one fitted to the scene, or one per cascade fitted to the receivers a depth slice of the
// view sees), the maps rendered by the z-buffer from them, each visible pixel tested against its
// map or by a shadow ray through the ray caster's BVH. Rows of the view run in parallel, each
// writing only its own pixels and counts, so any thread count gives the same mask.
#include <hsr/shadows.hpp>

#include <hsr/render.hpp>

#include "algorithms/bvh.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace hsr {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A point light farther out than this leaves the map's eye depths (floats) no precision.
constexpr double kMaxLightCoordinate = 1e30;

bool finite(const dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// v / |v|, scaled first so that tiny and huge (finite, non-zero) vectors normalize too.
dvec3 unit(const dvec3& v) {
  const double m = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  return glm::normalize(v / m);
}

std::string formatVec(const dvec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "%g,%g,%g", v.x, v.y, v.z);
  return text;
}

// --- The light's camera ------------------------------------------------------------------------

// An orthonormal frame whose third axis is `forward`: rows of a camera-from-world rotation in
// OpenCV axes (x right, y down, z forward). The up hint is the world axis least along forward.
void lightAxes(const dvec3& forward, dvec3 rows[3]) {
  const dvec3 f = unit(forward);
  const dvec3 a = glm::abs(f);
  const dvec3 up = a.x <= a.y && a.x <= a.z ? dvec3(1, 0, 0) : a.y <= a.z ? dvec3(0, 1, 0) : dvec3(0, 0, 1);
  const dvec3 s = glm::normalize(glm::cross(f, up));
  const dvec3 u = glm::cross(s, f);
  rows[0] = s;
  rows[1] = -u;
  rows[2] = f;
}

std::array<dvec3, 8> corners(const Bounds3& b) {
  std::array<dvec3, 8> c;
  for (int i = 0; i < 8; ++i) c[size_t(i)] = {i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z};
  return c;
}

dmat4 cameraFromWorld(const dvec3 rows[3], const dvec3& origin) {
  dmat4 m(1.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m[c][r] = rows[r][c];
    m[3][r] = -glm::dot(rows[r], origin);
  }
  return m;
}

// A range [lo, hi] widened to at least `least` (a flat scene seen edge-on still gets a map).
void widen(double& lo, double& hi, double least) {
  if (hi - lo >= least) return;
  const double mid = 0.5 * (lo + hi);
  lo = mid - 0.5 * least;
  hi = mid + 0.5 * least;
}

// Where maps are framed: the light's axes and, for a point light, its position. A map's box is
// given in the light's coordinates of a point: (x, y, z) along the axes for a directional light;
// the tangents x/z, y/z and the depth z from the position for a point light (all positive there:
// the scene's bounds lie in front of it).
struct LightSpace {
  dvec3 rows[3];
  dvec3 origin{0.0};
  bool perspective = false;
  double sceneDiagonal = 0;

  dvec3 coords(const dvec3& p) const {
    const dvec3 q{glm::dot(rows[0], p - origin), glm::dot(rows[1], p - origin), glm::dot(rows[2], p - origin)};
    return perspective ? dvec3(q.x / q.z, q.y / q.z, q.z) : q;
  }
  // The box of `b`'s corners (their coordinates bound those of every point inside).
  Bounds3 box(const Bounds3& b) const {
    Bounds3 out;
    for (const dvec3& c : corners(b)) out.add(coords(c));
    return out;
  }
};

// Orthographic along the direction the light travels, `box` filling the map but a texel at each
// side.
Camera directionalCamera(const LightSpace& space, const Bounds3& box, int n) {
  const double diag = space.sceneDiagonal;
  dvec3 lo = box.lo, hi = box.hi;
  for (int r = 0; r < 3; ++r) widen(lo[r], hi[r], 1e-9 * diag);
  const double margin = 0.01 * (hi.z - lo.z) + 1e-6 * diag;  // depth room in front and behind

  Camera cam;
  cam.width = cam.height = n;
  cam.orthographic = true;
  cam.cameraFromWorld = cameraFromWorld(space.rows, dvec3(0.0));
  cam.cameraFromWorld[3][2] = margin - lo.z;  // z = forward . p - lo.z + margin
  const double kx = (n - 2) / (hi.x - lo.x), ky = (n - 2) / (hi.y - lo.y);
  dmat4 pix(0.0);  // pix[col][row]
  pix[0][0] = kx;
  pix[3][0] = 1 - kx * lo.x;
  pix[1][1] = ky;
  pix[3][1] = 1 - ky * lo.y;
  pix[2][2] = 1;
  pix[3][3] = 1;
  cam.pixelFromCamera = pix;
  cam.near = 0.5 * margin;
  cam.far = hi.z - lo.z + 1.5 * margin;
  return cam;
}

// The largest tangent a point light's view may need: a 160-degree view.
constexpr double kMaxTangent = 5.6712818196177066;  // tan(80 degrees)

struct Frustum {
  dvec3 rows[3];
  dvec3 lo{kInf}, hi{-kInf};  // tangents x/z, y/z and depth z of the corners
  bool fits = false;
  double widest() const { return std::max({-lo.x, hi.x, -lo.y, hi.y}); }
};

Frustum frustumAlong(const Bounds3& bounds, const dvec3& position, const dvec3& forward) {
  Frustum fr;
  if (!(glm::length(forward) > 0) || !finite(forward)) return fr;
  lightAxes(forward, fr.rows);
  for (const dvec3& c : corners(bounds)) {
    const dvec3 q{glm::dot(fr.rows[0], c - position), glm::dot(fr.rows[1], c - position),
                  glm::dot(fr.rows[2], c - position)};
    if (!(q.z > 0)) return fr;
    fr.lo = glm::min(fr.lo, dvec3(q.x / q.z, q.y / q.z, q.z));
    fr.hi = glm::max(fr.hi, dvec3(q.x / q.z, q.y / q.z, q.z));
  }
  fr.fits = fr.widest() <= kMaxTangent && fr.lo.z > 1e-6 * fr.hi.z;
  return fr;
}

// A point light's axes, looking toward the bounds (at their centre, or along the mean direction
// of their corners when that frames them more tightly).
void pointAxes(const Bounds3& bounds, const dvec3& position, dvec3 rows[3]) {
  if (glm::all(glm::greaterThanEqual(position, bounds.lo)) && glm::all(glm::lessThanEqual(position, bounds.hi)))
    throw InputError("light position " + formatVec(position) +
                     " lies inside the scene's bounds: one perspective shadow map cannot see the whole scene "
                     "from there (place the light outside, or use a directional light)");
  dvec3 mean(0.0);
  for (const dvec3& c : corners(bounds)) mean += glm::normalize(c - position);
  Frustum fr = frustumAlong(bounds, position, bounds.center() - position);
  const Frustum other = frustumAlong(bounds, position, mean);
  if (other.fits && (!fr.fits || other.widest() < fr.widest())) fr = other;
  if (!fr.fits)
    throw InputError("light position " + formatVec(position) +
                     " is so close to the scene that its bounds do not fit in a 160-degree view (move the light "
                     "farther away, or use a directional light)");
  for (int r = 0; r < 3; ++r) rows[r] = fr.rows[r];
}

// Perspective from a point light, `box` (tangents and depths) filling the map but a texel at each
// side.
Camera pointCamera(const LightSpace& space, const Bounds3& box, int n) {
  dvec3 lo = box.lo, hi = box.hi;
  widen(lo.x, hi.x, 1e-9);
  widen(lo.y, hi.y, 1e-9);

  Camera cam;
  cam.width = cam.height = n;
  cam.orthographic = false;
  cam.cameraFromWorld = cameraFromWorld(space.rows, space.origin);
  const double kx = (n - 2) / (hi.x - lo.x), ky = (n - 2) / (hi.y - lo.y);
  dmat4 pix(0.0);  // hx = kx x + (1 - kx lo.x) z, w = z
  pix[0][0] = kx;
  pix[2][0] = 1 - kx * lo.x;
  pix[1][1] = ky;
  pix[2][1] = 1 - ky * lo.y;
  pix[2][2] = 1;
  pix[2][3] = 1;
  cam.pixelFromCamera = pix;
  cam.near = 0.99 * lo.z;
  cam.far = 1.01 * hi.z;
  return cam;
}

Camera mapCamera(const LightSpace& space, const Bounds3& box, int n) {
  return space.perspective ? pointCamera(space, box, n) : directionalCamera(space, box, n);
}

// --- Visible points ----------------------------------------------------------------------------

// The surface a view pixel shows: its world point and the unit normal of its plane turned toward
// the viewer.
struct Receiver {
  dvec3 point, normal;
};

class ReceiverFinder {
 public:
  ReceiverFinder(const Scene& scene, const Camera& view, const Frame& frame)
      : scene_(scene), view_(view), frame_(frame), worldFromCamera_(glm::inverse(view.cameraFromWorld)) {
    if (frame.triangleId.size() != size_t(frame.width) * size_t(frame.height))
      throw InputError("shadows: the frame has no triangle ids (render it with triangle ids)");
  }

  // False for a background pixel.
  bool find(int x, int y, Receiver& r) const {
    const size_t idx = frame_.index(x, y);
    const int32_t tri = frame_.triangleId[idx];
    if (tri < 0) return false;
    dvec3 o, d;
    view_.cameraRay(x + 0.5, y + 0.5, o, d);
    o = dvec3(worldFromCamera_ * dvec4(o, 1.0));
    d = dmat3(worldFromCamera_) * d;
    const Triangle& t = scene_.triangles[size_t(tri)];
    const dvec3& v0 = scene_.positions[t.v[0]];
    dvec3 n = glm::cross(scene_.positions[t.v[1]] - v0, scene_.positions[t.v[2]] - v0);
    const double nd = glm::dot(n, d);
    // The view ray's parameter is the eye depth (dir.z == 1): the frame's depth where the ray
    // runs along the plane.
    const double s = nd != 0 ? glm::dot(n, v0 - o) / nd : double(frame_.depth[idx]);
    r.point = o + (std::isfinite(s) ? s : double(frame_.depth[idx])) * d;
    const double len = glm::length(n);
    n = len > 0 ? n / len : -glm::normalize(d);
    r.normal = glm::dot(n, d) > 0 ? -n : n;
    return true;
  }

 private:
  const Scene& scene_;
  const Camera& view_;
  const Frame& frame_;
  dmat4 worldFromCamera_;
};

// The direction from `p` toward the light (not normalized for a point light: its length is the
// distance to it).
dvec3 towardLight(const Light& light, const dvec3& p) {
  return light.kind == Light::Kind::Directional ? -unit(light.vector) : light.vector - p;
}

// The facing rule: the side the viewer sees faces the light.
bool facesLight(const Receiver& r, const Light& light) { return glm::dot(r.normal, towardLight(light, r.point)) > 0; }

// --- Testing against the map -------------------------------------------------------------------

class MapTest {
 public:
  MapTest(const Camera& lightCam, const FrameBuffer<float>& depth, DepthFormat format, double bias)
      : cam_(lightCam), depth_(depth), format_(format), rotation_(dmat3(lightCam.cameraFromWorld)), bias_(bias) {
    const dmat4& M = lightCam.pixelFromCamera;
    texelPerUnit_ = std::min(M[0][0], M[1][1]);  // the wider texel side, per unit of x/z or x
  }

  // Whether the map puts something nearer the light than the receiver's plane at the centre of
  // the texel the receiver falls in, by more than the bias.
  bool shadowed(const Receiver& r, uint32_t& texel) const {
    const dvec3 p = cam_.toCamera(r.point);
    const dvec4 h = cam_.pixelFromCamera * dvec4(p, 1.0);
    const int n = cam_.width;
    const int ix = std::clamp(int(std::floor(h.x / h.w)), 0, n - 1);
    const int iy = std::clamp(int(std::floor(h.y / h.w)), 0, n - 1);
    texel = uint32_t(iy) * uint32_t(n) + uint32_t(ix);
    const double mapDepth = depth_[texel];
    const double texelWidth = (cam_.orthographic ? 1.0 : p.z) / texelPerUnit_;
    return mapDepth < planeDepthAtTexel(r, p, ix, iy) - bias_ * texelWidth - rounding(p.z);
  }

 private:
  // What the map's depth may be off by at eye depth z: two steps of its storage there, mapped
  // back to eye depth, and the rounding of eye depth to float.
  double rounding(double z) const {
    const double n = cam_.near, f = cam_.far, h = 1e-6 * (f - n);
    const double lo = std::max(n, z - h), hi = std::min(f, z + h);
    const double slope = std::abs(format_.map(hi, n, f, cam_.orthographic) - format_.map(lo, n, f, cam_.orthographic)) /
                         (hi - lo);
    const double step = format_.resolution(format_.map(z, n, f, cam_.orthographic));
    return (slope > 0 ? 2 * step / slope : 0) + std::abs(z) * 0x1p-22;
  }

  // The light-space depth of the receiver's plane along the light ray through texel (ix, iy)'s
  // centre; the receiver's own depth where that ray runs along or away from the plane.
  double planeDepthAtTexel(const Receiver& r, const dvec3& p, int ix, int iy) const {
    dvec3 o, d;
    cam_.cameraRay(ix + 0.5, iy + 0.5, o, d);
    const dvec3 n = rotation_ * r.normal;
    const double nd = glm::dot(n, d);
    if (!(nd < 0)) return p.z;  // (a receiver facing the light has its normal against the light's rays)
    const double z = o.z + glm::dot(n, p - o) / nd;
    return std::isfinite(z) ? z : p.z;
  }

  const Camera& cam_;
  const FrameBuffer<float>& depth_;
  DepthFormat format_;
  dmat3 rotation_;
  double bias_;
  double texelPerUnit_;
};

template <class Classify>
std::vector<ShadowMask> classifyPixels(const Frame& frame, int threads, Classify&& classify) {
  std::vector<ShadowMask> mask(size_t(frame.width) * size_t(frame.height), ShadowMask::Background);
  parallelFor(0, size_t(frame.height), resolveThreads(threads), [&](size_t y) {
    for (int x = 0; x < frame.width; ++x) mask[frame.index(x, int(y))] = classify(x, int(y));
  });
  return mask;
}

// A relative 1e-9 of the scene's size and distance from the origin: far above the rounding of a
// reconstructed point (about 1e-16 of it), far below any gap a scene means.
double selfHitOffset(const Bounds3& b) {
  if (b.empty()) return 0;
  const double extent = glm::length(b.hi - b.lo);
  const double reach = std::max(glm::length(b.lo), glm::length(b.hi));
  return 1e-9 * (extent + reach);
}

bool uniform3x3(int x, int y, int w, int h, auto&& value) {
  const auto centre = value(x, y);
  for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
    for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx)
      if (!(value(xx, yy) == centre)) return false;
  return true;
}

// Per texel of the maps that some receiver falls in: which reference verdicts and faces its
// receivers have; a texel is at an edge when its 3x3 neighbourhood in its own map holds both lit
// and shadowed receivers (a shadow boundary passes within a texel as the light sees it) or
// receivers of more than one face, or the light sees more than one face there (`lightFaces`: per
// map, the faces it sees).
class TexelEdges {
 public:
  TexelEdges(const Frame& frame, const ShadowResult& map, const std::vector<ShadowMask>& reference,
             const std::vector<Frame>& lightFaces)
      : side_(map.lightCameras.empty() ? 1u : uint32_t(map.lightCameras[0].width)), lightFaces_(lightFaces) {
    const bool faces = frame.faceId.size() == reference.size();
    for (size_t i = 0; i < reference.size(); ++i)
      if (map.texel[i] != kNoTexel)
        entries_.push_back({map.texel[i], faces ? frame.faceId[i] : 0, uint8_t(1u << uint8_t(reference[i])), false});
    std::sort(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) { return a.texel < b.texel; });
    // One entry per texel: its verdicts ORed, and whether its receivers show several faces.
    size_t out = 0;
    for (size_t i = 0; i < entries_.size(); ++i) {
      if (out > 0 && entries_[out - 1].texel == entries_[i].texel) {
        Entry& e = entries_[out - 1];
        e.verdicts |= entries_[i].verdicts;
        e.severalFaces = e.severalFaces || e.face != entries_[i].face;
      } else {
        entries_[out++] = entries_[i];
      }
    }
    entries_.resize(out);
  }

  bool nearEdge(uint32_t texel) const {
    if (texel == kNoTexel) return false;
    const uint32_t area = side_ * side_, first = texel / area * area, local = texel % area;
    const FrameBuffer<int32_t>& seen = lightFaces_[texel / area].faceId;
    const int64_t tx = local % side_, ty = local / side_;
    uint8_t verdicts = 0;
    int32_t face = -2;
    for (int64_t y = std::max<int64_t>(0, ty - 1); y <= std::min<int64_t>(side_ - 1, ty + 1); ++y)
      for (int64_t x = std::max<int64_t>(0, tx - 1); x <= std::min<int64_t>(side_ - 1, tx + 1); ++x) {
        const uint32_t t = first + uint32_t(y) * side_ + uint32_t(x);
        if (seen[t - first] != seen[local]) return true;
        auto it = std::lower_bound(entries_.begin(), entries_.end(), t,
                                   [](const Entry& e, uint32_t value) { return e.texel < value; });
        if (it == entries_.end() || it->texel != t) continue;
        verdicts |= it->verdicts;
        if (it->severalFaces || (face != -2 && it->face != face)) return true;
        face = it->face;
      }
    const uint8_t litAndShadowed = uint8_t(1u << uint8_t(ShadowMask::Lit)) | uint8_t(1u << uint8_t(ShadowMask::Shadowed));
    return (verdicts & litAndShadowed) == litAndShadowed;
  }

 private:
  struct Entry {
    uint32_t texel;
    int32_t face;
    uint8_t verdicts;
    bool severalFaces;
  };
  uint32_t side_;
  const std::vector<Frame>& lightFaces_;
  std::vector<Entry> entries_;
};

}  // namespace

void checkLight(const Light& light, const std::string& what) {
  if (!finite(light.vector)) throw InputError(what + ": the light's " +
                                              (light.kind == Light::Kind::Directional ? "direction" : "position") +
                                              " must be finite");
  if (light.kind == Light::Kind::Point && glm::any(glm::greaterThan(glm::abs(light.vector), dvec3(kMaxLightCoordinate))))
    throw InputError(what + ": the light's position has a coordinate beyond 1e30 in magnitude");
  if (light.kind == Light::Kind::Directional && light.vector == dvec3(0.0))
    throw InputError(what + ": the light's direction is zero");
}

Light defaultLight(const Camera& view) {
  const dvec3 travelInView = glm::normalize(dvec3(0.5, 0.8, 0.6));  // right, down, away
  Light light;
  light.kind = Light::Kind::Directional;
  light.vector = glm::transpose(dmat3(view.cameraFromWorld)) * travelInView;
  return light;
}

std::string describeLight(const Light& light) {
  return std::string(light.kind == Light::Kind::Directional ? "directional " : "point ") + formatVec(light.vector);
}

namespace {

// Both the options and a light camera made directly check the map size the same way.
void checkMapSize(int mapSize) {
  if (mapSize < kMinShadowMapSize || mapSize > kMaxShadowMapSize)
    throw InputError(Setting::ShadowMapSize, std::to_string(mapSize),
                     "must be " + std::to_string(kMinShadowMapSize) + " to " + std::to_string(kMaxShadowMapSize));
}

// The light's space for a scene of `sceneBounds` (InputError for a bad light or bounds).
LightSpace lightSpace(const Bounds3& sceneBounds, const Light& light) {
  checkLight(light, "shadows");
  if (sceneBounds.empty() || !finite(sceneBounds.lo) || !finite(sceneBounds.hi))
    throw InputError("shadows: the scene has no geometry to frame a shadow map around");
  if (!(glm::length(sceneBounds.hi - sceneBounds.lo) > 0))
    throw InputError("shadows: the scene is a single point: no shadow map can be framed around it");
  LightSpace space;
  space.sceneDiagonal = glm::length(sceneBounds.hi - sceneBounds.lo);
  space.perspective = light.kind == Light::Kind::Point;
  if (space.perspective) {
    pointAxes(sceneBounds, light.vector, space.rows);
    space.origin = light.vector;
  } else {
    lightAxes(light.vector, space.rows);
  }
  return space;
}

}  // namespace

Camera lightCamera(const Bounds3& sceneBounds, const Light& light, int mapSize) {
  checkLight(light, "shadows");  // (before the size, as lightSpace checks it again)
  checkMapSize(mapSize);
  const LightSpace space = lightSpace(sceneBounds, light);
  return mapCamera(space, space.box(sceneBounds), mapSize);
}

const char* shadowMethodName(ShadowMethod method) {
  return method == ShadowMethod::Single ? "single" : "cascaded";
}

ShadowMethod parseShadowMethod(const std::string& name, const std::string& what) {
  for (ShadowMethod m : {ShadowMethod::Single, ShadowMethod::Cascaded})
    if (name == shadowMethodName(m)) return m;
  throw InputError(what + " '" + name + "': expected single or cascaded");
}

void checkShadowOptions(const ShadowOptions& o) {
  checkMapSize(o.mapSize);
  if (!std::isfinite(o.bias) || o.bias < 0)
    throw InputError(Setting::ShadowBias, "", "must be a finite number of texels, 0 or more");
  if (!std::isfinite(o.ambient) || o.ambient < 0 || o.ambient > 1)
    throw InputError("shadows: the ambient factor must be in [0, 1]");
  if (o.method != ShadowMethod::Single && o.method != ShadowMethod::Cascaded)
    throw InputError("shadows: unknown shadow method");
  if (o.method == ShadowMethod::Cascaded) {
    if (o.cascades < 1 || o.cascades > kMaxShadowCascades)
      throw InputError("shadows: the cascade count " + std::to_string(o.cascades) + " must be 1 to " +
                       std::to_string(kMaxShadowCascades));
    // Texel numbers (ShadowResult::texel) run over all the maps in 32 bits.
    if (uint64_t(o.cascades) * uint64_t(o.mapSize) * uint64_t(o.mapSize) >= uint64_t(kNoTexel))
      throw InputError("shadows: " + std::to_string(o.cascades) + " cascades of " + std::to_string(o.mapSize) +
                       "x" + std::to_string(o.mapSize) + " texels are 2^32 texels or more (use fewer or smaller maps)");
  }
}

namespace {

// The practical split scheme's blend of its two splits: 1 is logarithmic (each slice as deep,
// relative to its distance, as the next), 0 uniform.
constexpr double kSplitBlend = 0.75;
// ShadowSlices::of for a pixel no map tests (background).
constexpr uint8_t kNoSlice = 0xff;

// The eye depths bounding K slices of [nearest, farthest]: slice i ends at
// blend * n (f/n)^(i/K) + (1 - blend) (n + (f - n) i/K); uniform when n is not positive.
std::vector<double> practicalSplits(double nearest, double farthest, int k) {
  std::vector<double> splits(size_t(k) + 1);
  for (int i = 0; i <= k; ++i) {
    const double t = double(i) / k;
    const double uniform = nearest + (farthest - nearest) * t;
    splits[size_t(i)] = nearest > 0 ? kSplitBlend * nearest * std::pow(farthest / nearest, t) + (1 - kSplitBlend) * uniform
                                    : uniform;
  }
  splits.front() = nearest;
  splits.back() = farthest;
  return splits;
}

// Which map tests each visible pixel, and the maps' cameras.
struct ShadowSlices {
  std::vector<uint8_t> of;  // per pixel: the index of its map in `cameras`, or kNoSlice
  std::vector<Camera> cameras;
  std::vector<double> splits;  // cascaded: the slices' bounding eye depths
};

// The single method: every visible pixel tested against one map of the whole scene.
ShadowSlices singleSlice(const Frame& frame, const LightSpace& space, const Bounds3& sceneBounds, int mapSize) {
  ShadowSlices out;
  out.cameras.push_back(mapCamera(space, space.box(sceneBounds), mapSize));
  out.of.resize(frame.triangleId.size());
  for (size_t i = 0; i < out.of.size(); ++i) out.of[i] = frame.triangleId[i] >= 0 ? 0 : kNoSlice;
  return out;
}

// The cascaded method: the visible depth range split into `cascades` slices, each pixel in the
// slice its eye depth falls in, and each slice's map fitted to the light-space box of its
// receivers, reaching from them toward the light as far as the scene's bounds (what casts on
// them). Slices without receivers get no map.
ShadowSlices cascadedSlices(const Frame& frame, const ReceiverFinder& finder, const LightSpace& space,
                            const Bounds3& sceneBounds, const ShadowOptions& options) {
  ShadowSlices out;
  out.of.assign(frame.triangleId.size(), kNoSlice);
  double nearest = kInf, farthest = -kInf;
  for (size_t i = 0; i < frame.triangleId.size(); ++i)
    if (frame.triangleId[i] >= 0) {
      nearest = std::min(nearest, double(frame.depth[i]));
      farthest = std::max(farthest, double(frame.depth[i]));
    }
  if (!(nearest <= farthest)) return out;  // nothing visible: no maps
  const int k = options.cascades;
  out.splits = practicalSplits(nearest, farthest, k);

  // Per row and slice, the box of the receivers' light coordinates (min and max: the same
  // whatever the order rows are combined in).
  const size_t rows = size_t(frame.height);
  std::vector<Bounds3> rowBoxes(rows * size_t(k));
  parallelFor(0, rows, resolveThreads(options.threads), [&](size_t y) {
    for (int x = 0; x < frame.width; ++x) {
      const size_t idx = frame.index(x, int(y));
      Receiver r;
      if (!finder.find(x, int(y), r)) continue;
      const auto it = std::upper_bound(out.splits.begin() + 1, out.splits.end() - 1, double(frame.depth[idx]));
      const size_t slice = size_t(it - (out.splits.begin() + 1));
      out.of[idx] = uint8_t(slice);
      rowBoxes[y * size_t(k) + slice].add(space.coords(r.point));
    }
  });
  const Bounds3 sceneBox = space.box(sceneBounds);
  std::vector<uint8_t> mapOf(size_t(k), kNoSlice);
  std::vector<double> splits{out.splits.front()};
  for (size_t slice = 0; slice < size_t(k); ++slice) {
    Bounds3 receivers;
    for (size_t y = 0; y < rows; ++y) receivers.add(rowBoxes[y * size_t(k) + slice]);
    if (receivers.empty()) continue;
    Bounds3 box = receivers;
    box.lo.z = std::min(box.lo.z, sceneBox.lo.z);  // the casters between the receivers and the light
    mapOf[slice] = uint8_t(out.cameras.size());
    out.cameras.push_back(mapCamera(space, box, options.mapSize));
    splits.push_back(out.splits[slice + 1]);
  }
  out.splits = splits;  // the bounds of the slices that have maps
  for (uint8_t& s : out.of)
    if (s != kNoSlice) s = mapOf[s];
  return out;
}

}  // namespace

ShadowResult shadowMap(const Scene& scene, const Camera& view, const Frame& frame, const Light& light,
                       const ShadowOptions& options) {
  checkShadowOptions(options);
  const ReceiverFinder finder(scene, view, frame);
  const LightSpace space = lightSpace(scene.bounds(), light);
  ShadowResult result;
  Timer timer;
  ShadowSlices slices = options.method == ShadowMethod::Single
                            ? singleSlice(frame, space, scene.bounds(), options.mapSize)
                            : cascadedSlices(frame, finder, space, scene.bounds(), options);
  result.fitMs = timer.lap();
  result.lightCameras = std::move(slices.cameras);
  result.splits = std::move(slices.splits);

  RenderOptions mapOptions;
  mapOptions.algorithm = "zbuffer";
  mapOptions.outputs = FrameOutputs::DepthOnly;
  mapOptions.depthFormat = options.depthFormat;
  mapOptions.cull = Cull::None;
  mapOptions.threads = options.threads;
  result.mask.assign(size_t(frame.width) * size_t(frame.height), ShadowMask::Background);
  result.texel.assign(result.mask.size(), kNoTexel);
  const uint32_t area = uint32_t(options.mapSize) * uint32_t(options.mapSize);
  // Per row, the lit, shadowed and facing-away pixels: each row counts its own, summed after.
  std::vector<std::array<uint64_t, 3>> rowCounts(size_t(frame.height), {0, 0, 0});
  // One map at a time: rendered by the same z-buffer from the light, depth only, then the pixels
  // it serves tested against it, each row writing only its own pixels.
  for (size_t m = 0; m < result.lightCameras.size(); ++m) {
    const Camera& cam = result.lightCameras[m];
    timer.lap();
    const Frame map = render(scene, cam, mapOptions);
    result.mapMs += timer.lap();
    result.mapBytes = std::max<uint64_t>(result.mapBytes, map.stats.memory_bytes ? map.stats.memory_bytes
                                                                                  : map.depth.size() * sizeof(float));
    const MapTest test(cam, map.depth, options.depthFormat, options.bias);
    parallelFor(0, size_t(frame.height), resolveThreads(options.threads), [&](size_t y) {
      for (int x = 0; x < frame.width; ++x) {
        const size_t idx = frame.index(x, int(y));
        if (slices.of[idx] != m) continue;
        Receiver r;
        if (!finder.find(x, int(y), r)) continue;
        uint32_t texel = 0;
        const bool occluded = test.shadowed(r, texel), faces = facesLight(r, light);
        result.texel[idx] = uint32_t(m) * area + texel;
        result.mask[idx] = !occluded && faces ? ShadowMask::Lit : ShadowMask::Shadowed;
        ++rowCounts[y][!occluded && faces ? 0 : 1];
        rowCounts[y][2] += !faces;
      }
    });
    result.testMs += timer.lap();
  }
  for (const auto& [lit, shadowed, facingAway] : rowCounts) {
    result.lit += lit;
    result.shadowed += shadowed;
    result.facingAway += facingAway;
  }
  return result;
}

std::vector<ShadowMask> shadowRays(const Scene& scene, const Camera& view, const Frame& frame, const Light& light,
                                   int threads) {
  checkLight(light, "shadows");
  const ReceiverFinder finder(scene, view, frame);
  const Camera world;  // identity: the BVH in world space
  const algo::CameraSpaceBvh bvh(scene, world);
  const double offset = selfHitOffset(scene.bounds());
  return classifyPixels(frame, threads, [&](int x, int y) {
    Receiver r;
    if (!finder.find(x, y, r)) return ShadowMask::Background;
    if (!facesLight(r, light)) return ShadowMask::Shadowed;
    const dvec3 origin = r.point + offset * r.normal;
    const dvec3 dir = towardLight(light, origin);
    // A directional light is infinitely far; a point light at t = 1 along origin + t dir.
    const double tMax = light.kind == Light::Kind::Directional ? kInf : 1.0;
    algo::TraceCounters counters;
    const algo::RayHit hit = bvh.closestHit(algo::WatertightRay(origin, dir), 0.0, tMax, Cull::None, counters);
    return hit.found() ? ShadowMask::Shadowed : ShadowMask::Lit;
  });
}

ShadowComparison compareShadowMasks(const Scene& scene, const Frame& frame, const ShadowResult& map,
                                    const std::vector<ShadowMask>& reference, const ShadowOptions& options) {
  const size_t n = size_t(frame.width) * size_t(frame.height);
  if (map.mask.size() != n || reference.size() != n || map.texel.size() != n)
    throw std::invalid_argument("compareShadowMasks: masks and frame differ in size");
  const bool faces = frame.faceId.size() == n;
  auto refAt = [&](int x, int y) { return reference[frame.index(x, y)]; };
  auto faceAt = [&](int x, int y) { return frame.faceId[frame.index(x, y)]; };
  RenderOptions faceOptions;  // the maps again, with the faces the light sees
  faceOptions.algorithm = "zbuffer";
  faceOptions.outputs = FrameOutputs::FaceIds;
  faceOptions.depthFormat = options.depthFormat;
  faceOptions.threads = options.threads;
  std::vector<Frame> lightFaces;
  for (const Camera& cam : map.lightCameras) lightFaces.push_back(render(scene, cam, faceOptions));
  const TexelEdges texelEdges(frame, map, reference, lightFaces);
  ShadowComparison c;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const size_t i = frame.index(x, y);
      const bool shadowEdge = !uniform3x3(x, y, frame.width, frame.height, refAt);
      const bool faceEdge = faces && !uniform3x3(x, y, frame.width, frame.height, faceAt);
      c.shadowEdgePixels += shadowEdge;
      c.faceEdgePixels += faceEdge;
      if (map.mask[i] == reference[i]) continue;
      ++c.wrong;
      if (shadowEdge) continue;
      ++c.wrongAwayFromShadowEdges;
      if (faceEdge) continue;
      ++c.wrongAwayFromEdges;
      if (c.firstWrongAwayFromEdges.size() < 16) c.firstWrongAwayFromEdges.emplace_back(x, y);
      if (texelEdges.nearEdge(map.texel[i])) continue;
      ++c.wrongUnexplained;
      if (c.firstUnexplained.size() < 16) c.firstUnexplained.emplace_back(x, y);
    }
  return c;
}

void darkenShadowed(Frame& frame, const std::vector<ShadowMask>& mask, double ambient) {
  if (frame.color.size() != mask.size()) return;
  auto scale = [ambient](uint8_t c) { return uint8_t(std::lround(double(c) * ambient)); };
  for (size_t i = 0; i < mask.size(); ++i) {
    if (mask[i] != ShadowMask::Shadowed) continue;
    Rgba8& c = frame.color[i];
    c = {scale(c.r), scale(c.g), scale(c.b), c.a};
  }
}

void addShadowTimes(Stats& stats, const ShadowResult& result, const ShadowOptions& options) {
  if (options.method == ShadowMethod::Cascaded) stats.addTime("shadow_fit", result.fitMs);
  stats.addTime("shadow_map", result.mapMs);
  stats.addTime("shadow_test", result.testMs);
}

ShadowComparison addShadows(const Scene& scene, const Camera& view, Frame& frame, const Light& light,
                            const ShadowOptions& options, bool verify) {
  ShadowResult result = shadowMap(scene, view, frame, light, options);
  darkenShadowed(frame, result.mask, options.ambient);
  Stats& st = frame.stats;
  addShadowTimes(st, result, options);
  st.addMemory("shadow_map", result.mapBytes);
  st.addMemory("shadow_mask", result.mask.size() * sizeof(ShadowMask));
  st.setDetail("shadow_light", describeLight(light));
  st.setDetail("shadow_method", std::string(shadowMethodName(options.method)));
  st.setDetail("shadow_maps", uint64_t(result.lightCameras.size()));
  st.setDetail("shadow_map_size", uint64_t(options.mapSize));
  st.setDetail("shadow_bias_texels", options.bias);
  st.setDetail("shadow_lit_pixels", result.lit);
  st.setDetail("shadow_shadowed_pixels", result.shadowed);
  st.setDetail("shadow_facing_away_pixels", result.facingAway);
  ShadowComparison comparison;
  if (!verify) return comparison;
  Timer timer;
  const std::vector<ShadowMask> reference = shadowRays(scene, view, frame, light, options.threads);
  comparison = compareShadowMasks(scene, frame, result, reference, options);
  st.addTime("shadow_verify", timer.ms());
  st.setDetail("shadow_wrong_pixels", comparison.wrong);
  st.setDetail("shadow_wrong_away_from_shadow_edges", comparison.wrongAwayFromShadowEdges);
  st.setDetail("shadow_wrong_away_from_edges", comparison.wrongAwayFromEdges);
  st.setDetail("shadow_wrong_unexplained", comparison.wrongUnexplained);
  st.setDetail("shadow_edge_pixels", comparison.shadowEdgePixels);
  st.setDetail("shadow_face_edge_pixels", comparison.faceEdgePixels);
  return comparison;
}

}  // namespace hsr

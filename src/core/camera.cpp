// Camera specs (JSON, automatic framing) and their resolution into a Camera for one image size.
// Consumed by every algorithm through Camera (include/hsr/camera.hpp), and by the CLI.
#include <hsr/camera.hpp>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/json_util.hpp"

namespace hsr {
namespace {

using json = nlohmann::json;

bool finite(const dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

dvec3 readVec3(const json& j, const char* key, const std::string& src) {
  const json& a = j.at(key);
  if (!a.is_array() || a.size() != 3) throw InputError(src + ": camera: '" + key + "' must be an array of 3 numbers");
  dvec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!a[i].is_number()) throw InputError(src + ": camera: '" + key + "' must be an array of 3 numbers");
    v[i] = a[i].get<double>();
  }
  if (!finite(v)) throw InputError(src + ": camera: '" + key + "' is not finite");
  return v;
}

double readNumber(const json& j, const char* key, const std::string& src) {
  const json& v = j.at(key);
  if (!v.is_number()) throw InputError(src + ": camera: '" + key + "' must be a number");
  double d = v.get<double>();
  if (!std::isfinite(d)) throw InputError(src + ": camera: '" + key + "' is not finite");
  return d;
}

template <int R, int C>
void readMatrix(const json& j, const char* key, double (&m)[R][C], const std::string& src) {
  const json& a = j.at(key);
  std::string shape = std::to_string(R) + "x" + std::to_string(C);
  if (!a.is_array() || a.size() != R) throw InputError(src + ": camera: '" + key + "' must be a " + shape + " array of rows");
  for (int r = 0; r < R; ++r) {
    if (!a[r].is_array() || a[r].size() != C) throw InputError(src + ": camera: '" + key + "' must be a " + shape + " array of rows");
    for (int c = 0; c < C; ++c) {
      if (!a[r][c].is_number()) throw InputError(src + ": camera: '" + key + "' has a non-number entry");
      m[r][c] = a[r][c].get<double>();
      if (!std::isfinite(m[r][c])) throw InputError(src + ": camera: '" + key + "' is not finite");
    }
  }
}

// A camera JSON's image side: a whole number of pixels, 1 to 16384 (the CLI's --size range).
int readSide(const json& j, const char* key, const std::string& src) {
  const json& v = j.at(key);
  if (!v.is_number_integer() || v.get<int64_t>() < 1 || v.get<int64_t>() > 16384)
    throw InputError(src + ": camera: '" + key + "' must be a whole number of pixels, 1 to 16384");
  return int(v.get<int64_t>());
}

// Beyond this magnitude eye and target are refused: their difference's squared length overflows.
constexpr double kMaxCoordinate = 1e30;
bool huge(const dvec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}) > kMaxCoordinate; }

}  // namespace

CameraSpec parseCameraJson(const std::string& text, const std::string& src) {
  json j = parseJsonOrThrow(text, src);
  if (!j.is_object()) throw InputError(src + ": camera: expected a JSON object");
  CameraSpec spec;
  static const char* known[] = {"eye", "target", "up", "fovy_deg", "near", "far", "ortho_height", "K", "world_to_camera",
                                "width", "height"};
  for (auto& [k, v] : j.items()) {
    bool ok = false;
    for (const char* n : known) ok = ok || k == n;
    if (!ok) throw InputError(src + ": camera: unknown key '" + k + "'");
  }
  if (j.contains("K") || j.contains("world_to_camera")) {
    spec.kind = CameraSpec::Kind::OpenCV;
    if (!j.contains("K") || !j.contains("world_to_camera"))
      throw InputError(src + ": camera: an OpenCV camera needs both 'K' and 'world_to_camera'");
    readMatrix(j, "K", spec.K, src);
    readMatrix(j, "world_to_camera", spec.worldToCamera, src);
  } else {
    spec.kind = CameraSpec::Kind::OpenGL;
    if (!j.contains("eye") || !j.contains("target"))
      throw InputError(src + ": camera: needs 'eye' and 'target' (OpenGL style) or 'K' and 'world_to_camera' (OpenCV style)");
    spec.eye = readVec3(j, "eye", src);
    spec.target = readVec3(j, "target", src);
    if (j.contains("up")) spec.up = readVec3(j, "up", src);
    if (j.contains("fovy_deg")) spec.fovyDeg = readNumber(j, "fovy_deg", src);
    if (j.contains("ortho_height")) spec.orthoHeight = readNumber(j, "ortho_height", src);
  }
  if (j.contains("near")) spec.near = readNumber(j, "near", src);
  if (j.contains("far")) spec.far = readNumber(j, "far", src);
  if (j.contains("width") != j.contains("height"))
    throw InputError(src + ": camera: give both 'width' and 'height' (the image size) or neither");
  if (j.contains("width")) {
    spec.width = readSide(j, "width", src);
    spec.height = readSide(j, "height", src);
  }
  return spec;
}

std::string cameraSpecToJson(const CameraSpec& s) {
  json j;
  auto vec = [](const dvec3& v) { return json::array({v.x, v.y, v.z}); };
  if (s.kind == CameraSpec::Kind::OpenGL) {
    j["eye"] = vec(s.eye);
    j["target"] = vec(s.target);
    j["up"] = vec(s.up);
    j["fovy_deg"] = s.fovyDeg;
    if (s.orthoHeight) j["ortho_height"] = *s.orthoHeight;
  } else {
    j["K"] = json::array();
    for (auto& row : s.K) j["K"].push_back(json::array({row[0], row[1], row[2]}));
    j["world_to_camera"] = json::array();
    for (auto& row : s.worldToCamera) j["world_to_camera"].push_back(json::array({row[0], row[1], row[2], row[3]}));
  }
  if (s.near) j["near"] = *s.near;
  if (s.far) j["far"] = *s.far;
  if (s.width && s.height) {
    j["width"] = *s.width;
    j["height"] = *s.height;
  }
  return j.dump(2);
}

CameraSpec frameBounds(const Bounds3& bounds, double fovyDeg) {
  CameraSpec spec;
  dvec3 c{0.0};
  double r = 1;
  if (!bounds.empty()) {
    c = bounds.center();
    r = glm::length(bounds.hi - bounds.lo) * 0.5;
    if (!(r > 0)) r = 1;
  }
  // A three-quarter view from the front-right, slightly above: reads as 3D for most models.
  dvec3 dir = glm::normalize(dvec3(0.55, 0.45, 1.0));
  double dist = r / std::sin(glm::radians(fovyDeg) * 0.5) * 1.02;
  spec.eye = c + dir * dist;
  spec.target = c;
  spec.up = {0, 1, 0};
  spec.fovyDeg = fovyDeg;
  return spec;
}

// --- Camera -------------------------------------------------------------------------------

void Camera::cameraRay(double px, double py, dvec3& origin, dvec3& dir) const {
  // Solve the 2x2 system rows hx, hy of pixelFromCamera for camera (x, y) with z = 1 (perspective,
  // through the centre of projection) or z = 0 (orthographic, on the plane z = 0).
  const dmat4& M = pixelFromCamera;  // M[col][row]
  double a = M[0][0], b = M[1][0], c = M[0][1], d = M[1][1];
  double rx, ry;
  if (orthographic) {
    rx = px - M[3][0];
    ry = py - M[3][1];
  } else {
    rx = px - M[2][0];
    ry = py - M[2][1];
  }
  double det = a * d - b * c;
  double x = (rx * d - b * ry) / det;
  double y = (a * ry - c * rx) / det;
  if (orthographic) {
    origin = {x, y, 0};
    dir = {0, 0, 1};
  } else {
    origin = {0, 0, 0};
    dir = {x, y, 1};
  }
}

dvec3 Camera::eyeWorld() const { return dvec3(glm::inverse(cameraFromWorld) * dvec4(0, 0, 0, 1)); }

Camera resolveCamera(const CameraSpec& spec, int width, int height, const Bounds3& sceneBounds,
                     const std::string& src) {
  if (width <= 0 || height <= 0) throw InputError(src + ": image size must be positive");
  Camera cam;
  cam.width = width;
  cam.height = height;
  dmat4 camFromWorld(1.0);
  dmat4 pix(0.0);  // pix[col][row]

  if (spec.kind == CameraSpec::Kind::OpenGL) {
    if (!finite(spec.eye) || !finite(spec.target) || !finite(spec.up))
      throw InputError(src + ": camera: eye, target and up must be finite");
    if (huge(spec.eye) || huge(spec.target))
      throw InputError(src + ": camera: eye or target has a coordinate beyond 1e30 in magnitude");
    dvec3 f = spec.target - spec.eye;
    if (glm::length(f) == 0) throw InputError(src + ": camera: eye and target are the same point");
    f = glm::normalize(f);
    dvec3 s = glm::cross(f, spec.up);
    if (glm::length(s) < 1e-12 * glm::length(spec.up) || glm::length(spec.up) == 0)
      throw InputError(src + ": camera: 'up' is zero or parallel to the view direction");
    s = glm::normalize(s);
    dvec3 u = glm::cross(s, f);
    // OpenCV axes: x = s (right), y = -u (down), z = f (forward).
    dvec3 rows[3] = {s, -u, f};
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) camFromWorld[c][r] = rows[r][c];
      camFromWorld[3][r] = -glm::dot(rows[r], spec.eye);
    }
    if (spec.orthoHeight) {
      double h = *spec.orthoHeight;
      if (!(h > 0) || !std::isfinite(h)) throw InputError(src + ": camera: ortho_height must be positive");
      double k = height / h;  // pixels per world unit
      pix[0][0] = k;
      pix[3][0] = width * 0.5;
      pix[1][1] = k;
      pix[3][1] = height * 0.5;
      pix[2][2] = 1;  // d = z
      pix[3][3] = 1;  // w = 1
      cam.orthographic = true;
    } else {
      if (!(spec.fovyDeg > 0 && spec.fovyDeg < 180))
        throw InputError(src + ": camera: fovy_deg must be in (0, 180)");
      double fy = (height * 0.5) / std::tan(glm::radians(spec.fovyDeg) * 0.5);
      pix[0][0] = fy;  // square pixels: fx = fy (aspect = width / height)
      pix[2][0] = width * 0.5;
      pix[1][1] = fy;
      pix[2][1] = height * 0.5;
      pix[2][2] = 1;  // d = z
      pix[2][3] = 1;  // w = z
    }
  } else {
    const auto& K = spec.K;
    if (K[1][0] != 0 || K[2][0] != 0 || K[2][1] != 0 || K[2][2] != 1)
      throw InputError(src + ": camera: K must be [[fx,s,cx],[0,fy,cy],[0,0,1]]");
    if (!(K[0][0] > 0) || !(K[1][1] > 0)) throw InputError(src + ": camera: K needs fx > 0 and fy > 0");
    const auto& P = spec.worldToCamera;
    if (P[3][0] != 0 || P[3][1] != 0 || P[3][2] != 0 || P[3][3] != 1)
      throw InputError(src + ": camera: world_to_camera's last row must be [0,0,0,1]");
    dmat3 R;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R[c][r] = P[r][c];
    dmat3 RtR = glm::transpose(R) * R;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (std::abs(RtR[c][r] - (r == c ? 1.0 : 0.0)) > 1e-6)
          throw InputError(src + ": camera: world_to_camera's rotation is not orthonormal");
    if (glm::determinant(R) < 0) throw InputError(src + ": camera: world_to_camera's rotation is a reflection");
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) camFromWorld[c][r] = P[r][c];
    // OpenCV pixel centres are at integers, ours at +0.5: shift the principal point.
    pix[0][0] = K[0][0];
    pix[1][0] = K[0][1];
    pix[2][0] = K[0][2] + 0.5;
    pix[1][1] = K[1][1];
    pix[2][1] = K[1][2] + 0.5;
    pix[2][2] = 1;
    pix[2][3] = 1;
  }
  cam.cameraFromWorld = camFromWorld;
  cam.pixelFromCamera = pix;

  // Near and far: given, or tight around the scene's bounding sphere seen from this camera.
  double autoNear = 0.01, autoFar = 100;
  if (!sceneBounds.empty()) {
    dvec3 c = dvec3(camFromWorld * dvec4(sceneBounds.center(), 1.0));
    double r = glm::length(sceneBounds.hi - sceneBounds.lo) * 0.5;
    double zFar = c.z + r, zNear = c.z - r;
    if (!(r > 0)) r = std::max(1.0, std::abs(c.z)) * 1e-3;
    autoFar = std::max(zFar * 1.01 + r * 1e-3, 1e-6);
    if (cam.orthographic) {
      autoNear = zNear - r * 0.01;
    } else {
      autoNear = std::max(zNear * 0.99, autoFar * 1e-4);
    }
    if (autoFar <= autoNear) autoFar = autoNear + std::max(1.0, std::abs(autoNear));
  }
  cam.near = spec.near.value_or(autoNear);
  cam.far = spec.far.value_or(std::max(autoFar, cam.near * 2 + 1e-9));
  if (!std::isfinite(cam.near) || !std::isfinite(cam.far)) throw InputError(src + ": camera: near/far must be finite");
  if (!cam.orthographic && !(cam.near > 0)) throw InputError(src + ": camera: near must be > 0");
  if (!(cam.far > cam.near)) throw InputError(src + ": camera: far must be greater than near");
  return cam;
}

}  // namespace hsr

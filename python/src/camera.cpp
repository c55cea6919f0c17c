// Cameras for Python: OpenCV (K and a world-to-camera pose), look-at and orthographic, the same
// CameraSpec the CLI's camera JSON gives (docs/conventions.md "Cameras"). Checked when made.
#include "common.hpp"

#include <cmath>

namespace hsrpy {

namespace {

// A `rows` x `cols` array of finite numbers (cols 0: a vector of `rows`).
std::vector<double> finiteArray(py::handle value, size_t rows, size_t cols, const std::string& what,
                                const std::string& src) {
  const std::string shape = cols ? std::to_string(rows) + "x" + std::to_string(cols) : std::to_string(rows) + "-vector";
  if (value.is_none()) valueError(src + ": camera: '" + what + "' is required");
  py::array a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(
        py::module_::import("numpy").attr("asarray")(value, "float64"));
  } catch (py::error_already_set&) {
    valueError(src + ": camera: '" + what + "' must be a " + shape + " array of numbers");
  }
  const bool ok = cols ? a.ndim() == 2 && size_t(a.shape(0)) == rows && size_t(a.shape(1)) == cols
                       : a.ndim() == 1 && size_t(a.shape(0)) == rows;
  if (!a || !ok) valueError(src + ": camera: '" + what + "' must be a " + shape + " array");
  const double* p = static_cast<const double*>(a.data());
  std::vector<double> out(p, p + rows * (cols ? cols : 1));
  for (double v : out)
    if (!std::isfinite(v)) valueError(src + ": camera: '" + what + "' is not finite");
  return out;
}

hsr::dvec3 vec3(py::handle value, const std::string& what, const std::string& src) {
  std::vector<double> v = finiteArray(value, 3, 0, what, src);
  return {v[0], v[1], v[2]};
}

std::optional<double> optionalNumber(py::handle value, const std::string& what, const std::string& src) {
  if (value.is_none()) return std::nullopt;
  double v = 0;
  try {
    v = value.cast<double>();
  } catch (py::cast_error&) {
    valueError(src + ": camera: '" + what + "' must be a number");
  }
  if (!std::isfinite(v)) valueError(src + ": camera: '" + what + "' is not finite");
  return v;
}

// Resolves the camera once, without a scene (near and far, when not given, then take fixed
// values), so that a bad camera fails where it is made with resolveCamera's messages, the CLI's.
PyCamera checked(PyCamera camera, const std::string& src) {
  checkImageSize(camera.width, camera.height);
  (void)hsr::resolveCamera(camera.spec, camera.width, camera.height, hsr::Bounds3{}, src);
  return camera;
}

}  // namespace

void checkImageSize(int width, int height) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    valueError("size " + std::to_string(width) + "x" + std::to_string(height) + ": width and height must be 1 to " +
               std::to_string(kMaxImageSide));
}

PyCamera opencvCamera(py::handle K, py::handle pose, py::handle R, py::handle t, int width, int height,
                      py::handle near, py::handle far) {
  const std::string src = "hsr.Camera.opencv";
  PyCamera camera;
  camera.width = width;
  camera.height = height;
  hsr::CameraSpec& s = camera.spec;
  s.kind = hsr::CameraSpec::Kind::OpenCV;
  const std::vector<double> k = finiteArray(K, 3, 3, "K", src);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.K[r][c] = k[size_t(3 * r + c)];
  if (!pose.is_none() && (!R.is_none() || !t.is_none()))
    valueError(src + ": camera: give world_to_camera or R and t, not both");
  if (pose.is_none()) {
    const std::vector<double> rotation = finiteArray(R, 3, 3, "R", src);
    const std::vector<double> translation = finiteArray(t, 3, 0, "t", src);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) s.worldToCamera[r][c] = rotation[size_t(3 * r + c)];
      s.worldToCamera[r][3] = translation[size_t(r)];
    }
  } else {
    const std::vector<double> m = finiteArray(pose, 4, 4, "world_to_camera", src);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) s.worldToCamera[r][c] = m[size_t(4 * r + c)];
  }
  s.near = optionalNumber(near, "near", src);
  s.far = optionalNumber(far, "far", src);
  return checked(camera, src);
}

PyCamera lookAtCamera(py::handle eye, py::handle target, int width, int height, py::handle up, double fovyDeg,
                      py::handle orthoHeight, py::handle near, py::handle far) {
  const std::string src = orthoHeight.is_none() ? "hsr.Camera.look_at" : "hsr.Camera.orthographic";
  PyCamera camera;
  camera.width = width;
  camera.height = height;
  hsr::CameraSpec& s = camera.spec;
  s.kind = hsr::CameraSpec::Kind::OpenGL;
  s.eye = vec3(eye, "eye", src);
  s.target = vec3(target, "target", src);
  s.up = vec3(up, "up", src);
  s.fovyDeg = fovyDeg;
  s.orthoHeight = optionalNumber(orthoHeight, "ortho_height", src);
  s.near = optionalNumber(near, "near", src);
  s.far = optionalNumber(far, "far", src);
  return checked(camera, src);
}

}  // namespace hsrpy

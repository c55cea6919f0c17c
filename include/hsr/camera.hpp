// Cameras. A CameraSpec is what the user gives (camera JSON, command-line flags, scene file);
// resolveCamera() turns it, with an image size and the scene bounds, into a Camera that every
// algorithm uses: a world-to-camera pose and a projection to pixel coordinates, in double.
//
// Conventions (docs/conventions.md): camera space here uses OpenCV axes — x right, y down,
// z forward — so eye depth d is simply camera-space z. Pixel (x, y) has its centre at
// (x + 0.5, y + 0.5), y = 0 is the top row. An OpenGL camera (lookAt + perspective) maps to the
// same pixels as OpenGL's viewport transform of its clip coordinates (with y flipped to put row 0
// at the top). An OpenCV camera's K uses OpenCV's pixel convention (pixel centres at integers):
// a point that K projects to (u, v) lands in pixel (floor(u + 0.5), floor(v + 0.5)).
#pragma once
#include <hsr/common.hpp>

#include <optional>
#include <string>

namespace hsr {

struct CameraSpec {
  enum class Kind { OpenGL, OpenCV };
  Kind kind = Kind::OpenGL;

  // OpenGL style.
  dvec3 eye{0, 0, 5}, target{0, 0, 0}, up{0, 1, 0};
  double fovyDeg = 60;
  std::optional<double> orthoHeight;  // set: orthographic, view volume this many units tall

  // OpenCV style: intrinsics K (row-major: K[r][c], may have skew K[0][1]) and the 4x4 row-major
  // world-to-camera pose (x right, y down, z forward).
  double K[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double worldToCamera[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};

  // Clipping planes (eye depth). Unset: chosen from the scene bounds.
  std::optional<double> near, far;

  // The image size the camera was made for (a camera JSON's "width" and "height", both or
  // neither), used when the caller gives none: an OpenCV K only fits its own image size.
  std::optional<int> width, height;
};

/// Parses a camera JSON (either style, docs/conventions.md). Throws InputError "file: problem".
CameraSpec parseCameraJson(const std::string& text, const std::string& sourceName);
/// Writes a camera spec as JSON (the same format parseCameraJson reads).
std::string cameraSpecToJson(const CameraSpec& spec);

/// Automatic framing: an OpenGL camera looking at the bounding sphere of `bounds` from a
/// three-quarter view, the sphere filling the view, near/far tight around it.
CameraSpec frameBounds(const Bounds3& bounds, double fovyDeg = 45);

/// A camera resolved for one image size. Maps world points to homogeneous pixel coordinates
/// h = (hx, hy, d, w): pixel position (hx/w, hy/w), eye depth d (camera-space z), and
/// w = d for perspective, w = 1 for orthographic. All four are linear in the world point, so
/// clipping interpolates them linearly.
struct Camera {
  int width = 0, height = 0;
  bool orthographic = false;
  double near = 0.1, far = 100;
  dmat4 cameraFromWorld{1.0};  // OpenCV axes; double precision, applied to world points directly
  dmat4 pixelFromCamera{1.0};  // rows: hx, hy, d, w (glm is column-major: element [col][row])

  dvec3 toCamera(const dvec3& world) const { return dvec3(cameraFromWorld * dvec4(world, 1.0)); }
  dvec4 toPixelH(const dvec3& world) const { return pixelFromCamera * (cameraFromWorld * dvec4(world, 1.0)); }
  /// Ray through pixel position (px, py) in camera space: origin + t * dir, with dir.z == 1, so
  /// the eye depth of the point at t is origin.z + t (origin.z == 0).
  void cameraRay(double px, double py, dvec3& origin, dvec3& dir) const;
  /// World position of the camera centre (perspective) or of the view plane centre (ortho).
  dvec3 eyeWorld() const;
};

/// Resolves a spec for a width x height image. Fills near/far from `sceneBounds` when unset.
/// Throws InputError (naming `sourceName`) on a degenerate camera (eye == target, up parallel to
/// the view direction, fov out of (0, 180), near <= 0, far <= near, singular K, NaN values).
Camera resolveCamera(const CameraSpec& spec, int width, int height, const Bounds3& sceneBounds,
                     const std::string& sourceName = "camera");

}  // namespace hsr

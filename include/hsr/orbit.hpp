// Orbits: a camera turned around the scene, for benchmarks and studies that
// render a static scene from many sides ("build once, view many times").
#pragma once
#include <hsr/camera.hpp>

#include <vector>

namespace hsr {

/// `camera` turned by `radians` about the axis through `centre` along the camera's own up
/// direction (image y up, in world space): the same view of the scene from another side, with
/// the same image size, projection and near/far.
Camera orbitCamera(const Camera& camera, const dvec3& centre, double radians);

/// `count` cameras evenly spaced on the full orbit of `camera` around `centre`, the first one
/// `camera` itself.
std::vector<Camera> orbitCameras(const Camera& camera, const dvec3& centre, int count);

}  // namespace hsr

// Orbits of a camera around a scene (include/hsr/orbit.hpp).
#include <hsr/orbit.hpp>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace hsr {

Camera orbitCamera(const Camera& camera, const dvec3& centre, double radians) {
  const dmat4 worldFromCamera = glm::inverse(camera.cameraFromWorld);
  const dvec3 up = glm::normalize(dvec3(worldFromCamera * dvec4(0, -1, 0, 0)));  // OpenCV axes: y is down
  // The camera moved by T(c) R T(-c) in the world: its cameraFromWorld gets the inverse on the right.
  const dmat4 unturn = glm::translate(dmat4(1.0), centre) * glm::rotate(dmat4(1.0), -radians, up) *
                       glm::translate(dmat4(1.0), -centre);
  Camera turned = camera;
  turned.cameraFromWorld = camera.cameraFromWorld * unturn;
  return turned;
}

std::vector<Camera> orbitCameras(const Camera& camera, const dvec3& centre, int count) {
  std::vector<Camera> cameras;
  for (int i = 0; i < count; ++i) cameras.push_back(orbitCamera(camera, centre, 2 * M_PI * i / count));
  return cameras;
}

}  // namespace hsr

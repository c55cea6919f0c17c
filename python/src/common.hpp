// What the Python module's parts share: the scene and camera objects Python holds, and the
// translation of hsr's errors into Python exceptions (python/README in docs/python.md).
#pragma once
#include <hsr/hsr.hpp>
#include <hsr/views.hpp>
#include <hsr/visibility.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace hsrpy {

namespace py = pybind11;

/// A finalized scene with what the module adds per face (the instance id of its mesh) and, made
/// on first use, the normals of its triangles. Immutable once built, so renders on several
/// Python threads may share it.
struct SceneData {
  hsr::Scene scene;
  std::vector<int32_t> meshInstance;  // per mesh (Scene::meshes)
  std::vector<int32_t> faceInstance;  // per face
  hsr::Bounds3 bounds;                // scene.bounds(), computed once (cameras fit near/far to it)
  /// The unit normals of Scene::triangles (hsr::triangleNormals), computed once.
  const std::vector<glm::vec3>& normals() const;

  mutable std::once_flag normalsOnce;
  mutable std::vector<glm::vec3> triangleNormals;

  /// Renders one view with the algorithm object this scene keeps for the last algorithm and
  /// parameters it rendered with, so that repeated hsr.render calls build once (a BSP tree, the
  /// tiled z-buffer's buffers); a call made while another uses it gets an object of its own.
  void render(const hsr::Camera& camera, const hsr::RenderOptions& options, hsr::Frame& frame) const;
  mutable std::mutex rendererMutex;
  mutable std::optional<hsr::Renderer> renderer;

  /// The per-instance visibility of `frame`, a view of this scene (hsr::VisibilityCounter), with
  /// a counter the scene keeps for later calls: one per call running at the same time.
  std::vector<hsr::InstanceVisibility> countVisibility(const hsr::Camera& camera, const hsr::RenderOptions& options,
                                                       const hsr::Frame& frame) const;
  mutable std::mutex countersMutex;
  mutable std::vector<hsr::VisibilityCounter> idleCounters;
};
/// Builds the SceneData of a finalized scene; `instances` per mesh (empty: the mesh index).
std::shared_ptr<SceneData> makeSceneData(hsr::Scene&& scene, std::vector<int32_t> instances = {});

/// A camera as the user gave it (hsr::CameraSpec) with the image size it renders; near and far,
/// when not given, are fitted to each scene it renders (as `hsr render` does).
struct PyCamera {
  hsr::CameraSpec spec;
  int width = 0, height = 0;
  hsr::Camera resolve(const SceneData& scene, const std::string& name) const {
    return hsr::resolveCamera(spec, width, height, scene.bounds, name);
  }
};

/// The largest image side the CLI accepts (its --size), kept by the module too.
inline constexpr int kMaxImageSide = 16384;

/// Throws ValueError with `message` (the module's own checks; hsr::InputError becomes ValueError too).
[[noreturn]] inline void valueError(const std::string& message) { throw py::value_error(message); }

/// An hsr::InputError in the module's terms: a keyed error names its setting as hsr.render's
/// keyword or the module's function ("depth_format: ...", "params={'raster': 'x'}: ...",
/// "... (hsr.set_max_memory)"); a plain one is its what() (module.cpp).
std::string pythonMessage(const hsr::InputError& error);

/// Loads a scene as hsr.load does: OSError (FileNotFoundError, IsADirectoryError, ...) when the
/// named file cannot be opened, ValueError for bad content; the messages are the CLI's.
hsr::Scene loadSceneOrRaise(const std::string& path);

/// Scene.from_arrays: one mesh (arrays) or several (lists of arrays).
std::shared_ptr<SceneData> sceneFromArrays(py::handle vertices, py::handle faces, py::handle colors,
                                                 py::handle instanceIds, py::handle names);

/// hsr.render: a dict of NumPy arrays.
py::dict renderToArrays(const SceneData& scene, py::handle cameras, py::handle outputs, const std::string& algorithm,
                        py::handle params, const std::string& depthFormat, const std::string& cull,
                        const std::string& shading, py::handle background, int threads);

/// Cameras from NumPy values: K (3x3), pose (4x4, or R 3x3 and t 3), vectors.
PyCamera opencvCamera(py::handle K, py::handle pose, py::handle R, py::handle t, int width, int height,
                      py::handle near, py::handle far);
PyCamera lookAtCamera(py::handle eye, py::handle target, int width, int height, py::handle up, double fovyDeg,
                      py::handle orthoHeight, py::handle near, py::handle far);
void checkImageSize(int width, int height);

/// hsr.screen_polygons (vector.cpp).
void bindVector(py::module_& m);

}  // namespace hsrpy

// The `hsr` Python package's extension `hsr._hsr` (python/hsr/__init__.py re-exports it): scenes (hsr.load, Scene.from_arrays), cameras (OpenCV, look-at,
// orthographic, camera JSON) and hsr.render into NumPy arrays. docs/python.md is its manual.
#include "common.hpp"

#include <hsr/limits.hpp>

#include <pybind11/stl.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#ifndef HSR_VERSION
#define HSR_VERSION "0.1.0"
#endif

namespace hsrpy {

std::string pythonMessage(const hsr::InputError& error) {
  switch (error.setting()) {
    case hsr::Setting::Algorithm: return error.worded("algorithm");
    case hsr::Setting::DepthFormat: return error.worded("depth_format");
    case hsr::Setting::Size: return error.worded("camera size");
    case hsr::Setting::MaxMemory: return error.worded("hsr.set_max_memory");
    case hsr::Setting::Param: {  // subject "KEY=VALUE": named as the dict entry that was passed
      const std::string& entry = error.subject();
      const size_t eq = std::min(entry.find('='), entry.size());
      const std::string value = eq < entry.size() ? entry.substr(eq + 1) : "";
      return error.worded("params={'" + entry.substr(0, eq) + "': '" + value + "'}", "");
    }
    // Settings the module does not offer: the library's own wording.
    case hsr::Setting::None:
    case hsr::Setting::Verify:
    case hsr::Setting::SwitchOff:
    case hsr::Setting::Svg:
    case hsr::Setting::OverdrawImage:
    case hsr::Setting::ShadowMapSize:
    case hsr::Setting::ShadowBias: return error.what();
  }
  return error.what();
}

namespace {

using SceneHandle = std::shared_ptr<SceneData>;

template <class T>
py::array copyArray(const T* data, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::memcpy(a.mutable_data(), data, size_t(a.size()) * sizeof(T));
  return a;
}

py::list meshesOf(const SceneData& d) {
  py::list out;
  for (size_t m = 0; m < d.scene.meshes.size(); ++m) {
    const hsr::MeshRange& r = d.scene.meshes[m];
    py::dict mesh;
    mesh["name"] = r.name;
    mesh["first_face"] = r.firstFace;
    mesh["face_count"] = r.faceCount;
    mesh["instance_id"] = d.meshInstance[m];
    out.append(mesh);
  }
  return out;
}

py::object boundsOf(const SceneData& d) {
  const hsr::Bounds3& b = d.bounds;
  if (b.empty()) return py::none();
  const double v[6] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
  return copyArray(v, {2, 3});
}

py::array trianglesOf(const hsr::Scene& scene, bool faces) {
  const size_t n = scene.triangles.size();
  std::vector<int64_t> v(faces ? n : 3 * n);
  for (size_t t = 0; t < n; ++t) {
    const hsr::Triangle& tri = scene.triangles[t];
    if (faces) v[t] = tri.face;
    else
      for (int k = 0; k < 3; ++k) v[3 * t + size_t(k)] = tri.v[k];
  }
  return faces ? copyArray(v.data(), {py::ssize_t(n)}) : copyArray(v.data(), {py::ssize_t(n), 3});
}

// The camera `hsr render SCENE --size WxH` uses without camera flags: the scene's own, else a
// framing of its bounds.
PyCamera defaultCamera(const SceneData& d, int width, int height) {
  checkImageSize(width, height);
  PyCamera c;
  c.spec = d.scene.camera ? *d.scene.camera : hsr::frameBounds(d.bounds);
  c.width = width;
  c.height = height;
  return c;
}

std::string readCameraText(const std::string& textOrPath, std::string& source) {
  const size_t start = textOrPath.find_first_not_of(" \t\r\n");
  if (start != std::string::npos && textOrPath[start] == '{') {
    source = "camera";
    return textOrPath;
  }
  source = textOrPath;
  std::ifstream in(textOrPath, std::ios::binary);
  if (!in) {
    const int error = errno ? errno : ENOENT;
    PyErr_SetObject(PyExc_OSError,
                    py::make_tuple(error, textOrPath + ": cannot open: " + std::strerror(error)).ptr());
    throw py::error_already_set();
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

PyCamera cameraFromJson(const std::string& textOrPath, int width, int height) {
  std::string source;
  const std::string text = readCameraText(textOrPath, source);
  PyCamera c;
  c.spec = hsr::parseCameraJson(text, source);
  c.width = width;
  c.height = height;
  checkImageSize(width, height);
  (void)hsr::resolveCamera(c.spec, width, height, hsr::Bounds3{}, source);
  return c;
}

// world_to_camera: a 4x4 pose, (R, t), or (N, 4, 4) poses (a list of cameras).
py::object opencvCameras(py::handle K, py::handle pose, int width, int height, py::handle near, py::handle far) {
  if ((py::isinstance<py::tuple>(pose) || py::isinstance<py::list>(pose)) && py::len(pose) == 2) {
    py::sequence rt = py::reinterpret_borrow<py::sequence>(pose);
    return py::cast(opencvCamera(K, py::none(), rt[0], rt[1], width, height, near, far));
  }
  py::array a = py::module_::import("numpy").attr("asarray")(pose);
  if (a.ndim() != 3) return py::cast(opencvCamera(K, pose, py::none(), py::none(), width, height, near, far));
  py::list cameras;
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    cameras.append(opencvCamera(K, a[py::int_(i)], py::none(), py::none(), width, height, near, far));
  return cameras;
}

py::object optionalOf(const std::optional<double>& v) { return v ? py::object(py::float_(*v)) : py::none(); }

py::array rowMajor(const hsr::dmat4& m) {
  double v[16];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[4 * r + c] = m[c][r];  // glm: [column][row]
  return copyArray(v, {4, 4});
}

// The camera as hsr renders `scene` with it: its pose, projection and clipping planes.
py::dict resolvedCamera(const PyCamera& c, const SceneData& d) {
  const hsr::Camera cam = c.resolve(d, "camera");
  py::dict out;
  out["camera_from_world"] = rowMajor(cam.cameraFromWorld);
  out["pixel_from_camera"] = rowMajor(cam.pixelFromCamera);
  out["near"] = cam.near;
  out["far"] = cam.far;
  out["orthographic"] = cam.orthographic;
  out["width"] = cam.width;
  out["height"] = cam.height;
  return out;
}

std::string cameraRepr(const PyCamera& c) {
  const char* kind = c.spec.kind == hsr::CameraSpec::Kind::OpenCV ? "opencv"
                     : c.spec.orthoHeight                         ? "orthographic"
                                                                  : "look_at";
  return "hsr.Camera(" + std::string(kind) + ", " + std::to_string(c.width) + "x" + std::to_string(c.height) + ")";
}

void bindScene(py::module_& m) {
  py::class_<SceneData, SceneHandle>(m, "Scene",
                                     "A finalized scene: meshes of polygons in world space, triangulated. Immutable; "
                                     "share it between renders and threads.")
      .def_static("from_arrays", &sceneFromArrays, py::arg("vertices"), py::arg("faces"), py::arg("colors") = py::none(),
                  py::arg("instance_ids") = py::none(), py::arg("names") = py::none(),
                  R"(A scene from NumPy arrays: one mesh, or several given as lists of arrays.

vertices: (N, 3) float32 or float64 world coordinates (a list of them: one per mesh).
faces: (M, 3) integer vertex indices (triangles), or (M, K) for polygons of K >= 3 vertices;
  indices are into the mesh's own vertices. Face ids count faces across meshes in order.
colors: per-face (M, 3|4) uint8 0-255 or float 0-1, or one (3|4,) colour for the mesh; default grey.
instance_ids: one integer >= 0 per mesh (default: the mesh's position, 0, 1, ...).
names: one name per mesh.
Raises ValueError for bad dtypes, shapes, non-finite coordinates, indices out of range, empty meshes.)")
      .def_property_readonly("source", [](const SceneData& d) { return d.scene.source; })
      .def_property_readonly("face_count", [](const SceneData& d) { return d.scene.faceCount(); })
      .def_property_readonly("triangle_count", [](const SceneData& d) { return d.scene.triangles.size(); })
      .def_property_readonly("vertex_count", [](const SceneData& d) { return d.scene.positions.size(); })
      .def_property_readonly("meshes", &meshesOf, "Per mesh: name, first_face, face_count, instance_id.")
      .def_property_readonly(
          "instance_ids", [](const SceneData& d) { return copyArray(d.meshInstance.data(), {py::ssize_t(d.meshInstance.size())}); },
          "The instance id of each mesh (int32).")
      .def_property_readonly(
          "face_instance_ids",
          [](const SceneData& d) { return copyArray(d.faceInstance.data(), {py::ssize_t(d.faceInstance.size())}); },
          "The instance id of each face (int32): what render's instance_id shows.")
      .def_property_readonly("bounds", [](const SceneData& d) { return boundsOf(d); },
                             "[[xmin, ymin, zmin], [xmax, ymax, zmax]] of the vertices faces use (None: empty).")
      .def_property_readonly(
          "vertices",
          [](const SceneData& d) {
            return copyArray(&d.scene.positions[0].x, {py::ssize_t(d.scene.positions.size()), 3});
          },
          "(N, 3) float64 vertex positions (a copy).")
      .def_property_readonly("triangles", [](const SceneData& d) { return trianglesOf(d.scene, false); },
                             "(T, 3) int64 vertex indices of the triangulation; triangle_id indexes its rows.")
      .def_property_readonly("triangle_faces", [](const SceneData& d) { return trianglesOf(d.scene, true); },
                             "(T,) int64: the face each triangle comes from.")
      .def("default_camera", &defaultCamera, py::arg("width"), py::arg("height"),
           "The camera `hsr render` uses without camera flags: the scene's own, else a framing of its bounds.")
      .def("__repr__", [](const SceneData& d) {
        return "hsr.Scene('" + d.scene.source + "', " + std::to_string(d.scene.faceCount()) + " faces, " +
               std::to_string(d.scene.meshes.size()) + " meshes)";
      });
}

void bindCamera(py::module_& m) {
  py::class_<PyCamera>(m, "Camera",
                       "A camera and the image size it renders. Camera space has OpenCV axes (x right, y down, z "
                       "forward); pixel (x, y) is centred at (x + 0.5, y + 0.5), row 0 at the top.")
      .def_static("opencv", &opencvCameras, py::arg("K"), py::arg("world_to_camera"), py::arg("width"),
                  py::arg("height"), py::arg("near") = py::none(), py::arg("far") = py::none(),
                  R"(An OpenCV camera: K = [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with OpenCV's pixel
convention (pixel centres at integers: a point K projects to (u, v) lands in pixel
(floor(u + 0.5), floor(v + 0.5))), and world_to_camera as a 4x4 matrix or a pair (R, t)
(x_cam = R x_world + t). (N, 4, 4) poses give a list of N cameras. near, far: eye depths
(None: fitted to the scene).)")
      .def_static(
          "look_at",
          [](py::handle eye, py::handle target, int width, int height, py::handle up, double fovy, py::handle near,
             py::handle far) { return lookAtCamera(eye, target, width, height, up, fovy, py::none(), near, far); },
          py::arg("eye"), py::arg("target"), py::arg("width"), py::arg("height"),
          py::arg("up") = py::make_tuple(0.0, 1.0, 0.0), py::arg("fovy_deg") = 60.0, py::arg("near") = py::none(),
          py::arg("far") = py::none(),
          "A perspective camera at `eye` looking at `target` (OpenGL's lookAt and perspective, vertical field of "
          "view fovy_deg, aspect width/height), as the CLI's --eye/--target/--up/--fov.")
      .def_static(
          "orthographic",
          [](py::handle eye, py::handle target, double viewHeight, int width, int height, py::handle up,
             py::handle near, py::handle far) {
            return lookAtCamera(eye, target, width, height, up, 60.0, py::float_(viewHeight), near, far);
          },
          py::arg("eye"), py::arg("target"), py::arg("view_height"), py::arg("width"), py::arg("height"),
          py::arg("up") = py::make_tuple(0.0, 1.0, 0.0), py::arg("near") = py::none(), py::arg("far") = py::none(),
          "An orthographic camera looking from `eye` at `target`, its view volume view_height world units tall "
          "(the CLI's --ortho).")
      .def_static("from_json", &cameraFromJson, py::arg("json"), py::arg("width"), py::arg("height"),
                  "A camera from a camera JSON text or file (docs/conventions.md), as `hsr render --camera`.")
      .def("to_json", [](const PyCamera& c) { return hsr::cameraSpecToJson(c.spec); },
           "The camera JSON `hsr render --camera` reads (the image size is --size).")
      .def("resolve", &resolvedCamera, py::arg("scene"),
           R"(The camera as hsr renders `scene` with it: camera_from_world (4x4, into OpenCV axes),
pixel_from_camera (4x4, rows hx, hy, d, w: pixel (hx/w, hy/w), pixel centres at +0.5, eye depth d),
near and far (fitted to the scene when not given), orthographic, width, height.)")
      .def_readonly("width", &PyCamera::width)
      .def_readonly("height", &PyCamera::height)
      .def_property_readonly("kind", [](const PyCamera& c) {
        return c.spec.kind == hsr::CameraSpec::Kind::OpenCV ? "opencv" : c.spec.orthoHeight ? "orthographic" : "look_at";
      })
      .def_property_readonly("near", [](const PyCamera& c) { return optionalOf(c.spec.near); })
      .def_property_readonly("far", [](const PyCamera& c) { return optionalOf(c.spec.far); })
      .def("__repr__", &cameraRepr)
      // Pickled as its camera JSON and size (exact: the JSON's numbers round-trip), so that cameras
      // travel to other processes (multiprocessing, hsr.distributed on Dask).
      .def(py::pickle([](const PyCamera& c) { return py::make_tuple(hsr::cameraSpecToJson(c.spec), c.width, c.height); },
                      [](const py::tuple& state) {
                        if (state.size() != 3) valueError("hsr.Camera: bad pickled state");
                        return cameraFromJson(state[0].cast<std::string>(), state[1].cast<int>(), state[2].cast<int>());
                      }));
}

}  // namespace

}  // namespace hsrpy

PYBIND11_MODULE(_hsr, m) {
  using namespace hsrpy;
  m.doc() = "hsr: exact depth, face-id, instance and barycentric images of meshes on the CPU (docs/python.md).";
  m.attr("__version__") = HSR_VERSION;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const hsr::InputError& e) {
      PyErr_SetString(PyExc_ValueError, pythonMessage(e).c_str());
    }
  });
  bindScene(m);
  bindCamera(m);
  bindVector(m);
  m.def(
      "load", [](const std::string& path) { return makeSceneData(loadSceneOrRaise(path)); }, py::arg("path"),
      R"(Loads a scene as `hsr render` does: OBJ, PLY, STL, OFF, glTF/GLB and other assimp formats, a scene
JSON, or "builtin:NAME[?k=v&...]". Each mesh's instance id is its position. Raises OSError when the
file cannot be opened and ValueError for bad content, with the CLI's messages.)");
  m.def("render", &renderToArrays, py::arg("scene"), py::arg("cameras"),
        py::arg("outputs") = py::make_tuple("depth", "face_id"), py::arg("algorithm") = "zbuffer",
        py::arg("params") = py::none(), py::arg("depth_format") = "", py::arg("cull") = "none",
        py::arg("shading") = "lambert", py::arg("background") = py::make_tuple(0, 0, 0), py::arg("threads") = 0,
        R"(Renders `scene` seen by one hsr.Camera (arrays (H, W[, C])) or a sequence of N cameras of one
size (arrays (N, H, W[, C]), the views spread over the threads). Returns a dict of the outputs asked for:
  depth        float32 eye depth (camera-space z), +inf on the background
  face_id      int32 face index, -1 on the background
  instance_id  int32 instance id of the face's mesh, -1 on the background
  triangle_id  int32 row of scene.triangles, -1 on the background
  barycentric  float32 (.., 3): the pixel centre on the visible triangle, b0 v0 + b1 v1 + b2 v2
  normal       float32 (.., 3): unit world normal of the visible triangle, 0 on the background
  color        uint8 (.., 4): the shaded RGBA image (shading: lambert, flat or faceid)
  visibility   per instance, sorted by id: a structured array (N views first) of instance_id,
               px_count_all (pixels covered alone), px_count_visib, visib_fract (docs/python.md)
algorithm, params, depth_format ("f32:reversed" by default), cull ("none", "back", "front") are
`hsr render`'s --algorithm, --param, --depth-format, --cull; threads 0 uses every core. The GIL is
released while rendering; the arrays are the module's buffers, not copies.)");
  m.def(
      "set_max_memory",
      [](py::handle size) {
        if (size.is_none()) return hsr::setMemoryLimit(0);
        if (!py::isinstance<py::str>(size) && !py::isinstance<py::int_>(size))
          throw hsr::InputError("hsr.set_max_memory: expected a number of bytes or a string such as '512M'");
        hsr::setMemoryLimit(hsr::parseMemorySize(py::str(size).cast<std::string>(), "hsr.set_max_memory"));
      },
      py::arg("size"),
      R"(Sets the memory limit that hsr.render and hsr.load check before allocating (the CLI's
--max-memory): bytes, or a string such as "512M" or "2GiB"; None restores the default, the machine's
available memory. A render whose outputs exceed it raises MemoryError, a built-in scene ValueError.)");
  m.def("max_memory", [] { return hsr::memoryLimit(); }, "The memory limit in bytes (hsr.set_max_memory).");
  m.def("algorithms", [] {
    std::vector<std::string> names;
    for (const hsr::AlgorithmInfo& a : hsr::algorithms()) names.push_back(a.name);
    return names;
  }, "The names of the visibility algorithms (`hsr algorithms`).");
  m.def("builtin_scenes", [] {
    std::vector<std::string> names;
    for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) names.push_back("builtin:" + b.name);
    return names;
  }, "The built-in scenes, as names hsr.load accepts.");
}

// Scenes for Python: hsr.load (files and builtin: names, with the CLI's errors) and
// Scene.from_arrays (NumPy vertices, faces, colours, several meshes with instance ids).
#include "common.hpp"

#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace hsrpy {

namespace fs = std::filesystem;

const std::vector<glm::vec3>& SceneData::normals() const {
  std::call_once(normalsOnce, [this] { triangleNormals = hsr::triangleNormals(scene); });
  return triangleNormals;
}

void SceneData::render(const hsr::Camera& camera, const hsr::RenderOptions& options, hsr::Frame& frame) const {
  std::unique_lock lock(rendererMutex, std::try_to_lock);
  if (!lock.owns_lock()) return hsr::render(scene, camera, options, frame);  // in use by another call
  if (!renderer || renderer->options().algorithm != options.algorithm || renderer->options().params != options.params)
    renderer.emplace(scene, options);
  renderer->render(camera, options, frame);
}

std::vector<hsr::InstanceVisibility> SceneData::countVisibility(const hsr::Camera& camera,
                                                                const hsr::RenderOptions& options,
                                                                const hsr::Frame& frame) const {
  std::optional<hsr::VisibilityCounter> counter;
  {
    std::lock_guard lock(countersMutex);
    if (!idleCounters.empty()) {
      counter.emplace(std::move(idleCounters.back()));
      idleCounters.pop_back();
    }
  }
  if (!counter) counter.emplace(scene, faceInstance);
  std::vector<hsr::InstanceVisibility> counts = counter->count(camera, options, frame);
  std::lock_guard lock(countersMutex);
  idleCounters.push_back(std::move(*counter));
  return counts;
}

std::shared_ptr<SceneData> makeSceneData(hsr::Scene&& scene, std::vector<int32_t> instances) {
  auto data = std::make_shared<SceneData>();
  data->scene = std::move(scene);
  data->bounds = data->scene.bounds();
  const size_t meshes = data->scene.meshes.size();
  if (instances.empty())
    for (size_t m = 0; m < meshes; ++m) instances.push_back(int32_t(m));
  data->meshInstance = std::move(instances);
  data->faceInstance = hsr::faceMeshIndices(data->scene);
  for (int32_t& f : data->faceInstance) f = f >= 0 ? data->meshInstance[size_t(f)] : -1;
  return data;
}

namespace {

// The errno of a file the loader cannot open (0: it can, or it is not a file name).
int fileProblem(const std::string& path) {
  if (path.starts_with("builtin:")) return 0;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return ENOENT;
  if (fs::is_directory(status)) return EISDIR;
  std::ifstream in(path, std::ios::binary);
  return in ? 0 : (errno ? errno : EACCES);
}

}  // namespace

hsr::Scene loadSceneOrRaise(const std::string& path) {
  const int problem = fileProblem(path);
  try {
    py::gil_scoped_release unlocked;
    return hsr::loadScene(path);
  } catch (const hsr::InputError& e) {
    if (!problem) throw;  // ValueError (the module's translator)
    // OSError(errno, message): Python picks the subclass (FileNotFoundError, ...) from errno.
    PyErr_SetObject(PyExc_OSError, py::make_tuple(problem, pythonMessage(e)).ptr());
    throw py::error_already_set();
  }
}

// --- Scene.from_arrays -----------------------------------------------------------------------

namespace {

// One mesh's arrays, checked and converted while the GIL is held.
struct MeshArrays {
  std::string name;
  std::vector<hsr::dvec3> positions;
  std::vector<uint32_t> indices;  // faces * corners, local to the mesh
  size_t corners = 3;
  std::vector<hsr::Rgba8> colors;  // per face, or one for all, or none (the loaders' grey)
  int32_t instance = 0;
};

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtypeText(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

py::array asArray(py::handle value, const std::string& what) {
  if (value.is_none()) valueError(what + ": expected an array, got None");
  try {
    return py::module_::import("numpy").attr("asarray")(value);
  } catch (py::error_already_set&) {
    valueError(what + ": not convertible to a NumPy array");
  }
}

std::vector<hsr::dvec3> checkVertices(py::handle value, const std::string& what) {
  py::array a = asArray(value, what);
  const char kind = a.dtype().kind();
  if (kind != 'f' || (a.itemsize() != 4 && a.itemsize() != 8))
    valueError(what + ": expected float32 or float64 coordinates, got " + dtypeText(a));
  if (a.ndim() != 2 || a.shape(1) != 3) valueError(what + ": expected shape (N, 3), got " + shapeText(a));
  if (a.shape(0) == 0) valueError(what + ": no vertices");
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const double* p = d.data();
  std::vector<hsr::dvec3> out(size_t(a.shape(0)));
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
    if (!std::isfinite(out[i].x) || !std::isfinite(out[i].y) || !std::isfinite(out[i].z))
      valueError(what + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
  }
  return out;
}

void checkFaces(py::handle value, const std::string& what, MeshArrays& mesh) {
  py::array a = asArray(value, what);
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u') valueError(what + ": expected integer vertex indices, got " + dtypeText(a));
  if (a.ndim() != 2 || a.shape(1) < 3)
    valueError(what + ": expected shape (M, 3) (triangles) or (M, K), K >= 3 (polygons), got " + shapeText(a));
  if (a.shape(0) == 0) valueError(what + ": no faces");
  auto d = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!d) valueError(what + ": indices do not fit in 64 bits");
  mesh.corners = size_t(a.shape(1));
  const size_t n = size_t(a.shape(0)) * mesh.corners, vertices = mesh.positions.size();
  mesh.indices.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int64_t v = d.data()[i];
    if (v < 0 || uint64_t(v) >= vertices)
      valueError(what + ": face " + std::to_string(i / mesh.corners) + ": vertex index " + std::to_string(v) +
                 " out of range (" + std::to_string(vertices) + " vertices)");
    mesh.indices[i] = uint32_t(v);
  }
}

hsr::Rgba8 colorOf(const double* c, size_t channels, bool unit, const std::string& what, size_t face) {
  uint8_t rgba[4] = {0, 0, 0, 255};
  for (size_t k = 0; k < channels; ++k) {
    const double v = unit ? c[k] * 255.0 : c[k];
    if (!(v >= 0 && v <= 255))  // (NaN fails too)
      valueError(what + ": face " + std::to_string(face) + ": colour component out of range (" +
                 (unit ? "floats 0 to 1" : "integers 0 to 255") + ")");
    rgba[k] = uint8_t(std::lround(v));
  }
  return {rgba[0], rgba[1], rgba[2], rgba[3]};
}

// Per-face colours (M, 3|4) or one colour (3|4,): uint8 0-255 or floats 0-1.
void checkColors(py::handle value, const std::string& what, size_t faces, MeshArrays& mesh) {
  if (value.is_none()) return;
  py::array a = asArray(value, what);
  const char kind = a.dtype().kind();
  if (kind != 'u' && kind != 'i' && kind != 'f')
    valueError(what + ": expected uint8 (0-255) or float (0-1) colours, got " + dtypeText(a));
  const bool one = a.ndim() == 1;
  const size_t channels = size_t(a.shape(a.ndim() - 1));
  if ((a.ndim() != 1 && a.ndim() != 2) || (channels != 3 && channels != 4) ||
      (!one && size_t(a.shape(0)) != faces))
    valueError(what + ": expected shape (" + std::to_string(faces) + ", 3|4) (one per face) or (3|4,), got " +
               shapeText(a));
  auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const size_t rows = one ? 1 : faces;
  for (size_t f = 0; f < rows; ++f) mesh.colors.push_back(colorOf(d.data() + f * channels, channels, kind == 'f', what, f));
}

// A list or tuple of meshes, or one mesh.
bool isMeshList(py::handle value) {
  if (!py::isinstance<py::list>(value) && !py::isinstance<py::tuple>(value)) return false;
  py::sequence s = py::reinterpret_borrow<py::sequence>(value);
  if (s.size() == 0) valueError("vertices: an empty list of meshes");
  return asArray(s[0], "vertices[0]").ndim() == 2;
}

// Item i of `value` when it lists meshes (None: none given).
py::object itemOf(py::handle value, size_t i, size_t count, const std::string& what) {
  if (value.is_none()) return py::none();
  if (!py::isinstance<py::list>(value) && !py::isinstance<py::tuple>(value))
    valueError(what + ": expected a list of " + std::to_string(count) + " (one per mesh)");
  py::sequence s = py::reinterpret_borrow<py::sequence>(value);
  if (s.size() != count)
    valueError(what + ": " + std::to_string(s.size()) + " entries for " + std::to_string(count) + " meshes");
  return s[i];
}

std::vector<MeshArrays> checkMeshes(py::handle vertices, py::handle faces, py::handle colors, py::handle instanceIds,
                                    py::handle names) {
  const bool many = isMeshList(vertices);
  const size_t count = many ? py::len(vertices) : 1;
  if (many && (!(py::isinstance<py::list>(faces) || py::isinstance<py::tuple>(faces)) || py::len(faces) != count))
    valueError("faces: expected a list of " + std::to_string(count) + " face arrays, one per vertex array");
  std::vector<MeshArrays> meshes(count);
  for (size_t m = 0; m < count; ++m) {
    const std::string at = many ? "[" + std::to_string(m) + "]" : "";
    MeshArrays& mesh = meshes[m];
    mesh.positions = checkVertices(many ? itemOf(vertices, m, count, "vertices") : py::reinterpret_borrow<py::object>(vertices),
                                   "vertices" + at);
    checkFaces(many ? itemOf(faces, m, count, "faces") : py::reinterpret_borrow<py::object>(faces), "faces" + at, mesh);
    const size_t faceCount = mesh.indices.size() / mesh.corners;
    checkColors(many ? itemOf(colors, m, count, "colors") : py::reinterpret_borrow<py::object>(colors),
                "colors" + at, faceCount, mesh);
    py::object id = instanceIds.is_none() ? py::object(py::int_(m)) : itemOf(instanceIds, m, count, "instance_ids");
    long long value = 0;
    try {
      value = id.cast<long long>();
    } catch (py::cast_error&) {
      valueError("instance_ids[" + std::to_string(m) + "]: expected an integer");
    }
    if (value < 0 || value > INT32_MAX)
      valueError("instance_ids[" + std::to_string(m) + "]: " + std::to_string(value) +
                 " is not in 0 to 2^31-1 (-1 marks the background)");
    mesh.instance = int32_t(value);
    py::object name = itemOf(names, m, count, "names");
    mesh.name = name.is_none() ? "mesh" + std::to_string(m) : py::str(name).cast<std::string>();
  }
  return meshes;
}

hsr::Scene buildScene(const std::vector<MeshArrays>& meshes) {
  hsr::Scene scene;
  scene.source = "arrays";
  uint64_t total = 0;
  for (const MeshArrays& mesh : meshes) total += mesh.positions.size();
  if (total > UINT32_MAX) valueError("vertices: more than 2^32 vertices in all");
  const hsr::Rgba8 grey{200, 200, 200, 255};  // the loaders' colour of faces without one
  for (const MeshArrays& mesh : meshes) {
    const uint32_t base = uint32_t(scene.positions.size());
    scene.beginMesh(mesh.name);
    scene.positions.insert(scene.positions.end(), mesh.positions.begin(), mesh.positions.end());
    std::vector<uint32_t> face(mesh.corners);
    for (size_t f = 0; f * mesh.corners < mesh.indices.size(); ++f) {
      for (size_t k = 0; k < mesh.corners; ++k) face[k] = base + mesh.indices[f * mesh.corners + k];
      const hsr::Rgba8 color = mesh.colors.empty() ? grey : mesh.colors[mesh.colors.size() == 1 ? 0 : f];
      scene.addFace(face, color);
    }
  }
  scene.finalize();
  return scene;
}

}  // namespace

std::shared_ptr<SceneData> sceneFromArrays(py::handle vertices, py::handle faces, py::handle colors,
                                                 py::handle instanceIds, py::handle names) {
  std::vector<MeshArrays> meshes = checkMeshes(vertices, faces, colors, instanceIds, names);
  std::vector<int32_t> instances;
  for (const MeshArrays& mesh : meshes) instances.push_back(mesh.instance);
  py::gil_scoped_release unlocked;
  return makeSceneData(buildScene(meshes), std::move(instances));
}

}  // namespace hsrpy

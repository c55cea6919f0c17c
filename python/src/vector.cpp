// hsr.screen_polygons: a list-priority algorithm's painting order as NumPy arrays of polygons on
// the image (hsr::screenPolygons, include/hsr/svg.hpp), what SVG output and hsr.matplotlib draw.
#include "options.hpp"

#include <cstring>

namespace hsrpy {

namespace {

py::dict screenPolygonsToArrays(const SceneData& scene, const PyCamera& pyCamera, const std::string& algorithm,
                                py::handle params, const std::string& cull, const std::string& shading) {
  hsr::RenderOptions options;
  const hsr::AlgorithmInfo* info = hsr::findAlgorithm(algorithm);
  if (!info || !hsr::paintsPolygons(algorithm)) {
    std::string known;
    for (const hsr::AlgorithmInfo& a : hsr::algorithms())
      if (hsr::paintsPolygons(a.name)) known += (known.empty() ? "" : ", ") + a.name;
    valueError("algorithm '" + algorithm + "': " + (info ? "paints no polygons" : "unknown") +
               " (the algorithms that paint polygons in order: " + known + ")");
  }
  options.algorithm = algorithm;
  options.params = paramsOf(params);
  hsr::resolveParams(*info, options.params);
  options.cull = cullOf(cull);
  options.shading = shadingOf(shading);
  const hsr::Camera camera = pyCamera.resolve(scene, "camera");
  hsr::ScreenPolygons painted;
  {
    py::gil_scoped_release unlocked;
    painted = hsr::screenPolygons(scene.scene, camera, options);
  }
  const py::ssize_t n = py::ssize_t(painted.polygons.size());
  py::ssize_t p = 0;
  for (const hsr::ScreenPolygon& s : painted.polygons) p += s.count;
  auto points = py::array_t<double>({p, py::ssize_t(2)});
  auto offsets = py::array_t<int64_t>(n + 1);
  auto faces = py::array_t<int32_t>(n);
  auto colors = py::array_t<uint8_t>({n, py::ssize_t(4)});
  auto groups = py::array_t<int32_t>(n);
  auto repaint = py::array_t<bool>(n);
  int64_t* offset = offsets.mutable_data();
  uint8_t* color = colors.mutable_data();
  offset[0] = 0;
  for (py::ssize_t i = 0; i < n; ++i) {
    const hsr::ScreenPolygon& s = painted.polygons[size_t(i)];
    offset[i + 1] = offset[i] + s.count;
    std::memcpy(points.mutable_data(offset[i]), &painted.points[s.first], s.count * sizeof(hsr::dvec2));
    faces.mutable_data()[i] = int32_t(s.face);
    groups.mutable_data()[i] = int32_t(s.group);
    repaint.mutable_data()[i] = s.repaint;
    std::memcpy(color + 4 * i, &s.color, 4);
  }
  using namespace pybind11::literals;
  return py::dict("points"_a = points, "offsets"_a = offsets, "face_id"_a = faces, "color"_a = colors,
                  "group"_a = groups, "repaint"_a = repaint);
}

}  // namespace

void bindVector(py::module_& m) {
  m.def("screen_polygons", &screenPolygonsToArrays, py::arg("scene"), py::arg("camera"), py::arg("algorithm") = "bsp",
        py::arg("params") = py::none(), py::arg("cull") = "none", py::arg("shading") = "lambert",
        R"(The painting order of a list-priority algorithm ("bsp", "newell" or "painter") for one
hsr.Camera: the scene's polygons back to front, split where the order needs it, clipped to the near
and far planes and to the image, in pixels (x right, y down) -- what `hsr render --svg` writes.
Returns a dict of NumPy arrays, polygon i being points[offsets[i]:offsets[i + 1]]:
  points    float64 (P, 2)  pixel coordinates
  offsets   int64 (N + 1,)
  face_id   int32 (N,)      the face each polygon is (a piece of)
  color     uint8 (N, 4)    its RGBA colour in `shading` ("lambert", "flat" or "faceid":
                            face index + 1 as 24-bit RGB)
  group     int32 (N,)      paint groups, 0, 1, ... in order: draw a group's polygons as ONE
                            shape (compound path, nonzero fill) and no seam shows where a
                            face was split
  repaint   bool (N,)       parts of earlier pieces of the face painted again with this group
params and cull ("none", "back", "front") are hsr.render's. Raises ValueError for an algorithm
that paints no polygons.)");
}

}  // namespace hsrpy

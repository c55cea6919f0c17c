// Many views of one scene, and what a visibility buffer tells about each pixel beyond its face id:
// the instance (mesh) it shows, the barycentric coordinates of its centre on the visible triangle
// and that triangle's normal. For users who render datasets (the Python module, `hsr render
// --instance-ids/--barycentric`); built on render() and the Frame, outside any algorithm.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <functional>
#include <span>
#include <vector>

namespace hsr {

/// Renders `scene` once per camera with `options`, the views spread over options.threads threads
/// (0: all cores): with at least as many views as threads, each thread renders whole views on
/// its own; with fewer, the views go one after another, each on every thread. Either way the
/// bits of every view are those of render(scene, cameras[i], options). `deliver(i, frame)` is
/// called once per view, on the thread that rendered it, with its frame (reused for that
/// thread's next view: copy out what is needed) and the number of threads it may use itself.
/// Views are delivered in no particular order. The first exception thrown by a render or by
/// `deliver` is rethrown once the views under way have finished; later views are not rendered.
using ViewSink = std::function<void(size_t view, const Frame& frame, int threads)>;
void renderViews(const Scene& scene, std::span<const Camera> cameras, const RenderOptions& options,
                 const ViewSink& deliver);
/// `target(i, frame)`, when given, is called before view i is rendered into `frame`, on the
/// thread that renders it: it may lend the frame's buffers memory of the caller's (lentBuffer),
/// so that the view is rendered straight into it.
using ViewTarget = std::function<void(size_t view, Frame& frame)>;
/// The same with frames the caller keeps from call to call (no buffers allocated once warm):
/// `frames` is resized to the frames the views need, one per thread rendering whole views.
void renderViews(const Scene& scene, std::span<const Camera> cameras, const RenderOptions& options,
                 const ViewSink& deliver, std::vector<Frame>& frames, const ViewTarget& target = {});

/// For each face of `scene`, the index of the mesh (Scene::meshes) it belongs to.
std::vector<int32_t> faceMeshIndices(const Scene& scene);

/// Per pixel: faceValue[frame.faceId] (e.g. an instance id per face), `background` where no face
/// shows. Needs the frame's face ids. Writes width * height values to `out`.
void resolveFaceValues(const Frame& frame, std::span<const int32_t> faceValue, int32_t background, int32_t* out,
                       int threads = 1);

/// Per pixel, the barycentric coordinates (b0, b1, b2) of the pixel centre on the visible
/// triangle (Scene::triangles[frame.triangleId], vertices v[0], v[1], v[2]): the point where the
/// ray through (x + 0.5, y + 0.5) meets the triangle's plane is b0 v0 + b1 v1 + b2 v2, with
/// b0 + b1 + b2 = 1 (computed in double, rounded to float once). On edge pixels a coordinate may
/// be slightly negative: coverage is decided on vertices snapped to 1/256 pixel. Background: 0.
/// Needs the frame's triangle ids. Writes 3 * width * height floats to `out`.
void resolveBarycentrics(const Scene& scene, const Camera& camera, const Frame& frame, float* out, int threads = 1);

/// Unit world-space normals of the scene's triangles, normalize((v1 - v0) x (v2 - v0)): the
/// front side is the one from which the triangle's vertices appear counter-clockwise.
std::vector<glm::vec3> triangleNormals(const Scene& scene);

/// Per pixel, normals[frame.triangleId] (3 floats), 0 on the background. Needs the frame's
/// triangle ids. Writes 3 * width * height floats to `out`.
void resolveNormals(std::span<const glm::vec3> normals, const Frame& frame, float* out, int threads = 1);

/// Writers of the attributes above (atomically, as io.hpp's): instance ids — faceValue[face id]
/// per pixel, -1 on the background — as face ids are written (.npy int32, or .png with id + 1 as
/// 24-bit RGB); barycentrics as .npy float32 of shape (height, width, 3).
void writeInstanceIds(const Frame& frame, std::span<const int32_t> faceValue, const std::string& path);
void writeBarycentrics(const Scene& scene, const Camera& camera, const Frame& frame, const std::string& path);
/// Throws InputError "path: ..." when the writer above does not know path's extension.
void checkInstanceIdsPath(const std::string& path);
void checkBarycentricsPath(const std::string& path);

}  // namespace hsr

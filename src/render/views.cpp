// Many views of one scene (renderViews) and the per-pixel attributes resolved from a visibility
// buffer: instance ids, barycentric coordinates, normals (include/hsr/views.hpp). Used by the
// Python module and the CLI's --instance-ids and --barycentric.
#include <hsr/views.hpp>

#include <hsr/io.hpp>
#include <hsr/render.hpp>

#include "core/parallel.hpp"
#include "io/encode.hpp"

#include <atomic>
#include <exception>
#include <mutex>
#include <optional>

namespace hsr {

namespace {

// The first exception of a parallel job, kept for the caller; later views are skipped.
class FirstError {
 public:
  bool raised() const { return raised_.load(std::memory_order_relaxed); }
  void keep() {
    std::lock_guard lock(m_);
    if (!error_) error_ = std::current_exception();
    raised_.store(true, std::memory_order_relaxed);
  }
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::mutex m_;
  std::exception_ptr error_;
  std::atomic<bool> raised_{false};
};

// Rows [0, height) of a frame over up to `threads` threads, fn(y) per row.
template <class Fn>
void forRows(const Frame& frame, int threads, Fn&& fn) {
  parallelFor(0, size_t(frame.height), threads, [&](size_t y) { fn(int(y)); });
}

void requireIds(bool present, const char* what) {
  if (!present) throw std::logic_error(std::string(what) + ": the frame was rendered without the ids it needs");
}

}  // namespace

void renderViews(const Scene& scene, std::span<const Camera> cameras, const RenderOptions& options,
                 const ViewSink& deliver) {
  std::vector<Frame> frames;
  renderViews(scene, cameras, options, deliver, frames);
}

void renderViews(const Scene& scene, std::span<const Camera> cameras, const RenderOptions& options,
                 const ViewSink& deliver, std::vector<Frame>& frames, const ViewTarget& target) {
  const int threads = resolveThreads(options.threads);
  if (cameras.size() < size_t(threads) || threads == 1) {
    frames.resize(1);  // one after another, each view on every thread
    Renderer renderer(scene, options);  // one algorithm object for every view
    for (size_t i = 0; i < cameras.size(); ++i) {
      if (target) target(i, frames[0]);
      renderer.render(cameras[i], frames[0]);
      deliver(i, frames[0], threads);
    }
    return;
  }
  // Whole views per thread: a frame and an algorithm object per thread, reused from view to view.
  RenderOptions single = options;
  single.threads = 1;
  frames.resize(static_cast<size_t>(threads));
  std::vector<std::optional<Renderer>> renderers(static_cast<size_t>(threads));
  FirstError error;
  runParallel(cameras.size(), threads, [&](size_t i) {
    if (error.raised()) return;
    try {
      const size_t part = currentPart();
      Frame& frame = frames[part];
      if (!renderers[part]) renderers[part].emplace(scene, single);
      if (target) target(i, frame);
      renderers[part]->render(cameras[i], frame);
      deliver(i, frame, 1);
    } catch (...) {
      error.keep();
    }
  });
  error.rethrow();
}

std::vector<int32_t> faceMeshIndices(const Scene& scene) {
  std::vector<int32_t> mesh(scene.faceCount(), -1);
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const MeshRange& r = scene.meshes[m];
    std::fill_n(mesh.begin() + r.firstFace, r.faceCount, int32_t(m));
  }
  return mesh;
}

void resolveFaceValues(const Frame& frame, std::span<const int32_t> faceValue, int32_t background, int32_t* out,
                       int threads) {
  requireIds(frame.faceId.size() == frame.index(0, frame.height), "resolveFaceValues");
  forRows(frame, threads, [&](int y) {
    const size_t row = frame.index(0, y);
    for (size_t i = row; i < row + size_t(frame.width); ++i) {
      const int32_t f = frame.faceId[i];
      out[i] = f >= 0 && size_t(f) < faceValue.size() ? faceValue[size_t(f)] : background;
    }
  });
}

void resolveBarycentrics(const Scene& scene, const Camera& camera, const Frame& frame, float* out, int threads) {
  requireIds(frame.triangleId.size() == frame.index(0, frame.height), "resolveBarycentrics");
  forRows(frame, threads, [&](int y) {
    for (int x = 0; x < frame.width; ++x) {
      const size_t i = frame.index(x, y);
      float* b = out + 3 * i;
      const int32_t t = frame.triangleId[i];
      b[0] = b[1] = b[2] = 0.0f;
      if (t < 0 || size_t(t) >= scene.triangles.size()) continue;  // background (or not a triangle of the scene)
      // Ray o + s dir through the pixel centre, in camera space, against the triangle's plane:
      // o + s dir = a + u (p1 - a) + v (p2 - a) (Moeller-Trumbore), all in double.
      const Triangle& tri = scene.triangles[size_t(t)];
      const dvec3 a = camera.toCamera(scene.positions[tri.v[0]]);
      const dvec3 e1 = camera.toCamera(scene.positions[tri.v[1]]) - a;
      const dvec3 e2 = camera.toCamera(scene.positions[tri.v[2]]) - a;
      dvec3 o, dir;
      camera.cameraRay(x + 0.5, y + 0.5, o, dir);
      const dvec3 p = glm::cross(dir, e2);
      const double det = glm::dot(e1, p);
      if (det == 0) continue;  // seen exactly edge-on: no point of the plane on the ray
      const dvec3 s = o - a;
      const double u = glm::dot(s, p) / det;
      const double v = glm::dot(dir, glm::cross(s, e1)) / det;
      b[0] = float(1.0 - u - v);
      b[1] = float(u);
      b[2] = float(v);
    }
  });
}

std::vector<glm::vec3> triangleNormals(const Scene& scene) {
  std::vector<glm::vec3> normals(scene.triangles.size());
  for (size_t t = 0; t < normals.size(); ++t) {
    const Triangle& tri = scene.triangles[t];
    const dvec3 a = scene.positions[tri.v[0]];
    const dvec3 n = glm::cross(scene.positions[tri.v[1]] - a, scene.positions[tri.v[2]] - a);
    const double length = glm::length(n);
    normals[t] = length > 0 ? glm::vec3(n / length) : glm::vec3(0.0f);
  }
  return normals;
}

void resolveNormals(std::span<const glm::vec3> normals, const Frame& frame, float* out, int threads) {
  requireIds(frame.triangleId.size() == frame.index(0, frame.height), "resolveNormals");
  forRows(frame, threads, [&](int y) {
    const size_t row = frame.index(0, y);
    for (size_t i = row; i < row + size_t(frame.width); ++i) {
      const int32_t t = frame.triangleId[i];
      const glm::vec3 n = t >= 0 && size_t(t) < normals.size() ? normals[size_t(t)] : glm::vec3(0.0f);
      out[3 * i] = n.x;
      out[3 * i + 1] = n.y;
      out[3 * i + 2] = n.z;
    }
  });
}

void checkInstanceIdsPath(const std::string& path) { checkOutputPath(OutputKind::FaceIds, path); }

void checkBarycentricsPath(const std::string& path) {
  if (io::extensionOf(path) != ".npy")
    throw InputError(path + ": barycentric coordinates are written as .npy (float32, height x width x 3)");
}

void writeInstanceIds(const Frame& frame, std::span<const int32_t> faceValue, const std::string& path) {
  checkInstanceIdsPath(path);
  Frame ids;  // the face-id writer, given the instance ids as its ids
  ids.width = frame.width;
  ids.height = frame.height;
  ids.faceId.resize(frame.faceId.size());
  resolveFaceValues(frame, faceValue, -1, ids.faceId.data());
  writeFaceIds(ids, path);
}

void writeBarycentrics(const Scene& scene, const Camera& camera, const Frame& frame, const std::string& path) {
  checkBarycentricsPath(path);
  std::vector<float> b(3 * size_t(frame.width) * size_t(frame.height));
  resolveBarycentrics(scene, camera, frame, b.data());
  io::writeBytes(io::encodeNpy("<f4", frame.height, frame.width, b.data(), 3), path);
}

}  // namespace hsr

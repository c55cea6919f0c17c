// hsr.render: one camera or a batch, the scene set up once, the views spread over the threads
// with the GIL released, every output handed to NumPy without a copy (buffers.hpp).
#include "buffers.hpp"
#include "options.hpp"

#include <hsr/limits.hpp>

#include <pybind11/stl.h>


#include <array>
#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <thread>
#include <utility>

namespace hsrpy {

namespace {

enum Output { Depth, FaceId, InstanceId, TriangleId, Barycentric, Normal, Color, Visibility, kOutputCount };
struct OutputInfo {
  const char* name;
  size_t channels;  // per pixel (1: an (H, W) image, else (H, W, channels); 0: per instance, not an image)
  size_t bytes;     // per channel
  const char* dtype;
};
constexpr OutputInfo kOutputs[kOutputCount] = {
    {"depth", 1, 4, "float32"},       {"face_id", 1, 4, "int32"}, {"instance_id", 1, 4, "int32"},
    {"triangle_id", 1, 4, "int32"},   {"barycentric", 3, 4, "float32"}, {"normal", 3, 4, "float32"},
    {"color", 4, 1, "uint8"},         {"visibility", 0, 0, ""}};
using Wanted = std::array<bool, kOutputCount>;

std::string outputNames() {
  std::string names;
  for (const OutputInfo& o : kOutputs) names += (names.empty() ? "" : ", ") + std::string(o.name);
  return names;
}

Wanted parseOutputs(py::handle outputs) {
  std::vector<std::string> names;
  if (py::isinstance<py::str>(outputs)) names.push_back(outputs.cast<std::string>());
  else
    try {
      names = outputs.cast<std::vector<std::string>>();
    } catch (py::cast_error&) {
      valueError("outputs: expected a name or a sequence of names (" + outputNames() + ")");
    }
  if (names.empty()) valueError("outputs: none asked for (" + outputNames() + ")");
  Wanted wanted{};
  for (const std::string& name : names) {
    int found = -1;
    for (int o = 0; o < kOutputCount; ++o)
      if (name == kOutputs[o].name) found = o;
    if (found < 0) valueError("outputs: unknown '" + name + "' (known: " + outputNames() + ")");
    wanted[size_t(found)] = true;
  }
  return wanted;
}

// What the z-buffer must resolve for the outputs (depth alone: the CLI's --outputs depth).
hsr::FrameOutputs frameOutputs(const Wanted& w) {
  uint8_t flags = 0;
  if (w[FaceId] || w[InstanceId] || w[Visibility]) flags |= uint8_t(hsr::FrameOutputs::FaceIds);
  if (w[TriangleId] || w[Barycentric] || w[Normal]) flags |= uint8_t(hsr::FrameOutputs::TriangleIds);
  if (w[Color]) flags |= uint8_t(hsr::FrameOutputs::Color);
  return hsr::FrameOutputs(flags);
}

hsr::Rgba8 backgroundOf(py::handle value) {
  std::vector<int> c;
  try {
    c = value.cast<std::vector<int>>();
  } catch (py::cast_error&) {
    valueError("background: expected (r, g, b) or (r, g, b, a), integers 0 to 255");
  }
  if (c.size() < 3 || c.size() > 4) valueError("background: expected (r, g, b) or (r, g, b, a), integers 0 to 255");
  for (int v : c)
    if (v < 0 || v > 255) valueError("background: components are integers 0 to 255");
  return {uint8_t(c[0]), uint8_t(c[1]), uint8_t(c[2]), uint8_t(c.size() == 4 ? c[3] : 255)};
}

hsr::RenderOptions optionsOf(const Wanted& wanted, const std::string& algorithm, py::handle params,
                             const std::string& depthFormat, const std::string& cull, const std::string& shading,
                             py::handle background, int threads) {
  hsr::RenderOptions o;
  o.algorithm = algorithm;
  const hsr::AlgorithmInfo* info = hsr::findAlgorithm(algorithm);
  if (!info) {
    std::string known;
    for (const hsr::AlgorithmInfo& a : hsr::algorithms()) known += (known.empty() ? "" : ", ") + a.name;
    valueError("algorithm '" + algorithm + "': unknown (known: " + known + ")");
  }
  o.params = paramsOf(params);
  hsr::resolveParams(*info, o.params);  // InputError keyed Param: pythonMessage words it
  if (!depthFormat.empty()) o.depthFormat = hsr::DepthFormat::parse(depthFormat);
  o.outputs = frameOutputs(wanted);
  o.cull = cullOf(cull);
  o.shading = shadingOf(shading);
  o.background = backgroundOf(background);
  if (threads < 0) valueError("threads: " + std::to_string(threads) + " is negative (0: all cores)");
  o.threads = threads;
  return o;
}

// The cameras resolved for the scene; `batch` when a sequence was given (even of one).
std::vector<hsr::Camera> camerasOf(const SceneData& data, py::handle cameras, bool& batch) {
  std::vector<hsr::Camera> out;
  batch = !py::isinstance<PyCamera>(cameras);
  if (!batch) {
    out.push_back(cameras.cast<const PyCamera&>().resolve(data, "camera"));
    return out;
  }
  if (!py::isinstance<py::sequence>(cameras) || py::isinstance<py::str>(cameras))
    valueError("cameras: expected an hsr.Camera or a sequence of them");
  py::sequence list = py::reinterpret_borrow<py::sequence>(cameras);
  if (list.size() == 0) valueError("cameras: an empty sequence");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string name = "cameras[" + std::to_string(i) + "]";
    if (!py::isinstance<PyCamera>(list[i])) valueError(name + ": not an hsr.Camera");
    out.push_back(list[i].cast<const PyCamera&>().resolve(data, name));
    if (out[i].width != out[0].width || out[i].height != out[0].height)
      valueError(name + ": " + std::to_string(out[i].width) + "x" + std::to_string(out[i].height) + ", but cameras[0] is " +
                 std::to_string(out[0].width) + "x" + std::to_string(out[0].height) + ": a batch has one image size");
  }
  return out;
}

// Refuses outputs larger than the memory limit (hsr.set_max_memory, by default the machine's
// available memory): MemoryError, before anything is allocated (Linux would promise the memory
// and kill the process when it is touched). The renders' own frames are checked by hsr::render.
void checkMemory(const Wanted& wanted, size_t views, const hsr::Camera& camera) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  double bytes = 0;
  for (int o = 0; o < kOutputCount; ++o)
    if (wanted[size_t(o)]) bytes += double(views) * double(pixels) * double(kOutputs[o].channels * kOutputs[o].bytes);
  try {
    hsr::checkMemory(bytes, "render: the outputs of " + std::to_string(views) + " view(s) of " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  } catch (const hsr::InputError& e) {
    PyErr_SetString(PyExc_MemoryError, pythonMessage(e).c_str());
    throw py::error_already_set();
  }
}

// Where view `view`'s outputs go: one block per output, views one after another.
struct Blocks {
  std::array<RawBlock, kOutputCount> block;
  size_t pixels = 0;
  template <class T>
  T* at(Output o, size_t view) const {
    if (!block[o].data()) return nullptr;
    const size_t viewBytes = pixels * kOutputs[o].channels * kOutputs[o].bytes;
    return reinterpret_cast<T*>(static_cast<uint8_t*>(block[o].data()) + view * viewBytes);
  }
};

Blocks allocate(const Wanted& wanted, size_t views, size_t pixels) {
  Blocks b;
  b.pixels = pixels;
  for (int o = 0; o < kOutputCount; ++o)
    if (wanted[size_t(o)] && kOutputs[o].channels)
      b.block[size_t(o)] = takeBlock(views * pixels * kOutputs[o].channels * kOutputs[o].bytes);
  return b;
}

// The outputs hsr resolves from the visibility buffer itself, into the blocks of view `view`.
void resolveAttributes(const SceneData& d, const hsr::Camera& camera, const hsr::Frame& frame, const Blocks& out,
                       size_t view, int threads) {
  if (int32_t* p = out.at<int32_t>(InstanceId, view)) hsr::resolveFaceValues(frame, d.faceInstance, -1, p, threads);
  if (float* p = out.at<float>(Barycentric, view)) hsr::resolveBarycentrics(d.scene, camera, frame, p, threads);
  if (float* p = out.at<float>(Normal, view)) hsr::resolveNormals(d.normals(), frame, p, threads);
}

// Whether view after view of output o lies in its block on a cache line, as the frame's buffers
// do (the tile kernel writes whole lines with streaming stores): then the frame is lent it.
bool lendable(const Blocks& out, Output o) {
  const size_t viewBytes = out.pixels * kOutputs[o].channels * kOutputs[o].bytes;
  return out.block[o].data() && reinterpret_cast<uintptr_t>(out.block[o].data()) % 64 == 0 && viewBytes % 64 == 0;
}

// The frame's buffers lent the blocks of view `view`, where lendable (batches): the view is
// rendered straight into the arrays.
void lendFrame(hsr::Frame& frame, const Blocks& out, size_t view) {
  auto lend = [&]<class T>(hsr::FrameBuffer<T>& buffer, Output o) {
    if (!lendable(out, o)) return;
    BufferPool::instance().give(std::exchange(buffer, hsr::lentBuffer(out.at<T>(o, view), out.pixels)));
  };
  lend(frame.depth, Depth);
  lend(frame.faceId, FaceId);
  lend(frame.triangleId, TriangleId);
  lend(frame.color, Color);
}

// The frame's buffers not rendered straight into the blocks of view `view`, copied there.
void copyFrame(const hsr::Frame& frame, const Blocks& out, size_t view) {
  auto copy = [&](Output o, const void* from) {
    void* to = out.at<uint8_t>(o, view);
    if (to && to != from) std::memcpy(to, from, out.pixels * kOutputs[o].channels * kOutputs[o].bytes);
  };
  copy(Depth, frame.depth.data());
  copy(FaceId, frame.faceId.data());
  copy(TriangleId, frame.triangleId.data());
  copy(Color, frame.color.data());
}

int threadsOf(const hsr::RenderOptions& options) {
  return options.threads > 0 ? options.threads : int(std::max(1u, std::thread::hardware_concurrency()));
}

std::vector<py::ssize_t> shapeOf(Output o, std::vector<py::ssize_t> image) {
  if (kOutputs[o].channels > 1) image.push_back(py::ssize_t(kOutputs[o].channels));
  return image;
}

// A frame whose buffers come from the pool where it has them (render() sizes them).
hsr::Frame pooledFrame(const hsr::Camera& camera, hsr::FrameOutputs outputs) {
  BufferPool& pool = BufferPool::instance();
  const size_t n = size_t(camera.width) * size_t(camera.height);
  hsr::Frame frame;
  frame.depth = pool.take<hsr::FrameBuffer<float>>(n);
  if (has(outputs, hsr::FrameOutputs::FaceIds)) frame.faceId = pool.take<hsr::FrameBuffer<int32_t>>(n);
  if (has(outputs, hsr::FrameOutputs::TriangleIds)) frame.triangleId = pool.take<hsr::FrameBuffer<int32_t>>(n);
  if (has(outputs, hsr::FrameOutputs::Color)) frame.color = pool.take<hsr::FrameBuffer<hsr::Rgba8>>(n);
  return frame;
}

// The frame's buffers back to the pool (lent ones are dropped: BufferPool::give).
void releaseFrame(hsr::Frame& frame) {
  BufferPool& pool = BufferPool::instance();
  pool.give(std::move(frame.depth));
  pool.give(std::move(frame.faceId));
  pool.give(std::move(frame.triangleId));
  pool.give(std::move(frame.color));
}

// "visibility": per instance of the scene (sorted by id), its pixels covered alone, visible, and
// their ratio, as a NumPy structured array with the BOP toolkit's names; views first in a batch.
struct VisibilityRow {
  int32_t instance;
  int32_t unused;
  int64_t all, visible;
  double fraction;
};
using ViewVisibility = std::vector<hsr::InstanceVisibility>;

py::array visibilityArray(const std::vector<ViewVisibility>& views, bool batch) {
  const py::dtype dtype(py::list(py::make_tuple("instance_id", "px_count_all", "px_count_visib", "visib_fract")),
                        py::list(py::make_tuple("<i4", "<i8", "<i8", "<f8")),
                        py::list(py::make_tuple(offsetof(VisibilityRow, instance), offsetof(VisibilityRow, all),
                                                offsetof(VisibilityRow, visible), offsetof(VisibilityRow, fraction))),
                        py::ssize_t(sizeof(VisibilityRow)));
  const size_t instances = views.empty() ? 0 : views[0].size();
  std::vector<py::ssize_t> shape{py::ssize_t(instances)};
  if (batch) shape.insert(shape.begin(), py::ssize_t(views.size()));
  py::array out(dtype, shape);
  auto* rows = static_cast<VisibilityRow*>(out.mutable_data());
  for (const ViewVisibility& view : views)
    for (const hsr::InstanceVisibility& v : view)
      *rows++ = {v.instance, 0, int64_t(v.pixelsAlone), int64_t(v.pixelsVisible), v.fraction()};
  return out;
}

// The counts of one view (options.threads threads).
ViewVisibility visibilityOf(const SceneData& d, const hsr::Camera& camera, const hsr::RenderOptions& options,
                            const hsr::Frame& frame, int threads) {
  hsr::RenderOptions counted = options;
  counted.threads = threads;
  return d.countVisibility(camera, counted, frame);
}

py::dict renderOne(const SceneData& d, const hsr::Camera& camera, const hsr::RenderOptions& options, const Wanted& wanted) {
  hsr::Frame frame = pooledFrame(camera, options.outputs);
  Wanted attributes = wanted;
  attributes[Depth] = attributes[FaceId] = attributes[TriangleId] = attributes[Color] = false;
  Blocks blocks;
  std::vector<ViewVisibility> visibility;
  {
    py::gil_scoped_release unlocked;
    d.render(camera, options, frame);
    blocks = allocate(attributes, 1, frame.depth.size());
    resolveAttributes(d, camera, frame, blocks, 0, threadsOf(options));
    if (wanted[Visibility]) visibility.push_back(visibilityOf(d, camera, options, frame, options.threads));
  }
  const std::vector<py::ssize_t> image{frame.height, frame.width};
  py::dict result;
  for (int o = 0; o < kOutputCount; ++o) {
    if (!wanted[size_t(o)]) continue;
    const Output out = Output(o);
    if (out == Visibility) {
      result[kOutputs[o].name] = visibilityArray(visibility, false);
      continue;
    }
    const py::dtype dtype(kOutputs[o].dtype);
    py::array a;
    switch (out) {
      case Depth: a = handOver(std::move(frame.depth), image, dtype); break;
      case FaceId: a = handOver(std::move(frame.faceId), image, dtype); break;
      case TriangleId: a = handOver(std::move(frame.triangleId), image, dtype); break;
      case Color: a = handOver(std::move(frame.color), shapeOf(out, image), dtype); break;
      default: a = handOver(std::move(blocks.block[size_t(o)]), shapeOf(out, image), dtype);
    }
    result[kOutputs[o].name] = a;
  }
  return result;
}

py::dict renderBatch(const SceneData& d, const std::vector<hsr::Camera>& cameras, const hsr::RenderOptions& options,
                     const Wanted& wanted) {
  const size_t pixels = size_t(cameras[0].width) * size_t(cameras[0].height);
  Blocks blocks;
  std::vector<ViewVisibility> visibility(wanted[Visibility] ? cameras.size() : 0);
  {
    py::gil_scoped_release unlocked;
    blocks = allocate(wanted, cameras.size(), pixels);
    std::vector<hsr::Frame> frames(size_t(threadsOf(options)));
    for (hsr::Frame& f : frames) f = pooledFrame(cameras[0], options.outputs);
    hsr::renderViews(
        d.scene, cameras, options,
        [&](size_t view, const hsr::Frame& frame, int threads) {
          copyFrame(frame, blocks, view);
          resolveAttributes(d, cameras[view], frame, blocks, view, threads);
          if (!visibility.empty()) visibility[view] = visibilityOf(d, cameras[view], options, frame, threads);
        },
        frames, [&](size_t view, hsr::Frame& frame) { lendFrame(frame, blocks, view); });
    for (hsr::Frame& f : frames) releaseFrame(f);
  }
  const std::vector<py::ssize_t> image{py::ssize_t(cameras.size()), cameras[0].height, cameras[0].width};
  py::dict result;
  for (int o = 0; o < kOutputCount; ++o)
    if (wanted[size_t(o)] && o == Visibility) result[kOutputs[o].name] = visibilityArray(visibility, true);
    else if (wanted[size_t(o)])
      result[kOutputs[o].name] =
          handOver(std::move(blocks.block[size_t(o)]), shapeOf(Output(o), image), py::dtype(kOutputs[o].dtype));
  return result;
}

}  // namespace

py::dict renderToArrays(const SceneData& scene, py::handle cameras, py::handle outputs, const std::string& algorithm,
                        py::handle params, const std::string& depthFormat, const std::string& cull,
                        const std::string& shading, py::handle background, int threads) {
  const Wanted wanted = parseOutputs(outputs);
  const hsr::RenderOptions options = optionsOf(wanted, algorithm, params, depthFormat, cull, shading, background, threads);
  bool batch = false;
  const std::vector<hsr::Camera> resolved = camerasOf(scene, cameras, batch);
  checkMemory(wanted, resolved.size(), resolved[0]);
  return batch ? renderBatch(scene, resolved, options, wanted) : renderOne(scene, resolved[0], options, wanted);
}

}  // namespace hsrpy

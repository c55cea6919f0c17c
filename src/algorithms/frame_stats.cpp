// What every algorithm's frame starts and ends with (algorithms.hpp): its statistics begun,
// its image size checked, the frame's own buffers counted in its memory. Used by the registry's
// algorithms, the occlusion buffer and render().
#include <hsr/limits.hpp>

#include "algorithms/algorithms.hpp"

namespace hsr {

void algo::beginStats(Stats& st, const Scene& scene, const Camera& camera) {
  // A fresh Stats, but the storage of its lists kept: a warm frame allocates none for them.
  auto times = std::move(st.time_ms);
  auto params = std::move(st.params);
  auto details = std::move(st.details);
  auto memory = std::move(st.memory);
  st = Stats{};
  st.time_ms = std::move(times);
  st.params = std::move(params);
  st.details = std::move(details);
  st.memory = std::move(memory);
  st.memory.clear();
  st.time_ms.clear();
  st.params.clear();
  st.details.clear();
  st.width = camera.width;
  st.height = camera.height;
  st.faces = scene.faceCount();
  st.triangles = scene.triangles.size();
}

void algo::checkImage(const Camera& camera, DepthFormat format) {
  if (camera.width <= 0 || camera.height <= 0 || camera.width > kMaxImageSize || camera.height > kMaxImageSize)
    throw InputError(Setting::Size, std::to_string(camera.width) + "x" + std::to_string(camera.height),
                     "width and height must be in 1.." + std::to_string(kMaxImageSize));
  if (format.mapping == DepthMapping::Inv && !(camera.near > 0))
    throw InputError(Setting::DepthFormat, "", "the inv mapping needs near > 0");
}

void algo::addFrameMemory(Stats& st, const Frame& frame) {
  st.addMemory("frame.depth", frame.depth.size() * sizeof(float));
  st.addMemory("frame.face_id", frame.faceId.size() * sizeof(int32_t));
  st.addMemory("frame.triangle_id", frame.triangleId.size() * sizeof(int32_t));
  st.addMemory("frame.color", frame.color.size() * sizeof(Rgba8));
  st.addMemory("frame.writes", frame.writes.size() * sizeof(WriteCount));
}

}  // namespace hsr

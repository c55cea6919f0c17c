// Per-instance visibility (include/hsr/visibility.hpp): the front end's set-up triangles in an
// order grouped by instance, binned into bands of rows and covered band by band (the centres
// set-up listed for a small box, else the reference half-space rasterizer; no depth), each pixel
// stamped with the last instance that counted it; the visible pixels from the frame's face ids.
#include <hsr/threads.hpp>
#include <hsr/visibility.hpp>

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <string>
#include <utility>

#include "algorithms/draw.hpp"
#include "core/parallel.hpp"
#include "frontend/frontend.hpp"
#include "raster/halfspace.hpp"

namespace hsr {

namespace {

// The height of a band of rows, in pixels: the unit of work, each band's pixels its own.
constexpr int kBand = 16;

// The instances of a scene, sorted, and each face's index among them (-1: none).
struct Slots {
  std::vector<int32_t> ids;
  std::vector<int32_t> ofFace;
};

Slots slotsOf(std::span<const int32_t> faceInstance) {
  Slots s;
  for (int32_t id : faceInstance)
    if (id >= 0) s.ids.push_back(id);
  std::sort(s.ids.begin(), s.ids.end());
  s.ids.erase(std::unique(s.ids.begin(), s.ids.end()), s.ids.end());
  s.ofFace.reserve(faceInstance.size());
  for (int32_t id : faceInstance)
    s.ofFace.push_back(id < 0 ? -1 : int32_t(std::lower_bound(s.ids.begin(), s.ids.end(), id) - s.ids.begin()));
  return s;
}

}  // namespace

// What a counter keeps from view to view: the instances, and the buffers of one view.
struct VisibilityCounter::State {
  const Scene* scene;
  Slots slots;
  FrontEndOutput fe;                      // the set-up triangles
  std::vector<const SetupTriangle*> tris;  // every set-up triangle (index g), submission order
  std::vector<int32_t> slotOf;            // per g: its instance slot, -1 for none
  std::vector<size_t> start;              // per slot: where its triangles start in `order`
  std::vector<uint32_t> order;            // g grouped by instance, when submission order is not
  std::vector<std::vector<uint32_t>> bins;  // per band of rows: the g whose pixel box meets it, in order
  std::vector<std::vector<uint32_t>> stamps;  // per band: 1 + the slot that counted each pixel last, 0 = none
  std::vector<std::vector<std::pair<uint32_t, uint64_t>>> runs;  // per band: (slot, pixels) per instance met

  // Per slot, the pixels its triangles cover alone (instanceVisibility).
  std::vector<uint64_t> pixelsAlone(const Camera& camera, const RenderOptions& options);
};

std::vector<uint64_t> VisibilityCounter::State::pixelsAlone(const Camera& camera, const RenderOptions& options) {
  RenderOptions setUp = options;
  setUp.outputs = FrameOutputs::DepthOnly;  // coverage only: the front end shades nothing
  runFrontEnd(*scene, camera, setUp, fe);

  const size_t instances = slots.ids.size();
  tris.clear();
  slotOf.clear();
  fe.forEach([&](const SetupTriangle& t) {
    tris.push_back(&t);
    slotOf.push_back(slots.ofFace[t.face]);
  });
  // The order grouped by instance, submission order within one: as submitted when each
  // instance's triangles come in one run (an instance per mesh), else a counting sort.
  start.assign(instances + 1, 0);
  bool grouped = true;
  for (size_t g = 0; g < slotOf.size(); ++g)
    if (const int32_t s = slotOf[g]; s >= 0) {
      grouped &= start[size_t(s) + 1] == 0 || slotOf[g - 1] == s;
      ++start[size_t(s) + 1];
    }
  if (!grouped) {
    for (size_t i = 0; i < instances; ++i) start[i + 1] += start[i];
    order.resize(start[instances]);
    for (size_t g = 0; g < slotOf.size(); ++g)
      if (slotOf[g] >= 0) order[start[size_t(slotOf[g])]++] = uint32_t(g);
  }

  // Each band of rows gets the triangles whose pixel box meets it, in that order.
  const size_t bandCount = size_t((camera.height + kBand - 1) / kBand);
  bins.resize(bandCount);
  stamps.resize(bandCount);
  runs.resize(bandCount);
  for (size_t b = 0; b < bandCount; ++b) bins[b].clear();
  auto bin = [&](uint32_t g) {
    if (slotOf[g] < 0) return;
    for (int b = tris[g]->minY / kBand; b <= tris[g]->maxY / kBand; ++b) bins[size_t(b)].push_back(g);
  };
  if (grouped)
    for (uint32_t g = 0; g < tris.size(); ++g) bin(g);
  else
    for (const uint32_t g : order) bin(g);

  // Band by band (each band's pixels its own), a run of (slot, pixels) per instance met there.
  parallelFor(0, bandCount, resolveThreads(options.threads), [&](size_t band) {
    const int y0 = int(band) * kBand, y1 = std::min(y0 + kBand, camera.height) - 1, x1 = camera.width - 1;
    std::vector<uint32_t>& stamp = stamps[band];
    stamp.assign(size_t(camera.width) * kBand, 0);
    runs[band].clear();
    uint32_t stampOf = 0;
    uint64_t count = 0;
    auto cover = [&](int x, int y) {
      uint32_t& s = stamp[size_t(y - y0) * size_t(camera.width) + size_t(x)];
      if (s == stampOf) return;
      s = stampOf;
      ++count;
    };
    for (const uint32_t g : bins[band]) {
      if (uint32_t(slotOf[g]) + 1 != stampOf) {
        if (count) runs[band].emplace_back(stampOf - 1, count);
        stampOf = uint32_t(slotOf[g]) + 1;
        count = 0;
      }
      const SetupTriangle& t = *tris[g];
      if (t.coverage) {  // a small box whose covered centres set-up listed: those in the band
        for (unsigned left = t.coverage; left; left &= left - 1) {
          const int bit = std::countr_zero(left), y = t.minY + bit / kCoverageBox;
          if (y >= y0 && y <= y1) cover(t.minX + bit % kCoverageBox, y);
        }
        continue;
      }
      rasterizeHalfSpace(algo::clippedTo(t, 0, y0, x1, y1), [&](int x, int y, double) { cover(x, y); });
    }
    if (count) runs[band].emplace_back(stampOf - 1, count);
  });
  std::vector<uint64_t> alone(instances, 0);
  for (size_t b = 0; b < bandCount; ++b)
    for (const auto& [slot, count] : runs[b]) alone[slot] += count;
  return alone;
}

VisibilityCounter::VisibilityCounter(const Scene& scene, std::span<const int32_t> faceInstance) {
  if (faceInstance.size() != scene.faceCount())
    throw std::invalid_argument("instanceVisibility: " + std::to_string(faceInstance.size()) +
                                " instance ids for " + std::to_string(scene.faceCount()) + " faces");
  state_ = std::make_unique<State>();
  state_->scene = &scene;
  state_->slots = slotsOf(faceInstance);
}

VisibilityCounter::~VisibilityCounter() = default;
VisibilityCounter::VisibilityCounter(VisibilityCounter&&) noexcept = default;
VisibilityCounter& VisibilityCounter::operator=(VisibilityCounter&&) noexcept = default;

std::vector<InstanceVisibility> VisibilityCounter::count(const Camera& camera, const RenderOptions& options,
                                                         const Frame& frame) {
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  if (frame.width != camera.width || frame.height != camera.height || frame.faceId.size() != pixels)
    throw std::invalid_argument("instanceVisibility: the frame is not a view of this camera with face ids");
  const Slots& slots = state_->slots;
  const std::vector<uint64_t> alone = state_->pixelsAlone(camera, options);
  std::vector<InstanceVisibility> out(slots.ids.size());
  for (size_t s = 0; s < out.size(); ++s) {
    out[s].instance = slots.ids[s];
    out[s].pixelsAlone = alone[s];
  }
  for (const int32_t face : frame.faceId)
    if (face >= 0 && size_t(face) < slots.ofFace.size())
      if (const int32_t s = slots.ofFace[size_t(face)]; s >= 0) ++out[size_t(s)].pixelsVisible;
  return out;
}

std::vector<InstanceVisibility> instanceVisibility(const Scene& scene, const Camera& camera,
                                                   const RenderOptions& options, const Frame& frame,
                                                   std::span<const int32_t> faceInstance) {
  return VisibilityCounter(scene, faceInstance).count(camera, options, frame);
}

}  // namespace hsr

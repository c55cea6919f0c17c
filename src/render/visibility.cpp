// Per-instance visibility (include/hsr/visibility.hpp): the front end's set-up triangles grouped
// by instance, binned into cells and covered cell by cell (the centres set-up listed for a small
// box, else the reference half-space rasterizer; no depth), each pixel stamped with the last
// instance that counted it; the visible pixels from the frame's face ids.
#include <hsr/threads.hpp>
#include <hsr/visibility.hpp>

#include <algorithm>
#include <array>
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

// The side of a cell, in pixels: a cell's stamps (16 KB) stay in a core's L1 cache.
constexpr int kCell = 64;

// The instances of a frame, sorted, and each face's index among them (-1: none).
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

// Per instance slot, the pixels its triangles cover alone: see instanceVisibility.
std::vector<uint64_t> pixelsAlone(const Scene& scene, const Camera& camera, const RenderOptions& options,
                                  const Slots& slots) {
  RenderOptions setUp = options;
  setUp.outputs = FrameOutputs::DepthOnly;  // coverage only: the front end shades nothing
  FrontEndOutput fe;
  runFrontEnd(scene, camera, setUp, fe);

  // The set-up triangles grouped by instance (a counting sort: submission order within one).
  const size_t instances = slots.ids.size();
  std::vector<size_t> start(instances + 1, 0);
  fe.forEach([&](const SetupTriangle& t) {
    if (const int32_t s = slots.ofFace[t.face]; s >= 0) ++start[size_t(s) + 1];
  });
  for (size_t i = 0; i < instances; ++i) start[i + 1] += start[i];
  std::vector<SetupTriangle> grouped(start[instances]);
  std::vector<uint32_t> slotOf(grouped.size());
  fe.forEach([&](const SetupTriangle& t) {
    if (const int32_t s = slots.ofFace[t.face]; s >= 0) {
      const size_t at = start[size_t(s)]++;
      grouped[at] = t;
      slotOf[at] = uint32_t(s);
    }
  });

  // Cell by cell (each cell's pixels its own), a run of (slot, pixels) per instance met there.
  const int columns = (camera.width + kCell - 1) / kCell, rows = (camera.height + kCell - 1) / kCell;
  const std::vector<std::vector<uint32_t>> bins = algo::binByCell(grouped, kCell, kCell, columns, rows);
  std::vector<std::vector<std::pair<uint32_t, uint64_t>>> runs(bins.size());
  parallelFor(0, bins.size(), resolveThreads(options.threads), [&](size_t cell) {
    const int x0 = int(cell % size_t(columns)) * kCell, y0 = int(cell / size_t(columns)) * kCell;
    const int x1 = std::min(x0 + kCell, camera.width) - 1, y1 = std::min(y0 + kCell, camera.height) - 1;
    // Per pixel of the cell: 1 + the slot that counted it last, 0 = none.
    std::array<uint32_t, size_t(kCell) * kCell> stamp{};
    uint32_t stampOf = 0;
    uint64_t count = 0;
    for (const uint32_t i : bins[cell]) {
      if (slotOf[i] + 1 != stampOf) {
        if (count) runs[cell].emplace_back(stampOf - 1, count);
        stampOf = slotOf[i] + 1;
        count = 0;
      }
      auto cover = [&](int x, int y) {
        uint32_t& s = stamp[size_t(y - y0) * kCell + size_t(x - x0)];
        if (s == stampOf) return;
        s = stampOf;
        ++count;
      };
      const SetupTriangle& t = grouped[i];
      if (t.coverage) {  // a small box whose covered centres set-up listed: those in the cell
        for (unsigned left = t.coverage; left; left &= left - 1) {
          const int bit = std::countr_zero(left), x = t.minX + bit % kCoverageBox, y = t.minY + bit / kCoverageBox;
          if (x >= x0 && x <= x1 && y >= y0 && y <= y1) cover(x, y);
        }
        continue;
      }
      rasterizeHalfSpace(algo::clippedTo(t, x0, y0, x1, y1), [&](int x, int y, double) { cover(x, y); });
    }
    if (count) runs[cell].emplace_back(stampOf - 1, count);
  });
  std::vector<uint64_t> alone(instances, 0);
  for (const auto& cellRuns : runs)
    for (const auto& [slot, count] : cellRuns) alone[slot] += count;
  return alone;
}

}  // namespace

std::vector<InstanceVisibility> instanceVisibility(const Scene& scene, const Camera& camera,
                                                   const RenderOptions& options, const Frame& frame,
                                                   std::span<const int32_t> faceInstance) {
  if (faceInstance.size() != scene.faceCount())
    throw std::invalid_argument("instanceVisibility: " + std::to_string(faceInstance.size()) +
                                " instance ids for " + std::to_string(scene.faceCount()) + " faces");
  const size_t pixels = size_t(camera.width) * size_t(camera.height);
  if (frame.width != camera.width || frame.height != camera.height || frame.faceId.size() != pixels)
    throw std::invalid_argument("instanceVisibility: the frame is not a view of this camera with face ids");
  const Slots slots = slotsOf(faceInstance);
  const std::vector<uint64_t> alone = pixelsAlone(scene, camera, options, slots);
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

}  // namespace hsr

// Triangle set-up: projected vertices in, SetupTriangles (with nearest depth bounds and deferred
// back faces) out — one at a time (setupTriangle, frontend.cpp: the reference, and clipped pieces)
// or in SIMD batches (setupBatch, setup_batch.cpp: bit for bit the same). Called by the front
// end's workers and by the tiled rasterizer's tile pass (deferred faces and clusters set up late).
#pragma once
#include <hsr/options.hpp>

#include <cstddef>
#include <cstdint>

#include "frontend/chunks.hpp"
#include "frontend/vertices.hpp"
#include "setup/fragment_depth.hpp"
#include "setup/setup_triangle.hpp"

namespace hsr {

/// Sets up one triangle whose vertices are inside the clip volume: culls and fills `t`.
/// Returns false, counting the reason in `counters`, when it draws nothing.
bool setupTriangle(const ProjectedVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t);
/// The same from homogeneous coordinates (projects first).
bool setupTriangle(const HVertex* v, uint32_t triIndex, uint32_t face, const Camera& cam, Cull cull,
                   FrontEndCounters& counters, SetupTriangle& t);

/// Lanes of the batched set-up (at most; fewer on narrower instruction sets).
inline constexpr size_t kSetupBatch = 8;

/// setupTriangle() for `count` triangles inside the clip volume at once, with SIMD
/// (frontend/setup_batch.cpp): triangle i has vertices projected[vertex[0..2][i]], scene index
/// triIndex[i] and face face[i]. Writes the survivors to out[0, n), in order, and returns n;
/// the SetupTriangles (colour aside) and counters are bit for bit those of setupTriangle().
/// What else setupBatch computes, and how (see SetupBatchOptions' fields).
struct SetupBatchOptions {
  /// With `depth`, also nearest[0, n): nearestStored(out[i], *depth), bit for bit.
  const DepthSetup* depth = nullptr;
  double* nearest = nullptr;
  /// With `deferred` (and `depth`), the back faces whose pixel box lies in one kDeferTile
  /// square go to deferred[0, *deferredCount) as DeferredFaces instead (in order; not counted
  /// in the result).
  DeferredFace* deferred = nullptr;
  size_t* deferredCount = nullptr;
  /// With a cull: the facing test runs over all the triangles first and only those it keeps
  /// are set up. Faster when many are culled, slower when few are; the output is the same.
  bool cullFirst = false;
};
size_t setupBatch(const ProjectedVertex* projected, const uint32_t* const* vertex, const uint32_t* triIndex,
                  const uint32_t* face, size_t count, const Camera& cam, Cull cull, FrontEndCounters& counters,
                  SetupTriangle* out, const SetupBatchOptions& options = {});

}  // namespace hsr

// The front end's pipeline: runFrontEnd (or runVertexPass, then runSetUp) turns a scene and a
// camera into chunks of SetupTriangles in submission order (frontend/chunks.hpp), for every
// rasterizing algorithm. Called from one thread; it spreads the chunks over the thread pool
// (core/parallel.hpp) and hands each finished chunk to an optional consumer on that worker.
//
// The stages: world -> homogeneous pixel coordinates (double, relative to the camera), clipping
// (near, far, guard band), perspective divide, snapping to 1/256 pixel, culling and triangle
// set-up (integer edge functions with the top-left rule, depth planes). The consumer runs while
// the chunk is still in its core's cache (the tiled rasterizer bins it there).
#pragma once
#include <hsr/options.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "frontend/chunks.hpp"
#include "setup/fragment_depth.hpp"

namespace hsr {

/// Called on a worker thread with each chunk's index as soon as the chunk is set up; chunks may
/// finish in any order and concurrently, so a consumer writes only to its chunk's own data.
using ChunkConsumer = std::function<void(size_t chunk)>;

/// Scene triangles [first, end).
struct TriangleRange {
  uint32_t first, end;
};

/// What runFrontEnd and runSetUp produce besides the set-up triangles, and which triangles they
/// set up. The defaults: set-up triangles only, for every scene triangle.
struct FrontEndOptions {
  /// Every chunk's `nearest` holds the triangles' nearest bounds in this depth setup.
  const DepthSetup* nearestFor = nullptr;
  /// With `nearestFor`: the back faces setupBatch can defer go to the chunks' `deferred` lists,
  /// and the clusters that face away from the eye (deferCluster) to their `clusters` lists,
  /// instead of `triangles`.
  bool deferBackFaces = false;
  /// Whether whole clusters are deferred (with deferBackFaces) or, with RenderOptions::cull ==
  /// Cull::Back, culled whole when cullCluster accepts them.
  bool deferClusters = true;
  /// Only these triangles are set up (sorted, disjoint ranges, each a union of whole meshes, so
  /// no cluster is split): the chunks stay the same, the others are left out as if culled,
  /// uncounted.
  const std::vector<TriangleRange>* only = nullptr;
};

/// Runs the front end over all scene triangles, in order, on up to options.threads threads; the
/// work is split into fixed chunks, so the output never depends on the thread count.
/// `out` is reused across frames. `consumer`, when given, is called once per chunk (see
/// ChunkConsumer), before runFrontEnd returns. `frontEnd`: see FrontEndOptions, e.g.
/// runFrontEnd(scene, cam, opt, fe, consumer, {.nearestFor = &depth, .deferBackFaces = true}).
void runFrontEnd(const Scene& scene, const Camera& camera, const RenderOptions& options, FrontEndOutput& out,
                 const ChunkConsumer& consumer = {}, const FrontEndOptions& frontEnd = {});

/// runFrontEnd in two steps: the vertex pass (every vertex transformed, projected where inside
/// the clip volume; meshes outside it culled whole), into `out`; then set-up (and the consumer)
/// reading `vertices`, the output of a vertex pass with the same scene, camera and options,
/// into `out`'s chunks and counters (`out` may be `vertices`), as FrontEndOptions asks.
/// `meshConsumer`, when given, is called with runs [first, last) of meshes whose view test
/// (FrontEndOutput::meshCulled) is done, on the worker that did it, while the vertex pass goes on.
/// With `vertices` false, only the meshes are tested: the caller transforms the vertices it
/// needs (transformVertices into `out.outcodes` and `out.projected`, sized here) before set-up.
using MeshConsumer = std::function<void(size_t first, size_t last)>;
void runVertexPass(const Scene& scene, const Camera& camera, const RenderOptions& options, FrontEndOutput& out,
                   const MeshConsumer& meshConsumer = {}, bool vertices = true);
void runSetUp(const Scene& scene, const Camera& camera, const RenderOptions& options, const FrontEndOutput& vertices,
              FrontEndOutput& out, const ChunkConsumer& consumer = {}, const FrontEndOptions& frontEnd = {});

}  // namespace hsr

// The geometry front end shared by every rasterizing algorithm: world -> homogeneous pixel
// coordinates (double, relative to the camera), clipping (near, far, guard band), perspective
// divide, snapping to 1/256 pixel, culling and triangle setup (integer edge functions with the
// top-left rule, depth planes). Produces SetupTriangles in submission order; consumed by the
// rasterizers (raster/) through the algorithms. Called from one thread; spreads its fixed chunks
// of vertices and triangles over the thread pool (core/parallel.hpp).
#pragma once
#include <hsr/render.hpp>

#include <vector>

namespace hsr {

/// Sub-pixel precision of snapped vertex positions: 8 bits, 1/256 pixel.
inline constexpr int kSubpixelBits = 8;
inline constexpr int64_t kSubpixelOne = int64_t(1) << kSubpixelBits;
/// Guard band: geometry is clipped to this many pixels beyond each image border, which bounds
/// snapped coordinates by 2^15 pixels (2^23 fixed point) so edge functions fit int64 with room.
inline constexpr double kGuardBandPixels = 8192;
inline constexpr int kMaxImageSize = 16384;

/// Integer division rounding towards minus / plus infinity (b > 0), for pixel ranges.
inline int64_t floorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
inline int64_t ceilDiv(int64_t a, int64_t b) { return -floorDiv(-a, b); }

/// An affine function of pixel position: value(x, y) = a x + b y + c (x, y in pixels).
struct Plane {
  double a = 0, b = 0, c = 0;
  double at(double x, double y) const { return a * x + b * y + c; }
};

/// A triangle ready to rasterize. Vertices are in fixed point (1/256 pixel), ordered so that the
/// edge functions E_i are positive inside (see raster/edge.hpp); bounding box in whole pixels.
struct SetupTriangle {
  int32_t x[3], y[3];
  int minX, minY, maxX, maxY;  // inclusive pixel range whose centres may be covered, in the image
  Plane depthNum, depthDen;    // eye depth at pixel position p = depthNum(p) / depthDen(p)
  uint32_t triangle;           // index into Scene::triangles
  uint32_t face;
  Rgba8 color;
  bool frontFacing;            // counter-clockwise as seen by the camera

  double eyeDepth(double px, double py) const { return depthNum.at(px, py) / depthDen.at(px, py); }
};

/// Homogeneous pixel coordinates of a vertex: pixel = (hx / w, hy / w), eye depth d (w > 0).
struct HVertex {
  double hx, hy, d, w;
};

/// A vertex inside the clip volume, projected once and shared by all its triangles.
struct ProjectedVertex {
  double sx, sy;   // pixel position (unsnapped)
  int64_t X, Y;    // snapped to 1/256 pixel
  double num, den; // d/w and 1/w, both affine in screen space
};

/// Why triangles were not drawn, counted per scene triangle or clipped piece.
struct FrontEndCounters {
  uint64_t clipped = 0, culledBackface = 0, culledFrustum = 0, degenerate = 0;
  void add(const FrontEndCounters& o) {
    clipped += o.clipped;
    culledBackface += o.culledBackface;
    culledFrustum += o.culledFrustum;
    degenerate += o.degenerate;
  }
};

struct FrontEndOutput : FrontEndCounters {
  std::vector<SetupTriangle> triangles;  // in submission order
  uint64_t memoryBytes() const;

  // Scratch reused from frame to frame (no allocation once warm).
  std::vector<HVertex> hv;
  std::vector<uint8_t> outcodes;
  std::vector<ProjectedVertex> projected;
  std::vector<uint8_t> faceVisible;
  std::vector<std::vector<SetupTriangle>> chunks;
  std::vector<FrontEndCounters> chunkCounters;
};

/// Projects and snaps a vertex that lies inside the clip volume.
ProjectedVertex projectVertex(const HVertex& v);

/// Sets up one triangle whose vertices are inside the clip volume: culls and fills `t`.
/// Returns false, counting the reason in `counters`, when it draws nothing.
bool setupTriangle(const ProjectedVertex* v, uint32_t triIndex, uint32_t face, Rgba8 color, const Camera& cam,
                   Cull cull, FrontEndCounters& counters, SetupTriangle& t);
/// The same from homogeneous coordinates (projects first).
bool setupTriangle(const HVertex* v, uint32_t triIndex, uint32_t face, Rgba8 color, const Camera& cam,
                   Cull cull, FrontEndCounters& counters, SetupTriangle& t);

/// Runs the front end over all scene triangles, in order, on up to options.threads threads; the
/// work is split into fixed chunks, so the output never depends on the thread count.
/// `out` is reused across frames.
void runFrontEnd(const Scene& scene, const Camera& camera, const RenderOptions& options, FrontEndOutput& out);

}  // namespace hsr

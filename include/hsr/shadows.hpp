// Shadows, the z-buffer's other use (docs/shadows.md): shadow maps rendered with the z-buffer
// from the light, each visible pixel of a view frame tested against one, and the exact reference
// (a shadow ray per visible pixel through the ray caster's BVH) that the maps are verified against.
// Consumed by `hsr render --shadows`, `hsr bench --shadows` and the tests.
//
// Conventions:
//  - a visible pixel's point is where the view ray through its centre meets the plane of the
//    triangle the frame shows there (Frame::triangleId), in double precision;
//  - a point is lit when the side of its surface the viewer sees faces the light (the plane's
//    normal turned toward the viewer has a positive dot product with the direction to the light)
//    and nothing lies between it and the light; otherwise it is shadowed (both methods apply the
//    same facing rule, so they differ only in what lies between);
//  - a map is square, mapSize x mapSize texels. The `single` method fits one map to the scene's
//    bounds as seen from the light; the `cascaded` method splits the view's visible depth range
//    into K slices and fits one map to each slice's receivers (the points its pixels show) and
//    to what lies between them and the light;
//  - the depth bias is in texels: a receiver is shadowed when the map's depth at its texel centre
//    is nearer than the receiver's own plane there by more than bias texel widths.
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace hsr {

inline constexpr int kMinShadowMapSize = 16;
inline constexpr int kMaxShadowMapSize = 16384;

/// Throws InputError "`what`: problem" for a light with a NaN or infinite component or a zero
/// direction.
void checkLight(const Light& light, const std::string& what);

/// The light used when neither the scene nor the caller gives one: a sun over the viewer's left
/// shoulder (travelling right, down and away in the view camera's axes).
Light defaultLight(const Camera& view);

/// "directional x,y,z" or "point x,y,z", for statistics and messages.
std::string describeLight(const Light& light);

/// The shadow map's camera for `light`, mapSize x mapSize texels, fitted to `sceneBounds` with a
/// texel of margin: orthographic along a directional light's direction; perspective from a point
/// light, looking at the bounds. Throws InputError for a bad light or size, empty bounds, a point
/// light inside the bounds (no one perspective map sees the whole scene from there) or one so
/// close that the bounds do not fit in a 160-degree view.
Camera lightCamera(const Bounds3& sceneBounds, const Light& light, int mapSize);

inline constexpr int kMaxShadowCascades = 16;

/// How the light's maps are fitted (docs/shadows.md "Method").
enum class ShadowMethod : uint8_t {
  Single,    // one map fitted to the whole scene's bounds
  Cascaded,  // the view's visible depth range split into `cascades` slices (the practical split
             // scheme), one map per slice fitted to the receivers the slice's pixels show
};
/// "single" or "cascaded".
const char* shadowMethodName(ShadowMethod method);
/// The method named `name`; throws InputError "`what` 'name': expected single or cascaded".
ShadowMethod parseShadowMethod(const std::string& name, const std::string& what);

struct ShadowOptions {
  ShadowMethod method = ShadowMethod::Cascaded;
  int cascades = 4;          // Cascaded: the slices (maps), 1..kMaxShadowCascades; 1 = one map
                             // fitted to all the visible receivers
  int mapSize = 2048;        // texels per side of each map, kMinShadowMapSize..kMaxShadowMapSize
  double bias = 1.0;         // depth bias in texel widths at the receiver, >= 0 (finite)
  double ambient = 0.35;     // a shadowed pixel's colour is multiplied by this, in [0, 1]
  DepthFormat depthFormat;   // of the map's z-buffer (default f32:reversed)
  int threads = 0;           // 0: all cores
};
/// Throws InputError keyed Setting::ShadowMapSize or ShadowBias for a value out of range, and a
/// plain InputError for a cascade count out of range.
void checkShadowOptions(const ShadowOptions& options);

/// Per view pixel (row 0 at the top).
enum class ShadowMask : uint8_t { Background = 0, Lit = 1, Shadowed = 2 };
/// ShadowResult::texel of a background pixel (and of every pixel when no map was needed).
inline constexpr uint32_t kNoTexel = 0xffffffffu;

struct ShadowResult {
  std::vector<ShadowMask> mask;       // frame.width * frame.height
  std::vector<uint32_t> texel;        // per pixel, the texel it was tested at:
                                      // map * mapSize^2 + y * mapSize + x
  uint64_t lit = 0, shadowed = 0;
  uint64_t facingAway = 0;            // of the shadowed: the viewer sees the side away from the light
  std::vector<Camera> lightCameras;   // the maps' cameras (cascaded: one per slice that has receivers)
  std::vector<double> splits;         // cascaded: the slices' eye depths, near to far (maps + 1 of them)
  double fitMs = 0;                   // cascaded: finding each slice's receivers and their bounds
  double mapMs = 0, testMs = 0;       // rendering the maps; testing the pixels against them
  uint64_t mapBytes = 0;              // the largest map's z-buffer and depth frame (its Stats::memory_bytes):
                                      // the maps are rendered and used one after another
};

/// Renders the shadow map(s) of `scene` with the `zbuffer` algorithm (depth only) from the light
/// and tests each visible pixel of `frame` (rendered from `view`, with triangle ids) against its
/// map. Throws InputError for bad options, a bad light, or a frame without triangle ids.
ShadowResult shadowMap(const Scene& scene, const Camera& view, const Frame& frame, const Light& light,
                       const ShadowOptions& options);

/// The exact reference: per visible pixel of `frame`, the facing rule, then a ray from its point
/// (moved off its plane toward the light by a relative 1e-9 of the scene's size) toward the light
/// through the ray caster's BVH; shadowed when any triangle is hit before the light.
std::vector<ShadowMask> shadowRays(const Scene& scene, const Camera& view, const Frame& frame, const Light& light,
                                   int threads = 0);

/// How a shadow map's mask compares with the reference. A pixel is near a shadow edge when the
/// reference mask is not the same over its 3x3 neighbourhood (clipped to the image), and near a
/// face edge when the frame's face ids are not (silhouettes and creases of the view): edges at
/// the scale of the view's pixels. A wrong pixel away from both is still explained by the map's
/// resolution when its texel is at an edge as the light sees it: over the 3x3 texels around it (in
/// its own map), the receivers (visible pixels) that fall there include both lit and shadowed ones
/// (in the reference), or the light sees more than one face (the map rendered again with face ids).
struct ShadowComparison {
  uint64_t wrong = 0;                 // pixels whose mask differs from the reference's
  uint64_t wrongAwayFromShadowEdges = 0;
  uint64_t wrongAwayFromEdges = 0;    // away from shadow edges and from face edges (pixel scale)
  uint64_t wrongUnexplained = 0;      // of those, not at an edge at the texel scale either
  uint64_t shadowEdgePixels = 0, faceEdgePixels = 0;
  std::vector<std::pair<int, int>> firstWrongAwayFromEdges, firstUnexplained;  // up to 16 (x, y) each
};
ShadowComparison compareShadowMasks(const Scene& scene, const Frame& frame, const ShadowResult& map,
                                    const std::vector<ShadowMask>& reference, const ShadowOptions& options);

/// Adds the shadow pass's times to `stats`: "shadow_fit" (cascaded), "shadow_map", "shadow_test".
void addShadowTimes(Stats& stats, const ShadowResult& result, const ShadowOptions& options);

/// Multiplies the colour of every shadowed pixel by `ambient` (red, green and blue; alpha kept).
void darkenShadowed(Frame& frame, const std::vector<ShadowMask>& mask, double ambient);

/// What `hsr render --shadows` does after rendering `frame`: shadowMap(), darkenShadowed() when
/// the frame has colour, and the statistics (times "shadow_fit" (cascaded), "shadow_map",
/// "shadow_test", memory "shadow_map" and "shadow_mask", details shadow_*); with `verify`, also shadowRays() and
/// compareShadowMasks(), recorded as the details shadow_wrong_* and time "shadow_verify". Returns the comparison (empty
/// without `verify`).
ShadowComparison addShadows(const Scene& scene, const Camera& view, Frame& frame, const Light& light,
                            const ShadowOptions& options, bool verify);

}  // namespace hsr

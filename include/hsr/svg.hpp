// Exact vector output: the painting order of a list-priority algorithm (painter, newell, bsp) as
// SVG polygons, back to front, projected to the pixels of the camera's image. With newell or bsp
// the order is exact, so an SVG renderer's picture is the raster image (away from anti-aliased
// edges). Used by `hsr render --svg` (docs/vector-output.md).
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <string>

namespace hsr {

/// Whether `algorithm` paints polygons in an order that vector output writes (its registry entry
/// declares Capability::PaintsInOrder).
bool paintsPolygons(const std::string& algorithm);

/// The scene seen by `camera` as an SVG document of camera.width x camera.height pixels: the
/// background, then options.algorithm's polygons (with options.params) back to front, each clipped
/// to the view (near and far planes, the image rectangle), filled with its shaded colour
/// (options.shading, as the raster image; faceid colours decode to face ids), alpha below 255 as
/// fill-opacity; back faces left out as options.cull says. Coordinates in pixels to 1/1000 (finer
/// than the rasterizer's 1/256 snapping). Throws InputError for an algorithm that paints no
/// polygons or a bad parameter.
std::string renderSvg(const Scene& scene, const Camera& camera, const RenderOptions& options);

/// Throws InputError "path: ..." unless `path` ends in .svg.
void checkSvgPath(const std::string& path);
/// renderSvg written atomically to `path` (temporary file + rename).
void writeSvg(const Scene& scene, const Camera& camera, const RenderOptions& options, const std::string& path);

}  // namespace hsr

// Exact vector output: the painting order of a list-priority algorithm (painter, newell, bsp) as
// polygons on the camera's image, back to front, the pieces of a face in paint groups drawn as
// one shape (no anti-aliasing seam), as data (screenPolygons) or SVG. With newell or bsp the order
// is exact, so an SVG renderer's picture is the raster image (away from anti-aliased edges). Used
// by `hsr render --svg` (docs/vector-output.md) and hsr.matplotlib (docs/matplotlib.md).
#pragma once
#include <hsr/camera.hpp>
#include <hsr/frame.hpp>
#include <hsr/options.hpp>
#include <hsr/scene.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hsr {

/// Whether `algorithm` paints polygons in an order that vector output writes (its registry entry
/// declares Capability::PaintsInOrder).
bool paintsPolygons(const std::string& algorithm);

/// One polygon of the painting order in pixels (ScreenPolygons).
struct ScreenPolygon {
  uint32_t first = 0, count = 0;  // its vertices: ScreenPolygons::points[first, first + count)
  uint32_t face = 0;              // the scene face it is (a piece of)
  Rgba8 color;                    // its shaded colour (the raster image's shading), alpha = opacity
  uint32_t group = 0;             // its paint group (below); groups are numbered 0, 1, ... in painting order
  /// A part of a piece of the same face painted in an earlier group and still on top there,
  /// painted again in this group's shape so that the face's groups meet without a seam.
  bool repaint = false;
};

/// A list-priority algorithm's painting order as polygons on the image, back to front.
///
/// The polygons come in paint groups: a group is consecutive polygons of one face, meant to be
/// painted as ONE shape (an SVG <path> of several subpaths, a compound path), so that a renderer
/// computes the anti-aliased coverage of their union and shows no seam where a face was split.
/// The order of two polygons that overlap on the image is the algorithm's, so the picture is the
/// same; among such orders the pieces of a face are painted together where they can be. Where a
/// face still ends in several groups (something lies between its pieces in depth), each later
/// group of an opaque face also repaints the parts of the face's earlier pieces beside it that are
/// still on top: their colour was already there, and the seam between the groups falls inside
/// one shape.
struct ScreenPolygons {
  std::vector<dvec2> points;            // pixel coordinates (x right, y down), inside the image
  std::vector<ScreenPolygon> polygons;  // in painting order, groups contiguous
  uint32_t groups = 0;                  // number of paint groups
};

/// The scene seen by `camera` as options.algorithm's (with options.params) polygons back to
/// front, each clipped in world space to the near and far planes, projected to pixels and clipped
/// to the image rectangle, with the colour of options.shading (faceid: face index + 1 as 24-bit
/// RGB), back faces left out as options.cull says, in paint groups. Polygons of no area after
/// projection are left out. Throws InputError for an algorithm that paints no polygons or a bad
/// parameter.
ScreenPolygons screenPolygons(const Scene& scene, const Camera& camera, const RenderOptions& options);

/// The scene seen by `camera` as an SVG document of camera.width x camera.height pixels, nothing
/// for the background (the shared conventions: the viewer's page shows through), then screenPolygons(): a paint group of one polygon as a <polygon>, a larger one as
/// one <path> of a subpath per polygon (fill-rule nonzero: the pieces of a face have one
/// orientation), each filled with its shaded colour, alpha below 255 as fill-opacity.
/// Coordinates in pixels to 1/1000 (finer than the rasterizer's 1/256 snapping).
std::string renderSvg(const Scene& scene, const Camera& camera, const RenderOptions& options);

/// Throws InputError "path: ..." unless `path` ends in .svg.
void checkSvgPath(const std::string& path);
/// renderSvg written atomically to `path` (temporary file + rename).
void writeSvg(const Scene& scene, const Camera& camera, const RenderOptions& options, const std::string& path);

}  // namespace hsr

// SetupTriangle: one triangle ready to rasterize (snapped vertices, pixel box, depth planes, ids,
// colour). The front end (frontend/) writes them; the rasterizers (raster/) and the algorithms
// that draw read them, on whichever thread holds the triangle's chunk or tile.
#pragma once
#include <cstdint>

#include "scene/shading.hpp"

namespace hsr {

/// An affine function of pixel position: value(x, y) = a x + b y + c (x, y in pixels).
struct Plane {
  double a = 0, b = 0, c = 0;
  double at(double x, double y) const { return a * x + b * y + c; }
};

/// A triangle ready to rasterize. Vertices are in fixed point (1/256 pixel), ordered so that the
/// edge functions E_i are positive inside (see setup/edge.hpp); bounding box in whole pixels.
/// 96 bytes: everything the rasterizers and the resolve read.
struct SetupTriangle {
  int32_t x[3], y[3];
  int16_t minX, minY, maxX, maxY;  // inclusive pixel range whose centres may be covered, in the image
  Plane depthNum, depthDen;        // eye depth at pixel position p = depthNum(p) / depthDen(p)
  uint32_t triangle;               // index into Scene::triangles
  uint32_t face;
  bool frontFacing;                // counter-clockwise as seen by the camera
  // A box of at most kCoverageBox x kCoverageBox pixels (most triangles of a dense mesh): the
  // pixel centres it covers, bit kCoverageBox (y - minY) + (x - minX), as the edge functions
  // decide (never 0: such a triangle is dropped); 0 for a larger box. Lets the tiled kernel skip
  // its edge set-up.
  uint16_t coverage = 0;
  Rgba8 color;  // shaded (scene/shading.hpp) when the frame keeps colour and frontFacing (a
                // back face is mostly hidden: the resolve shades the few that show)

  double eyeDepth(double px, double py) const { return depthNum.at(px, py) / depthDen.at(px, py); }
};

/// Side of the largest pixel box whose covered centres set-up lists (SetupTriangle::coverage).
inline constexpr int kCoverageBox = 4;
static_assert(kCoverageBox * kCoverageBox <= 16, "SetupTriangle::coverage holds one bit per centre");
static_assert(sizeof(SetupTriangle) == 96, "a set-up triangle is one and a half cache lines");

/// The colour of a set-up triangle, one rule for every rasterizer: the front end shades front
/// faces (SetupTriangle::color); a back face, mostly hidden, is shaded only when it shows.
inline Rgba8 triangleColor(const SetupTriangle& t, const TriangleShader& shade) {
  return t.frontFacing ? t.color : shade(t.triangle);
}

}  // namespace hsr

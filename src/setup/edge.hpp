// Integer edge functions of a SetupTriangle, shared by every rasterizer so their coverage is
// identical by construction: set-up (coverage of small boxes), binning, the tiled kernel and the
// reference rasterizers (raster/halfspace.hpp, raster/scanline.hpp). Pure functions, any thread.
//
// Edge i runs from vertex i to vertex i+1. For a point p (fixed point, 1/256 pixel):
//   E_i(p) = dx * (p.y - a.y) - dy * (p.x - a.x),  dx = b.x - a.x, dy = b.y - a.y,
// positive inside (the front end orders vertices so). Top-left rule, with y pointing down:
// a "top" edge is horizontal with the interior below (dy == 0, dx > 0), a "left" edge goes up
// (dy < 0). A centre exactly on an edge is inside only for top and left edges, so two triangles
// sharing an edge never both cover a pixel and never both miss it.
#pragma once
#include <algorithm>
#include <cstdint>

#include "setup/fixed_point.hpp"
#include "setup/setup_triangle.hpp"

namespace hsr {

struct Edge {
  int64_t dx, dy, ax, ay;
  int64_t bias;  // 0 for top-left edges, 1 otherwise: inside iff E(p) >= bias

  int64_t at(int64_t px, int64_t py) const { return dx * (py - ay) - dy * (px - ax); }
  // Change of E per pixel step in x and in y.
  int64_t stepX() const { return -dy * kSubpixelOne; }
  int64_t stepY() const { return dx * kSubpixelOne; }
};

inline Edge makeEdge(const SetupTriangle& t, int i) {
  int j = (i + 1) % 3;
  Edge e{int64_t(t.x[j]) - t.x[i], int64_t(t.y[j]) - t.y[i], t.x[i], t.y[i], 0};
  bool topLeft = e.dy < 0 || (e.dy == 0 && e.dx > 0);
  e.bias = topLeft ? 0 : 1;
  return e;
}

/// Fixed-point position of pixel (x, y)'s centre.
inline int64_t centerFixed(int i) { return int64_t(i) * kSubpixelOne + kSubpixelOne / 2; }

/// Narrows [first, last] (first <= last + 1 on entry and exit), tiles of tileSize pixels in one
/// row of tiles, to those where `edge` passes on the tile's part of the pixel rows y0..y1 and
/// columns [minX, maxX] (tile tx spans columns max(tx T, minX) .. min(tx T + T - 1, maxX)):
/// with `whole` false, where it is not wholly outside (the corner where E is largest is inside);
/// with `whole` true, where every pixel centre is inside (the corner where it is smallest). E
/// grows with x when dy < 0 and with y when dx > 0. Along the row E at pixel column x is R + k x
/// with k = -dy S (S = kSubpixelOne), so the columns inside are x >= ceil((bias - R) / k) when
/// k > 0 and x <= floor((R - bias) / -k) when k < 0: exact integer arithmetic (E is below 2^49),
/// no search over the tiles.
inline void narrowTilesToEdge(const Edge& edge, bool whole, int tileSize, int minX, int maxX, int y0, int y1,
                              int& first, int& last) {
  const bool lowerRow = (edge.dx > 0) != whole;  // the row where E is largest (or smallest, whole)
  const int64_t R = edge.dx * (centerFixed(lowerRow ? y1 : y0) - edge.ay) - edge.dy * (kSubpixelOne / 2 - edge.ax);
  const int64_t T = tileSize;
  if (edge.dy < 0) {  // inside from column xMin on: the tile's rightmost column (or leftmost, whole) must be
    const int64_t xMin = ceilDiv(edge.bias - R, -edge.dy * kSubpixelOne);
    int64_t firstTile;
    if (!whole) firstTile = maxX < xMin ? int64_t(last) + 1 : ceilDiv(xMin - (T - 1), T);
    else firstTile = minX >= xMin ? int64_t(first) : ceilDiv(xMin, T);
    first = int(std::clamp<int64_t>(firstTile, first, int64_t(last) + 1));
  } else if (edge.dy > 0) {  // inside up to column xMax: the tile's leftmost column (or rightmost, whole) must be
    const int64_t xMax = floorDiv(R - edge.bias, edge.dy * kSubpixelOne);
    int64_t lastTile;
    if (!whole) lastTile = minX > xMax ? int64_t(first) - 1 : floorDiv(xMax, T);
    else lastTile = maxX <= xMax ? int64_t(last) : floorDiv(xMax - (T - 1), T);
    last = int(std::clamp<int64_t>(lastTile, int64_t(first) - 1, last));
  } else if (R < edge.bias) {  // horizontal: the same for every tile
    last = first - 1;
  }
}

}  // namespace hsr

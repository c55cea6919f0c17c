// Integer edge functions of a SetupTriangle, shared by both rasterizers so their coverage is
// identical by construction. Consumed by raster/halfspace.hpp and raster/scanline.hpp.
//
// Edge i runs from vertex i to vertex i+1. For a point p (fixed point, 1/256 pixel):
//   E_i(p) = dx * (p.y - a.y) - dy * (p.x - a.x),  dx = b.x - a.x, dy = b.y - a.y,
// positive inside (the front end orders vertices so). Top-left rule, with y pointing down:
// a "top" edge is horizontal with the interior below (dy == 0, dx > 0), a "left" edge goes up
// (dy < 0). A centre exactly on an edge is inside only for top and left edges, so two triangles
// sharing an edge never both cover a pixel and never both miss it.
#pragma once
#include "frontend/frontend.hpp"

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

}  // namespace hsr

// The scanline rasterizer of the lecture notes: for each pixel row, intersect the three edges with
// the row to get the span [xl, xr] of covered pixel centres (exact integer arithmetic, same
// edge functions and top-left rule as the half-space rasterizer, hence identical coverage),
// then walk the span stepping depth by the plane equation: z(i+1) = z(i) + dz/dx along the
// span and z(j+1) = z(j) + dz/dy between rows (the lecture notes write these -A/C and -B/C). Depth here is
// the pair (d/w, 1/w), both affine in screen space; eye depth d = their ratio.
// Calls visit(x, y, eyeDepth) in row order. Consumed by the algorithms (--raster scanline).
#pragma once
#include "setup/edge.hpp"

namespace hsr {

template <class Visit>
void rasterizeScanline(const SetupTriangle& t, Visit&& visit) {
  const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
  // Plane values at the centre of column 0 of the first row, stepped down row by row.
  double numRow = t.depthNum.at(0.5, t.minY + 0.5), denRow = t.depthDen.at(0.5, t.minY + 0.5);
  for (int y = t.minY; y <= t.maxY; ++y, numRow += t.depthNum.b, denRow += t.depthDen.b) {
    const int64_t py = centerFixed(y);
    int64_t xl = t.minX, xr = t.maxX;
    // Edge i: inside iff dx*(py-ay) - dy*(px-ax) >= bias, i.e. dy*px <= K with
    // K = dx*(py-ay) + dy*ax - bias; solve for the pixel index x of px = 256x + 128.
    for (const Edge& edge : e) {
      const int64_t K = edge.dx * (py - edge.ay) + edge.dy * edge.ax - edge.bias;
      const int64_t h = kSubpixelOne / 2;
      if (edge.dy == 0) {
        if (K < 0) xr = xl - 1;  // the whole row is outside this horizontal edge
      } else if (edge.dy > 0) {  // px <= K / dy
        xr = std::min(xr, floorDiv(floorDiv(K, edge.dy) - h, kSubpixelOne));
      } else {  // px >= K / dy = (-K) / (-dy)
        xl = std::max(xl, ceilDiv(ceilDiv(-K, -edge.dy) - h, kSubpixelOne));
      }
    }
    if (xl > xr) continue;
    double num = numRow + t.depthNum.a * double(xl), den = denRow + t.depthDen.a * double(xl);
    for (int64_t x = xl; x <= xr; ++x, num += t.depthNum.a, den += t.depthDen.a) visit(int(x), y, num / den);
  }
}

}  // namespace hsr

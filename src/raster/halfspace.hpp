// The half-space (edge function) rasterizer, the scalar reference: walks the triangle's bounding
// box in 8x8 blocks, rejects or accepts whole blocks by the edge functions at the block's corner
// pixel centres, and tests pixels one by one only in partial blocks. Calls visit(x, y, eyeDepth)
// for every covered pixel centre, row-major within a block. The default rasterizer is the tiled
// SIMD one (raster/tiled.hpp), which bins triangles into tiles, vectorises this block loop and
// must match this one bit for bit. Consumed by the algorithms (algorithms/*.cpp).
#pragma once
#include "setup/edge.hpp"

namespace hsr {

inline constexpr int kRasterBlock = 8;

template <class Visit>
void rasterizeHalfSpace(const SetupTriangle& t, Visit&& visit) {
  const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
  for (int by = t.minY; by <= t.maxY; by += kRasterBlock) {
    const int y1 = std::min<int>(by + kRasterBlock - 1, t.maxY);
    for (int bx = t.minX; bx <= t.maxX; bx += kRasterBlock) {
      const int x1 = std::min<int>(bx + kRasterBlock - 1, t.maxX);
      // Each edge function is linear, so over the block's pixel centres its extremes are at
      // the four corner centres: all corners outside -> block empty; all inside -> block full.
      bool full = true, empty = false;
      for (const Edge& edge : e) {
        int inside = 0;
        for (int c = 0; c < 4; ++c) {
          int64_t px = centerFixed(c & 1 ? x1 : bx), py = centerFixed(c & 2 ? y1 : by);
          inside += edge.at(px, py) >= edge.bias;
        }
        empty |= inside == 0;
        full &= inside == 4;
      }
      if (empty) continue;
      for (int y = by; y <= y1; ++y) {
        const double cy = y + 0.5;
        int64_t row[3];
        for (int i = 0; i < 3; ++i) row[i] = e[i].at(centerFixed(bx), centerFixed(y));
        for (int x = bx; x <= x1; ++x) {
          if (full || (row[0] >= e[0].bias && row[1] >= e[1].bias && row[2] >= e[2].bias))
            visit(x, y, t.eyeDepth(x + 0.5, cy));
          for (int i = 0; i < 3; ++i) row[i] += e[i].stepX();
        }
      }
    }
  }
}

}  // namespace hsr

// The vertex pass with SIMD (Highway, dispatched at run time): transformVertices and
// boxCornersInView (vertices.hpp), lane by lane the same IEEE operations in the same order as
// transformVertex, clipOutcode and projectVertex (frontend.cpp). Run by the front end's vertex
// pass on its workers (a chunk of vertices, or a run of meshes' box corners, each).

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "frontend/vertex_batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "frontend/vertices.hpp"
#include "setup/fixed_point.hpp"

HWY_BEFORE_NAMESPACE();
namespace hsr {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Lanes of the vertex pass, at most (fewer on narrower instruction sets).
constexpr size_t kVertexLanes = 8;
using D = hn::CappedTag<double, kVertexLanes>;
using V = hn::Vec<D>;
using M = hn::Mask<D>;

// transformVertices() (vertices.hpp): transformVertex, clipOutcode and projectVertex
// (frontend.cpp) lane by lane, with the same IEEE operations in the same order.
void TransformVertices(const dvec3* positions, size_t count, const dmat4& matrix, const Camera& cam,
                       uint8_t* outcodes, ProjectedVertex* projected) {
  static_assert(sizeof(dvec3) == 3 * sizeof(double));
  const D d;
  const size_t N = hn::Lanes(d);
  V m[4][4];
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = hn::Set(d, matrix[c][r]);
  const V zero = hn::Zero(d), nearV = hn::Set(d, cam.near), farV = hn::Set(d, cam.far);
  const V gx0 = hn::Set(d, -kGuardBandPixels), gx1 = hn::Set(d, cam.width + kGuardBandPixels);
  const V gy0 = hn::Set(d, -kGuardBandPixels), gy1 = hn::Set(d, cam.height + kGuardBandPixels);
  const V one = hn::Set(d, 1.0);
  const double* in = reinterpret_cast<const double*>(positions);
  for (size_t first = 0; first < count; first += N) {
    const size_t lanes = std::min(N, count - first);
    V x, y, z;
    if (lanes == N) {
      hn::LoadInterleaved3(d, in + 3 * first, x, y, z);
    } else {
      HWY_ALIGN double px[kVertexLanes], py[kVertexLanes], pz[kVertexLanes];
      for (size_t j = 0; j < N; ++j) {
        const dvec3& p = positions[first + std::min(j, lanes - 1)];
        px[j] = p.x, py[j] = p.y, pz[j] = p.z;
      }
      x = hn::Load(d, px), y = hn::Load(d, py), z = hn::Load(d, pz);
    }
    auto row = [&](int r) {
      return hn::Add(hn::Add(hn::Add(hn::Mul(m[0][r], x), hn::Mul(m[1][r], y)), hn::Mul(m[2][r], z)), m[3][r]);
    };
    const V hx = row(0), hy = row(1), depth = row(2), w = row(3);
    // planeDistance(v, p) < 0 for the six planes, in clipOutcode's bit order.
    const M outside[6] = {hn::Lt(hn::Sub(depth, nearV), zero),      hn::Lt(hn::Sub(farV, depth), zero),
                          hn::Lt(hn::Sub(hx, hn::Mul(gx0, w)), zero), hn::Lt(hn::Sub(hn::Mul(gx1, w), hx), zero),
                          hn::Lt(hn::Sub(hy, hn::Mul(gy0, w)), zero), hn::Lt(hn::Sub(hn::Mul(gy1, w), hy), zero)};
    // projectVertex: every lane (unless only the outcodes are asked for).
    // The six masks as the rows of an 8x8 bit matrix (byte p, bit j: lane j outside plane p),
    // transposed (Hacker's Delight 7-3): byte j becomes lane j's outcode.
    uint64_t matrix = 0;
    for (int p = 0; p < 6; ++p) {
      uint8_t bits[8] = {};
      hn::StoreMaskBits(d, outside[p], bits);
      matrix |= uint64_t(bits[0]) << (8 * p);
    }
    matrix = (matrix & 0xAA55AA55AA55AA55ull) | ((matrix & 0x00AA00AA00AA00AAull) << 7) |
             ((matrix >> 7) & 0x00AA00AA00AA00AAull);
    matrix = (matrix & 0xCCCC3333CCCC3333ull) | ((matrix & 0x0000CCCC0000CCCCull) << 14) |
             ((matrix >> 14) & 0x0000CCCC0000CCCCull);
    matrix = (matrix & 0xF0F0F0F00F0F0F0Full) | ((matrix & 0x00000000F0F0F0F0ull) << 28) |
             ((matrix >> 28) & 0x00000000F0F0F0F0ull);
    for (size_t j = 0; j < lanes; ++j) outcodes[first + j] = uint8_t(matrix >> (8 * j));
    if (!projected) continue;
    const V sx = hn::Div(hx, w), sy = hn::Div(hy, w);
    const V num = hn::Div(depth, w), den = hn::Div(one, w);
    if (lanes == N) {  // N whole records at once (a vertex outside gets values no triangle reads)
      static_assert(sizeof(ProjectedVertex) == 4 * sizeof(double));
      hn::StoreInterleaved4(sx, sy, num, den, d, reinterpret_cast<double*>(projected + first));
    } else {
      HWY_ALIGN double l[4][kVertexLanes];
      hn::Store(sx, d, l[0]), hn::Store(sy, d, l[1]), hn::Store(num, d, l[2]), hn::Store(den, d, l[3]);
      for (size_t j = 0; j < lanes; ++j)
        if (!outcodes[first + j]) projected[first + j] = {l[0][j], l[1][j], l[2][j], l[3][j]};
    }
  }
}

// boxCornersInView() (vertices.hpp): the eight corners lane by lane, with boxInView's IEEE
// operations in its order.
bool BoxCornersInView(const Bounds3& box, const dmat4& matrix, const Camera& cam, double margin, double wRoom,
                      double* extent) {
  const D d;
  constexpr size_t kCorners = 8;
  static_assert(kVertexLanes == kCorners, "D holds at most the eight corners");
  const size_t N = hn::Lanes(d);  // (at most kVertexLanes = 8, a power of two: a divisor of 8)
  HWY_ALIGN double cx[kCorners], cy[kCorners], cz[kCorners];  // corner c: bits 1, 2, 4 pick hi
  for (size_t c = 0; c < kCorners; ++c) {
    cx[c] = c & 1 ? box.hi.x : box.lo.x;
    cy[c] = c & 2 ? box.hi.y : box.lo.y;
    cz[c] = c & 4 ? box.hi.z : box.lo.z;
  }
  const V marginV = hn::Set(d, margin), nearV = hn::Set(d, cam.near), farV = hn::Set(d, cam.far);
  const V gx0 = hn::Set(d, -kGuardBandPixels), gx1 = hn::Set(d, cam.width + kGuardBandPixels);
  const V gy0 = hn::Set(d, -kGuardBandPixels), gy1 = hn::Set(d, cam.height + kGuardBandPixels);
  const double inf = std::numeric_limits<double>::infinity();
  V zMin = hn::Set(d, inf), x0 = zMin, y0 = zMin, zMax = hn::Set(d, -inf), x1 = zMax, y1 = zMax;
  for (size_t first = 0; first < kCorners; first += N) {
    const V x = hn::LoadU(d, cx + first), y = hn::LoadU(d, cy + first), z = hn::LoadU(d, cz + first);
    auto row = [&](int r) {
      return hn::Add(hn::Add(hn::Add(hn::Mul(hn::Set(d, matrix[0][r]), x), hn::Mul(hn::Set(d, matrix[1][r]), y)),
                             hn::Mul(hn::Set(d, matrix[2][r]), z)),
                     hn::Set(d, matrix[3][r]));
    };
    const V hx = row(0), hy = row(1), depth = row(2), w = row(3);
    // planeDistance(corner, p) > margin for the six planes (frontend.cpp).
    M inside = hn::And(hn::Gt(hn::Sub(depth, nearV), marginV), hn::Gt(hn::Sub(farV, depth), marginV));
    inside = hn::And(inside, hn::Gt(hn::Sub(hx, hn::Mul(gx0, w)), marginV));
    inside = hn::And(inside, hn::Gt(hn::Sub(hn::Mul(gx1, w), hx), marginV));
    inside = hn::And(inside, hn::Gt(hn::Sub(hy, hn::Mul(gy0, w)), marginV));
    inside = hn::And(inside, hn::Gt(hn::Sub(hn::Mul(gy1, w), hy), marginV));
    if (!hn::AllTrue(d, inside)) return false;
    const V room = hn::Set(d, wRoom);
    zMin = hn::Min(zMin, hn::Sub(w, room)), zMax = hn::Max(zMax, hn::Add(w, room));
    const V inverse = hn::Div(hn::Set(d, 1.0), w), sx = hn::Mul(hx, inverse), sy = hn::Mul(hy, inverse);
    x0 = hn::Min(x0, sx), x1 = hn::Max(x1, sx);
    y0 = hn::Min(y0, sy), y1 = hn::Max(y1, sy);
  }
  extent[0] = hn::GetLane(hn::MinOfLanes(d, zMin));
  extent[1] = hn::GetLane(hn::MaxOfLanes(d, zMax));
  extent[2] = hn::GetLane(hn::MinOfLanes(d, x0));
  extent[3] = hn::GetLane(hn::MinOfLanes(d, y0));
  extent[4] = hn::GetLane(hn::MaxOfLanes(d, x1));
  extent[5] = hn::GetLane(hn::MaxOfLanes(d, y1));
  return true;
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hsr {
HWY_EXPORT(TransformVertices);
HWY_EXPORT(BoxCornersInView);

bool boxCornersInView(const Bounds3& box, const dmat4& M, const Camera& cam, double margin, double wRoom,
                      double* extent) {
  return HWY_DYNAMIC_DISPATCH(BoxCornersInView)(box, M, cam, margin, wRoom, extent);
}

void transformVertices(const dvec3* positions, size_t count, const dmat4& M, const Camera& cam, uint8_t* outcodes,
                       ProjectedVertex* projected) {
  HWY_DYNAMIC_DISPATCH(TransformVertices)(positions, count, M, cam, outcodes, projected);
}
}  // namespace hsr
#endif

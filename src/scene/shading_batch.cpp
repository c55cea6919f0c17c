// The headlight Lambert shade of many triangles at once, with SIMD (Highway, dispatched at run
// time): TriangleShader::operator() (shading.cpp) lane by lane, with the same IEEE operations in
// the same order, for triangles whose face is the triangle itself (its polygon's three vertices
// in the triangle's order), so every lane gets the scalar function's bits
// (tests/raster_test.cpp, Raster.BatchedShadingEqualsScalarOnEveryInstructionSet). Used by the
// front end for the front faces it keeps.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "scene/shading_batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include "scene/shading.hpp"

HWY_BEFORE_NAMESPACE();
namespace hsr {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// k = 0.25 + 0.75 |cos| for triangles whose corners are positions[corner[0..2][i]], i < count.
void LambertFactors(const dvec3* positions, const uint32_t* const* corner, size_t count, const dvec3& eye,
                    const dvec3& forward, bool orthographic, double* factor) {
  using D = hn::CappedTag<double, 8>;
  const D d;
  const hn::Rebind<int64_t, D> di;
  const size_t N = hn::Lanes(d);
  const double* base = reinterpret_cast<const double*>(positions);
  static_assert(sizeof(dvec3) == 3 * sizeof(double));
  for (size_t first = 0; first < count; first += N) {
    const size_t lanes = std::min(N, count - first);
    HWY_ALIGN int64_t offset[3][8];
    for (int k = 0; k < 3; ++k)
      for (size_t j = 0; j < N; ++j) offset[k][j] = int64_t(corner[k][first + std::min(j, lanes - 1)]) * 3;
    using V = hn::Vec<D>;
    V x[3], y[3], z[3];
    for (int k = 0; k < 3; ++k) {
      const auto idx = hn::Load(di, offset[k]);
      x[k] = hn::GatherIndex(d, base + 0, idx);
      y[k] = hn::GatherIndex(d, base + 1, idx);
      z[k] = hn::GatherIndex(d, base + 2, idx);
    }
    // n = cross(b - a, c - a), as glm computes it.
    const V e1x = hn::Sub(x[1], x[0]), e1y = hn::Sub(y[1], y[0]), e1z = hn::Sub(z[1], z[0]);
    const V e2x = hn::Sub(x[2], x[0]), e2y = hn::Sub(y[2], y[0]), e2z = hn::Sub(z[2], z[0]);
    const V nx = hn::Sub(hn::Mul(e1y, e2z), hn::Mul(e2y, e1z));
    const V ny = hn::Sub(hn::Mul(e1z, e2x), hn::Mul(e2z, e1x));
    const V nz = hn::Sub(hn::Mul(e1x, e2y), hn::Mul(e2x, e1y));
    V vx, vy, vz;
    if (orthographic) {
      vx = hn::Set(d, forward.x), vy = hn::Set(d, forward.y), vz = hn::Set(d, forward.z);
    } else {
      // sum of (p - a) over the polygon (a, b, c), from zero; view = (a - eye) 3 + sum.
      auto sum = [&](const V* p) {
        return hn::Add(hn::Add(hn::Add(hn::Zero(d), hn::Sub(p[0], p[0])), hn::Sub(p[1], p[0])), hn::Sub(p[2], p[0]));
      };
      const V three = hn::Set(d, 3.0);
      vx = hn::Add(hn::Mul(hn::Sub(x[0], hn::Set(d, eye.x)), three), sum(x));
      vy = hn::Add(hn::Mul(hn::Sub(y[0], hn::Set(d, eye.y)), three), sum(y));
      vz = hn::Add(hn::Mul(hn::Sub(z[0], hn::Set(d, eye.z)), three), sum(z));
    }
    auto dot = [&](V ax, V ay, V az, V bx, V by, V bz) {
      return hn::Add(hn::Add(hn::Mul(ax, bx), hn::Mul(ay, by)), hn::Mul(az, bz));
    };
    const V ln2 = hn::Mul(dot(nx, ny, nz, nx, ny, nz), dot(vx, vy, vz, vx, vy, vz));
    const auto lit = hn::Gt(ln2, hn::Zero(d));
    const V cosine = hn::IfThenElse(lit, hn::Div(hn::Abs(dot(nx, ny, nz, vx, vy, vz)), hn::Sqrt(ln2)), hn::Set(d, 1.0));
    const V k = hn::Add(hn::Set(d, 0.25), hn::Mul(hn::Set(d, 0.75), cosine));
    HWY_ALIGN double out[8];
    hn::Store(k, d, out);
    for (size_t j = 0; j < lanes; ++j) factor[first + j] = out[j];
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hsr {
HWY_EXPORT(LambertFactors);

void TriangleShader::lambertFactors(const uint32_t* triangles, size_t count, double* factor) const {
  // Triangles that are their own face go to the SIMD kernel in groups; the rest one by one.
  constexpr size_t kGroup = 64;
  uint32_t corner[3][kGroup], index[kGroup];
  double grouped[kGroup];
  size_t n = 0;
  auto flush = [&] {
    const uint32_t* c[3] = {corner[0], corner[1], corner[2]};
    HWY_DYNAMIC_DISPATCH(LambertFactors)(scene_.positions.data(), c, n, eye_, forward_, orthographic_, grouped);
    for (size_t g = 0; g < n; ++g) factor[index[g]] = grouped[g];
    n = 0;
  };
  for (size_t i = 0; i < count; ++i) {
    const Triangle& tri = scene_.triangles[triangles[i]];
    if (!ownFaces_ && !ownFace(tri)) {
      factor[i] = lambertFactor(triangles[i]);
      continue;
    }
    for (int k = 0; k < 3; ++k) corner[k][n] = tri.v[k];
    index[n++] = uint32_t(i);
    if (n == kGroup) flush();
  }
  if (n) flush();
}

void TriangleShader::shadeMany(const uint32_t* triangles, size_t count, Rgba8* out) const {
  if (shading_ != Shading::Lambert) {
    for (size_t i = 0; i < count; ++i) out[i] = (*this)(triangles[i]);
    return;
  }
  constexpr size_t kGroup = 64;
  double factor[kGroup];
  for (size_t first = 0; first < count; first += kGroup) {
    const size_t n = std::min(kGroup, count - first);
    lambertFactors(triangles + first, n, factor);
    for (size_t i = 0; i < n; ++i)
      out[first + i] = lambertColor(scene_.faceColors[scene_.triangles[triangles[first + i]].face], factor[i]);
  }
}
}  // namespace hsr
#endif

// meshBounds (mesh_bounds.hpp): the occlusion buffer's test of a whole mesh — a pixel box and a
// nearest stored value for all its triangles — for runs of meshes, several at once with SIMD
// (Highway, dispatched at run time): one lane a mesh, the same arithmetic in the same order in
// every lane, so a mesh's bound does not depend on its neighbours. The planes' distance and
// the mapping to a stored value stay scalar, lane by lane.
//
// Why the box and the bound hold for every fragment of the mesh's triangles: as for a deferred
// cluster (deferCluster, steps 2.-4. in clusters.cpp), with step 1's distance c from the eye to
// each triangle's plane taken from the mesh's planes instead of a normal cone: at least
// |d - n . e| - dSlack - nSlack |e| (MeshPlane), less 1e-9 of the magnitudes involved for the
// rounding of each triangle's n_t and d_t (a few ulps: its triangles are well shaped). The mesh
// is bounded only when that is at least kEdgeOn of the greatest distance from the eye to its
// box: no triangle is seen nearer edge on, so on screen its well-shaped triangles are no slivers
// and their planes are well conditioned (step 4); half of c stands in for c against rounding, as
// half of kAway does for clusters. Occlusion.MeshBoundHoldsForEveryTriangle
// (tests/occlusion_test.cpp) checks the box and bound against every triangle's own.

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "frontend/mesh_bounds.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h

#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "frontend/clusters.hpp"
#include "frontend/mesh_bounds.hpp"
#include "setup/fixed_point.hpp"

#ifndef HSR_MESH_BOUNDS_ONCE
#define HSR_MESH_BOUNDS_ONCE
namespace hsr::mesh_bounds {
constexpr double kEdgeOn = 1e-4;
constexpr size_t kLanes = 8;  // at most (4 on AVX2)
}  // namespace hsr::mesh_bounds
#endif

HWY_BEFORE_NAMESPACE();
namespace hsr {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void MeshBounds(const Scene& scene, size_t first, size_t last, const MeshView& mv, MeshTest* tests,
                MeshBound* bounds) {
  using namespace mesh_bounds;
  const hn::CappedTag<double, kLanes> d;
  using V = hn::Vec<decltype(d)>;
  const size_t N = hn::Lanes(d);
  const Camera& cam = *mv.camera;
  // The camera's columns, lane-broadcast: [column][row].
  V pos[3][4], neg[3][4], mag[4][4], col3[4];
  for (int r = 0; r < 4; ++r) {
    for (int j = 0; j < 3; ++j) {
      pos[j][r] = hn::Set(d, mv.positive[j][r]);
      neg[j][r] = hn::Set(d, mv.negative[j][r]);
    }
    for (int j = 0; j < 4; ++j) mag[j][r] = hn::Set(d, mv.magnitude[j][r]);
    col3[r] = hn::Set(d, mv.pixelFromWorld[3][r]);
  }
  const V tiny = hn::Set(d, 1e-12), one = hn::Set(d, 1.0), zero = hn::Zero(d), half = hn::Set(d, 0.5);
  const V planeScale = hn::Set(d, 2 * kGuardBandPixels + cam.width + cam.height + 1);
  const V nearFar = hn::Set(d, cam.near + cam.far), nearV = hn::Set(d, cam.near), farV = hn::Set(d, cam.far);
  const V gx0 = hn::Set(d, -kGuardBandPixels), gx1 = hn::Set(d, cam.width + kGuardBandPixels);
  const V gy0 = hn::Set(d, -kGuardBandPixels), gy1 = hn::Set(d, cam.height + kGuardBandPixels);
  const V room = hn::Set(d, 1.0 / 256);  // pixelBoxOf's (clusters.cpp)
  const V lastX = hn::Set(d, double(cam.width - 1)), lastY = hn::Set(d, double(cam.height - 1));
  const V eye[3] = {hn::Set(d, mv.eye.x), hn::Set(d, mv.eye.y), hn::Set(d, mv.eye.z)};
  const V gradient64 = hn::Set(d, mv.gradient / 64), edgeOn = hn::Set(d, kEdgeOn);

  HWY_ALIGN double lo[3][kLanes], hi[3][kLanes], c[kLanes];
  HWY_ALIGN double outX0[kLanes], outX1[kLanes], outY0[kLanes], outY1[kLanes], outZ[kLanes], outNearest[kLanes];
  HWY_ALIGN double inView[kLanes], onScreen[kLanes], faceOn[kLanes];
  bool usable[kLanes];
  for (size_t group = first; group < last; group += N) {
    const size_t count = std::min(N, last - group);
    // Lane by lane: the box (a lane without a usable mesh gets a unit box, its result dropped),
    // and the least distance from the eye to the mesh's planes.
    bool any = false;
    for (size_t k = 0; k < N; ++k) {
      const size_t m = group + std::min(k, count - 1);
      const MeshRange& mesh = scene.meshes[m];
      usable[k] = k < count && mv.enabled && mesh.planeCount > 0 && !mesh.bounds.empty();
      any |= usable[k];
      const Bounds3& b = usable[k] ? mesh.bounds : Bounds3{dvec3(0.0), dvec3(1.0)};  // (any box: dropped)
      for (int j = 0; j < 3; ++j) lo[j][k] = b.lo[j], hi[j][k] = b.hi[j];
      c[k] = -1;
      if (!usable[k]) continue;
      const dvec3 most = glm::max(glm::abs(b.lo), glm::abs(b.hi));
      double least = std::numeric_limits<double>::infinity();
      for (uint32_t i = mesh.firstPlane; i < mesh.firstPlane + mesh.planeCount; ++i) {
        const MeshPlane& p = scene.meshPlanes[i];
        least = std::min(least, std::abs(p.d - glm::dot(p.n, mv.eye)) - p.dSlack - p.nSlack * mv.eyeLength);
      }
      c[k] = least - 1e-9 * (most.x + most.y + most.z + mv.eyeLength);
    }
    if (!any) {
      for (size_t k = 0; k < count; ++k) tests[group - first + k] = MeshTest::None;
      continue;
    }
    const V loV[3] = {hn::Load(d, lo[0]), hn::Load(d, lo[1]), hn::Load(d, lo[2])};
    const V hiV[3] = {hn::Load(d, hi[0]), hn::Load(d, hi[1]), hn::Load(d, hi[2])};
    // The box in view, by intervals: each homogeneous coordinate over the box (a bound of every
    // corner's, as transformVertex computes it, and so of every vertex's), the least from each
    // positive coefficient times the box's low end and each negative one times its high end, the
    // greatest the other way round, widened by 1e-12 of the terms' magnitudes (rounding).
    V most[3];
    for (int j = 0; j < 3; ++j) most[j] = hn::Max(hn::Abs(loV[j]), hn::Abs(hiV[j]));
    V rowLo[4], rowHi[4], terms[4];
    for (int r = 0; r < 4; ++r) {
      terms[r] = hn::Add(hn::Add(hn::Add(mag[3][r], hn::Mul(mag[0][r], most[0])), hn::Mul(mag[1][r], most[1])),
                         hn::Mul(mag[2][r], most[2]));
      V l = col3[r], h = col3[r];
      for (int j = 0; j < 3; ++j) {
        l = hn::Add(l, hn::Add(hn::Mul(pos[j][r], loV[j]), hn::Mul(neg[j][r], hiV[j])));
        h = hn::Add(h, hn::Add(hn::Mul(pos[j][r], hiV[j]), hn::Mul(neg[j][r], loV[j])));
      }
      rowLo[r] = hn::Sub(l, hn::Mul(tiny, terms[r]));
      rowHi[r] = hn::Add(h, hn::Mul(tiny, terms[r]));
    }
    const V wLo = rowLo[3], wHi = rowHi[3];  // (a pinhole camera: eye depth d is w)
    const V margin = hn::Mul(hn::Set(d, 1e-9),
                             hn::Add(hn::Add(hn::Add(hn::Add(terms[0], terms[1]), terms[2]), hn::Mul(terms[3], planeScale)),
                                     nearFar));
    auto inViewM = hn::And(hn::Gt(hn::Sub(wLo, nearV), margin), hn::Gt(hn::Sub(farV, wHi), margin));
    // (Reciprocals rather than four divisions: their rounding, ~1e-16 relative, is far within
    // the pixel box's room. A lane out of view may divide by anything: its result is dropped.)
    const V safeLo = hn::IfThenElse(inViewM, wLo, one), safeHi = hn::IfThenElse(inViewM, wHi, one);
    const V invLo = hn::Div(one, safeLo), invHi = hn::Div(one, safeHi);
    const V x0 = hn::Min(hn::Mul(rowLo[0], invLo), hn::Mul(rowLo[0], invHi));
    const V x1 = hn::Max(hn::Mul(rowHi[0], invLo), hn::Mul(rowHi[0], invHi));
    const V y0 = hn::Min(hn::Mul(rowLo[1], invLo), hn::Mul(rowLo[1], invHi));
    const V y1 = hn::Max(hn::Mul(rowHi[1], invLo), hn::Mul(rowHi[1], invHi));
    // Inside the guard band with room (every corner's planeDistance above the margin).
    const V guard = hn::Mul(hn::Add(margin, margin), invLo);
    inViewM = hn::And(inViewM, hn::And(hn::And(hn::Gt(hn::Sub(x0, gx0), guard), hn::Gt(hn::Sub(gx1, x1), guard)),
                                       hn::And(hn::Gt(hn::Sub(y0, gy0), guard), hn::Gt(hn::Sub(gy1, y1), guard))));
    // Pixels whose centres a triangle inside may cover (pixelBoxOf in clusters.cpp).
    const V bx0 = hn::Max(zero, hn::Ceil(hn::Sub(hn::Sub(x0, half), room)));
    const V bx1 = hn::Min(lastX, hn::Floor(hn::Add(hn::Sub(x1, half), room)));
    const V by0 = hn::Max(zero, hn::Ceil(hn::Sub(hn::Sub(y0, half), room)));
    const V by1 = hn::Min(lastY, hn::Floor(hn::Add(hn::Sub(y1, half), room)));
    const auto onScreenM = hn::And(hn::Le(bx0, bx1), hn::Le(by0, by1));
    // Not seen nearly edge on: c against the farthest distance from the eye to the box (L1 norms).
    const V cV = hn::Load(d, c);
    V farthest = zero;
    for (int j = 0; j < 3; ++j) {
      const V centre = hn::Mul(half, hn::Add(loV[j], hiV[j]));
      farthest = hn::Add(farthest, hn::Add(hn::Abs(hn::Sub(centre, eye[j])), hn::Mul(half, hn::Sub(hiV[j], loV[j]))));
    }
    farthest = hn::Mul(farthest, hn::Set(d, 1 + 1e-12));
    const auto faceOnM = hn::Ge(cV, hn::Mul(edgeOn, farthest));
    // 2.-4. with half of c: the largest D = (1 + 1e-6) / zMin + 2 (gradient / (c / 2)) / 256, as
    // an eye depth (one division).
    const V denominator = hn::Add(hn::Mul(hn::Set(d, 1 + 1e-6), cV), hn::Mul(wLo, gradient64));
    const V safeDen = hn::IfThenElse(hn::And(inViewM, faceOnM), denominator, one);
    const V nearestDepth = hn::Div(hn::Mul(hn::Set(d, 1 - 1e-12), hn::Mul(wLo, cV)), safeDen);
    hn::Store(bx0, d, outX0);
    hn::Store(bx1, d, outX1);
    hn::Store(by0, d, outY0);
    hn::Store(by1, d, outY1);
    hn::Store(wLo, d, outZ);
    hn::Store(nearestDepth, d, outNearest);
    hn::Store(hn::IfThenElseZero(inViewM, one), d, inView);
    hn::Store(hn::IfThenElseZero(onScreenM, one), d, onScreen);
    hn::Store(hn::IfThenElseZero(faceOnM, one), d, faceOn);
    for (size_t k = 0; k < count; ++k) {
      MeshTest& test = tests[group - first + k];
      MeshBound& out = bounds[group - first + k];
      test = MeshTest::None;
      if (!usable[k] || inView[k] == 0) continue;
      if (onScreen[k] == 0) {
        test = MeshTest::Outside;
        continue;
      }
      out.minX = int16_t(outX0[k]), out.maxX = int16_t(outX1[k]), out.minY = int16_t(outY0[k]),
      out.maxY = int16_t(outY1[k]);
      out.zMin = outZ[k];
      if (faceOn[k] == 0) continue;
      out.nearest = storedNearest(outNearest[k], mv.depth);
      if (std::isfinite(out.nearest) && outNearest[k] > 0) test = MeshTest::Bounded;
    }
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace hsr
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hsr {
HWY_EXPORT(MeshBounds);

void meshBounds(const Scene& scene, size_t first, size_t last, const MeshView& view, MeshTest* tests,
                MeshBound* bounds) {
  HWY_DYNAMIC_DISPATCH(MeshBounds)(scene, first, last, view, tests, bounds);
}

MeshTest meshBound(const Scene& scene, size_t mesh, const MeshView& view, MeshBound& out) {
  MeshTest test;
  meshBounds(scene, mesh, mesh + 1, view, &test, &out);
  return test;
}
}  // namespace hsr
#endif

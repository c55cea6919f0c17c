// Shared pieces of the built-in scene generators: validated parameters, a portable random
// number source, the colour palette and the box builder. Used by builtin.cpp (registry and spec
// parsing) and the generator files builtin_classic.cpp and builtin_stress.cpp.
#pragma once
#include <cstdint>
#include <hsr/builtin.hpp>
#include <map>
#include <random>
#include <string>

namespace hsr::builtin {

/// The parameters of one generation: every parameter of the scene, given or defaulted, already
/// checked against its range. Asking for a parameter the scene does not declare is a bug.
class Args {
 public:
  struct Value {
    int64_t integer = 0;
    double real = 0;
    std::string text;
  };
  std::map<std::string, Value, std::less<>> values;

  int64_t integer(std::string_view name) const { return at(name).integer; }
  double real(std::string_view name) const { return at(name).real; }
  const std::string& text(std::string_view name) const { return at(name).text; }

 private:
  const Value& at(std::string_view name) const;
};

/// Uniform numbers from a std::mt19937_64, whose output sequence the C++ standard fixes. The
/// mapping to reals is our own (53 random bits -> [0, 1)), unlike
/// std::uniform_real_distribution, whose results differ between standard libraries.
class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  double uniform() { return double(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [0, n), n > 0 (a fixed-point multiply: portable, bias below 2^-53 * n).
  uint64_t below(uint64_t n) { return uint64_t(uniform() * double(n)); }
  /// Uniform direction on the unit sphere (rejection in the cube: only +, *, sqrt, so the
  /// result is bit-identical on every IEEE platform, unlike sin/cos from a maths library).
  dvec3 unitVector();

 private:
  std::mt19937_64 engine_;
};

/// Pleasant, distinct colours: hues stepped by the golden angle, so neighbours in index order
/// differ strongly. `saturation` and `value` in [0, 1].
Rgba8 paletteColor(uint64_t index, double saturation = 0.55, double value = 0.92);
/// `color` scaled towards black by `factor` in [0, 1] (1 keeps it).
Rgba8 shade(Rgba8 color, double factor);

/// Adds a box as 8 vertices and 6 quads wound counter-clockwise seen from outside (outward
/// normals, so back-face culling works). `axes` columns are the box's orthonormal axes (a proper
/// rotation), `half` the half extents along them. faceColor(k) gives the colour of quad k in the
/// order -x, +x, -y, +y, -z, +z.
template <class FaceColor>
void addBox(Scene& scene, const dvec3& center, const dmat3& axes, const dvec3& half,
            FaceColor faceColor) {
  const auto base = uint32_t(scene.positions.size());
  for (int corner = 0; corner < 8; ++corner) {
    const dvec3 local((corner & 1) ? half.x : -half.x, (corner & 2) ? half.y : -half.y,
                      (corner & 4) ? half.z : -half.z);
    scene.positions.push_back(center + axes * local);
  }
  // Corner index bits are (x, y, z); each row lists a face counter-clockwise seen from outside.
  static constexpr uint32_t kQuads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                            {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int k = 0; k < 6; ++k) {
    const auto* q = kQuads[k];
    scene.addFace({base + q[0], base + q[1], base + q[2], base + q[3]}, faceColor(k));
  }
}

/// Adds a polygon of 3 to 8 new vertices, in the given (counter-clockwise as seen) order.
void addPolygon(Scene& scene, std::initializer_list<dvec3> corners, Rgba8 color);

/// Brightness factor of box face k (order of addBox), so that faces of one colour stay apart
/// even in flat shading.
inline double faceShade(int k) {
  static constexpr double kShade[6] = {0.78, 0.9, 0.6, 1.0, 0.7, 0.85};
  return kShade[k];
}

/// Rotation about the y axis by the angle whose cosine and sine are given (pass exact pairs such
/// as 4/5, 3/5 rather than calling std::cos: the scenes must be bit-identical everywhere).
dmat3 rotationY(double cosine, double sine);
/// Rotation about the x axis, likewise.
dmat3 rotationX(double cosine, double sine);

/// An OpenGL-style default camera (y up) with explicit clipping planes.
CameraSpec perspectiveCamera(const dvec3& eye, const dvec3& target, double fovyDeg, double near,
                             double far);

// The generators, one per scene (builtin_classic.cpp: small figures of the documents;
// builtin_stress.cpp: large and parametric scenes). Each returns an unfinalized scene with its
// meshes (Scene::beginMesh per object; finalize() counts their faces) and default camera;
// makeBuiltin() sets the source and finalizes.
Scene makeCubes(const Args&);
Scene makePainterMidpoint(const Args&);
Scene makePainterCycle(const Args&);
Scene makeInterpenetrate(const Args&);
Scene makeZfight(const Args&);
Scene makeGlass(const Args&);
Scene makeRandom(const Args&);
Scene makeSphere(const Args&);
Scene makeLayers(const Args&);
Scene makeCity(const Args&);
Scene makeClutter(const Args&);
Scene makeCsg(const Args&);

/// Largest triangle count any generator may produce: guards memory against absurd parameters.
inline constexpr int64_t kMaxTriangles = 50'000'000;

}  // namespace hsr::builtin

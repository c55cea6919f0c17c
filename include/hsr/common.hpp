// Basic types shared by every part of hsr: double-precision math (glm), colours, the one
// exception type for bad input, and small helpers. Included by every public header.
#pragma once
#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace hsr {

using dvec2 = glm::dvec2;
using dvec3 = glm::dvec3;
using dvec4 = glm::dvec4;
using dmat3 = glm::dmat3;
using dmat4 = glm::dmat4;

/// Bad input: a malformed file, an out-of-range option, NaN coordinates, ... The message is one
/// line naming the file (and line, where there is one) and the problem: "file:line: problem".
/// The command line turns it into exit status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// 8-bit RGBA colour. Alpha is opacity (255 = opaque).
struct Rgba8 {
  uint8_t r = 0, g = 0, b = 0, a = 255;
  friend bool operator==(const Rgba8&, const Rgba8&) = default;
};

/// Axis-aligned bounding box in double precision.
struct Bounds3 {
  dvec3 lo{std::numeric_limits<double>::infinity()};
  dvec3 hi{-std::numeric_limits<double>::infinity()};
  bool empty() const { return lo.x > hi.x; }
  void add(const dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const Bounds3& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  dvec3 center() const { return (lo + hi) * 0.5; }
};

}  // namespace hsr

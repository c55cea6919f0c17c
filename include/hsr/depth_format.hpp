// Depth buffer formats: a storage type (u16, u24, u32, f32) and a mapping from eye depth d to a
// stored value in [0, 1]. Written "STORAGE:MAPPING" on the command line (--depth-format).
//
//  mapping   value                          clear  nearer wins   notes
//  z         OpenGL window z, far = 1       1      less          perspective: f(d-n)/((f-n)d)
//  reversed  1 - z                          0      greater       reversed-Z; with f32 the default
//  inv       n / d  (1/w scaled, as in the Java chapter) 0      greater       0 is infinitely far
//  linear    (d - n) / (f - n)              1      less          eye depth, equal steps
//
// Integer storage keeps round(value * (2^bits - 1)); f32 keeps the value rounded to float.
// Default: f32:reversed — float's exponent puts its finest steps near 0, which reversed-Z puts
// at the far plane, where perspective z is coarsest: the two cancel and precision is nearly
// uniform in eye depth (Reed, "Depth Precision Visualized").
#pragma once
#include <cstdint>
#include <string>

namespace hsr {

enum class DepthStorage : uint8_t { U16, U24, U32, F32 };
enum class DepthMapping : uint8_t { Z, Reversed, Inv, Linear };

struct DepthFormat {
  DepthStorage storage = DepthStorage::F32;
  DepthMapping mapping = DepthMapping::Reversed;

  /// Parses "u16:z", "f32:reversed", ... (also just "u24", mapping z). Throws InputError.
  static DepthFormat parse(const std::string& text);
  std::string name() const;

  bool greaterWins() const { return mapping == DepthMapping::Reversed || mapping == DepthMapping::Inv; }
  double clearValue() const { return greaterWins() ? 0.0 : 1.0; }
  int bits() const;
  /// Bytes per pixel of the buffer as allocated (u24 is kept in 32 bits).
  int bytesPerPixel() const;

  /// Mapped value in [0, 1] (clamped) of eye depth d, for a camera with these planes.
  double map(double d, double near, double far, bool orthographic) const;
  /// Value as stored (integer code or float), as a double.
  double quantize(double value) const;
  /// Smallest step the storage can make at `value` (1 / (2^bits - 1), or the float ulp there).
  double resolution(double value) const;
};

}  // namespace hsr

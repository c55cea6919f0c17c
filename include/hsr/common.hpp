// Basic types shared by every part of hsr: double-precision math (glm), colours, the one
// exception type for bad input, and small helpers. Included by every public header.
#pragma once
#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace hsr {

using dvec2 = glm::dvec2;
using dvec3 = glm::dvec3;
using dvec4 = glm::dvec4;
using dmat3 = glm::dmat3;
using dmat4 = glm::dmat4;

/// The settings of the library's API an InputError can be about. The library does not know how a
/// front end spells them (the CLI's "--depth-format", Python's "depth_format"): a keyed error
/// names its setting, and each front end words it in its own terms (InputError::worded).
enum class Setting : uint8_t {
  None,           // a plain error: no setting
  Algorithm,      // RenderOptions::algorithm
  Param,          // RenderOptions::params; subject "KEY=VALUE"
  Size,           // the image size, Camera::width and height; subject "WxH"
  DepthFormat,    // RenderOptions::depthFormat
  Verify,         // RenderOptions::verify
  SwitchOff,      // switchOff(); subject: the switch's name
  Svg,            // vector output (writeSvg)
  OverdrawImage,  // RenderOptions::countWrites, the overdraw picture
  ShadowMapSize,  // ShadowOptions::mapSize; subject: the size given
  ShadowBias,     // ShadowOptions::bias
  MaxMemory,      // the memory limit (setMemoryLimit); subject: the request it refuses
};

/// Bad input: a malformed file, an out-of-range option, NaN coordinates, ... The message is one
/// line naming the file (and line, where there is one) and the problem: "file:line: problem".
/// An error about a setting is keyed: it carries the setting, the subject (the value or request
/// in question; may be empty) and the detail, and what() words them neutrally ("depth format:
/// unknown storage 'u17' (...)") for a front end to word again as its own. The command line
/// turns an InputError into exit status 2, the Python module into ValueError.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;  // a plain error: the message as it is
  InputError(Setting setting, std::string subject, std::string detail);

  Setting setting() const { return key_ ? key_->setting : Setting::None; }
  const std::string& subject() const;
  const std::string& detail() const;
  /// The message with the setting called `name` and the subject written `subject`: "NAME
  /// SUBJECT: DETAIL" ("NAME: DETAIL" without a subject); for MaxMemory the request comes first
  /// and the setting that would let it through last, "SUBJECT DETAIL (NAME)". A plain error's
  /// message is what() whatever the name.
  std::string worded(const std::string& name, const std::string& subject) const;
  std::string worded(const std::string& name) const { return worded(name, subject()); }

 private:
  struct Key {
    Setting setting;
    std::string subject, detail;
  };
  std::shared_ptr<const Key> key_;  // shared: an exception is copied without throwing
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

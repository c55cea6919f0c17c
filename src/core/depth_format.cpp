// Depth formats: parsing, the eye-depth -> stored-value mappings and their resolution.
// The mappings are the single definition used by the z-buffer, --verify and the docs.
#include <hsr/common.hpp>
#include <hsr/depth_format.hpp>

#include <algorithm>
#include <cmath>

#include "core/depth_map.hpp"

namespace hsr {

DepthFormat DepthFormat::parse(const std::string& text) {
  DepthFormat f;
  std::string storage = text, mapping = "z";
  if (auto colon = text.find(':'); colon != std::string::npos) {
    storage = text.substr(0, colon);
    mapping = text.substr(colon + 1);
  } else if (text == "f32") {
    mapping = "reversed";
  }
  if (storage == "u16") f.storage = DepthStorage::U16;
  else if (storage == "u24") f.storage = DepthStorage::U24;
  else if (storage == "u32") f.storage = DepthStorage::U32;
  else if (storage == "f32") f.storage = DepthStorage::F32;
  else throw InputError(Setting::DepthFormat, "", "unknown storage '" + storage + "' (u16, u24, u32, f32)");
  if (mapping == "z") f.mapping = DepthMapping::Z;
  else if (mapping == "reversed") f.mapping = DepthMapping::Reversed;
  else if (mapping == "inv") f.mapping = DepthMapping::Inv;
  else if (mapping == "linear") f.mapping = DepthMapping::Linear;
  else throw InputError(Setting::DepthFormat, "", "unknown mapping '" + mapping + "' (z, reversed, inv, linear)");
  return f;
}

std::string DepthFormat::name() const {
  static const char* s[] = {"u16", "u24", "u32", "f32"};
  static const char* m[] = {"z", "reversed", "inv", "linear"};
  return std::string(s[int(storage)]) + ":" + m[int(mapping)];
}

int DepthFormat::bits() const {
  switch (storage) {
    case DepthStorage::U16: return 16;
    case DepthStorage::U24: return 24;
    default: return 32;
  }
}

int DepthFormat::bytesPerPixel() const { return storage == DepthStorage::U16 ? 2 : 4; }

double DepthFormat::map(double d, double n, double f, bool ortho) const {
  switch (mapping) {
    case DepthMapping::Z: return mapDepth<DepthMapping::Z>(d, n, f, ortho);
    case DepthMapping::Reversed: return mapDepth<DepthMapping::Reversed>(d, n, f, ortho);
    case DepthMapping::Inv: return mapDepth<DepthMapping::Inv>(d, n, f, ortho);
    default: return mapDepth<DepthMapping::Linear>(d, n, f, ortho);
  }
}

double DepthFormat::quantize(double v) const {
  if (storage == DepthStorage::F32) return double(float(v));
  double scale = std::ldexp(1.0, bits()) - 1;
  return std::floor(v * scale + 0.5);
}

double DepthFormat::resolution(double v) const {
  if (storage == DepthStorage::F32) {
    float fv = float(v);
    return double(std::nextafter(fv, 2.0f)) - double(fv);
  }
  return 1.0 / (std::ldexp(1.0, bits()) - 1);
}

}  // namespace hsr

// Keyword values of the module's functions read into hsr's options, with ValueError naming the
// keyword for a bad one (hsr.screen_polygons; the same words as hsr.render's).
#pragma once
#include "common.hpp"

#include <initializer_list>
#include <map>
#include <string>
#include <utility>

namespace hsrpy {

/// The value `names` gives `value`; ValueError "WHAT 'VALUE': unknown (known: ...)" otherwise.
template <class Enum>
Enum choice(const std::string& what, const std::string& value, std::initializer_list<std::pair<const char*, Enum>> names) {
  std::string known;
  for (const auto& [name, e] : names) {
    if (value == name) return e;
    known += (known.empty() ? "" : ", ") + std::string(name);
  }
  valueError(what + " '" + value + "': unknown (known: " + known + ")");
}

inline hsr::Cull cullOf(const std::string& cull) {
  return choice<hsr::Cull>("cull", cull, {{"none", hsr::Cull::None}, {"back", hsr::Cull::Back}, {"front", hsr::Cull::Front}});
}

inline hsr::Shading shadingOf(const std::string& shading) {
  return choice<hsr::Shading>(
      "shading", shading, {{"lambert", hsr::Shading::Lambert}, {"flat", hsr::Shading::Flat}, {"faceid", hsr::Shading::FaceId}});
}

/// An algorithm's parameters from a dict (None: none); booleans as on/off, other values as text.
inline std::map<std::string, std::string> paramsOf(py::handle params) {
  std::map<std::string, std::string> out;
  if (params.is_none()) return out;
  if (!py::isinstance<py::dict>(params)) valueError("params: expected a dict of name: value");
  for (auto [key, value] : py::reinterpret_borrow<py::dict>(params)) {
    if (!py::isinstance<py::str>(key)) valueError("params: names are strings");
    const bool isBool = py::isinstance<py::bool_>(value);
    out[key.cast<std::string>()] = isBool ? (value.cast<bool>() ? "on" : "off") : py::str(value).cast<std::string>();
  }
  return out;
}

}  // namespace hsrpy

// JSON parsing with error messages that name the file and line (nlohmann reports a byte offset).
// Used by the camera, scene JSON and CLI readers.
#pragma once
#include <hsr/common.hpp>

#include <nlohmann/json.hpp>
#include <string>

namespace hsr {

inline nlohmann::json parseJsonOrThrow(const std::string& text, const std::string& src) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    size_t line = 1;
    for (size_t i = 0; i < e.byte && i < text.size(); ++i) line += text[i] == '\n';
    std::string what = e.what();
    auto pos = what.find("parse error");
    throw InputError(src + ":" + std::to_string(line) + ": JSON " + (pos == std::string::npos ? what : what.substr(pos)));
  } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double
    throw InputError(src + ": JSON " + e.what());
  }
}

}  // namespace hsr

// Built-in scenes, generated deterministically from their parameters (seed included):
// "builtin:NAME" or "builtin:NAME?n=5000&seed=7". Consumed by loadScene() and `hsr scenes`.
#pragma once
#include <hsr/scene.hpp>

#include <map>
#include <string>
#include <vector>

namespace hsr {

struct BuiltinParam {
  std::string name;
  std::string defaultValue;
  std::string help;
};
struct BuiltinInfo {
  std::string name;
  std::string summary;
  std::vector<BuiltinParam> params;
};

const std::vector<BuiltinInfo>& builtinScenes();
/// Generates builtin scene `spec` ("NAME" or "NAME?k=v&k=v", without the "builtin:" prefix).
/// Throws InputError on an unknown name or parameter. The scene is finalized and carries a
/// default camera suited to it.
Scene makeBuiltin(const std::string& spec);

}  // namespace hsr

// `hsr algorithms` and `hsr scenes`: the registries of visibility algorithms and built-in scenes,
// listed as text, JSON or (algorithms) Markdown parameter tables for docs/algorithms/NAME.md.
// Set up by apps/main.cpp's table; `hsr help algorithms` prints the same listing.
#include <hsr/hsr.hpp>

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <memory>
#include <sstream>
#include <tuple>

#include "commands.hpp"

namespace hsr::cli {
namespace {

using Json = nlohmann::ordered_json;

// The guarantees an algorithm gives with other values of its choice parameters, where they
// differ from its default one: (parameter, value, guarantee).
std::vector<std::tuple<std::string, std::string, std::string>> otherGuarantees(const hsr::AlgorithmInfo& a) {
  std::vector<std::tuple<std::string, std::string, std::string>> out;
  if (!a.guaranteeFor) return out;
  const std::string byDefault = a.guaranteeWith(hsr::resolveParams(a, {})).describe();
  for (const hsr::ParamSpec& p : a.params)
    for (const std::string& value : p.choices) {
      const std::string g = a.guaranteeWith(hsr::resolveParams(a, {{p.name, value}})).describe();
      if (g != byDefault) out.emplace_back(p.name, value, g);
    }
  return out;
}

// `hsr algorithms`: the registry, as text or JSON.
Json algorithmsJson() {
  Json out = Json::array();
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) {
    Json params = Json::array();
    for (const hsr::ParamSpec& p : a.params) {
      Json entry = {{"name", p.name}, {"type", hsr::paramTypeName(p.type)}, {"default", p.defaultValue}};
      if (p.type == hsr::ParamType::Choice) entry["values"] = p.choices;
      if (p.type == hsr::ParamType::Int || p.type == hsr::ParamType::Real || p.type == hsr::ParamType::Size)
        entry["range"] = {p.min, p.max};
      entry["help"] = p.help;
      params.push_back(entry);
    }
    Json others = Json::array();
    for (const auto& [param, value, guarantee] : otherGuarantees(a))
      others.push_back({{"param", param}, {"value", value}, {"guarantee", guarantee}});
    out.push_back({{"name", a.name}, {"summary", a.summary}, {"source", a.source},
                   {"guarantee", a.guaranteeWith(hsr::resolveParams(a, {})).describe()}, {"params", params},
                   {"guarantee_with", others}});
  }
  return out;
}

// `text` broken into lines of at most `width` characters, each after `indent`.
std::string wrapped(const std::string& text, const std::string& indent, size_t width = 96) {
  std::string out, line;
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    if (!line.empty() && indent.size() + line.size() + 1 + word.size() > width) {
      out += indent + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += indent + line + "\n";
  return out;
}

}  // namespace

void printAlgorithms() {
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) {
    const hsr::Guarantee byDefault = a.guaranteeWith(hsr::resolveParams(a, {}));
    fmt::print("{}\n  {}\n  source: {}\n{}", a.name, a.summary, a.source,
               wrapped("guarantee: " + byDefault.describe(), "  "));
    if (!byDefault.condition.empty() && byDefault.kind == hsr::Guarantee::Kind::Exact)
      fmt::print("{}", wrapped("(" + byDefault.condition + ")", "    "));
    for (const auto& [param, value, guarantee] : otherGuarantees(a))
      fmt::print("{}", wrapped("with " + param + "=" + value + ": " + guarantee, "    "));
    if (a.params.empty()) fmt::print("  parameters: none\n");
    for (const hsr::ParamSpec& p : a.params) {
      std::string values = p.type == hsr::ParamType::Choice ? fmt::format("{}", fmt::join(p.choices, "|"))
                           : p.type == hsr::ParamType::Bool ? "on|off"
                           : p.type == hsr::ParamType::Size
                               ? fmt::format("WxH|full (each in [{}, {}])", p.min, p.max)
                               : fmt::format("{} in [{}, {}]", hsr::paramTypeName(p.type), p.min, p.max);
      fmt::print("  --param {}={}  (default {})\n{}", p.name, values, p.defaultValue, wrapped(p.help, "      "));
    }
    fmt::print("\n");
  }
  fmt::print("Set a parameter with 'hsr render SCENE --algorithm NAME --param KEY=VALUE'.\n");
}

Runner setupAlgorithms(CLI::App& cmd) {
  auto json = std::make_shared<bool>(false);
  cmd.add_flag("--json", *json, "Print a JSON array instead");
  return [json] {
    if (*json) fmt::print("{}\n", algorithmsJson().dump(2));
    else printAlgorithms();
    return 0;
  };
}

Runner setupScenes(CLI::App& cmd) {
  auto json = std::make_shared<bool>(false);
  auto names = std::make_shared<bool>(false);
  cmd.add_flag("--json", *json, "Print a JSON array instead");
  cmd.add_flag("--names", *names, "Print only the names, one per line (for scripts)");
  cmd.footer("Use one as SCENE: builtin:NAME or builtin:NAME?param=value&param=value");
  return [json, names] {
    if (*names) {
      for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) fmt::print("{}\n", b.name);
      return 0;
    }
    if (*json) {
      Json out = Json::array();
      for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) {
        Json params = Json::array();
        for (const hsr::BuiltinParam& p : b.params)
          params.push_back({{"name", p.name}, {"default", p.defaultValue}, {"help", p.help}});
        out.push_back({{"name", b.name}, {"summary", b.summary}, {"params", params}});
      }
      fmt::print("{}\n", out.dump(2));
      return 0;
    }
    for (const hsr::BuiltinInfo& b : hsr::builtinScenes()) {
      fmt::print("builtin:{:<16} {}\n", b.name, b.summary);
      for (const hsr::BuiltinParam& p : b.params) fmt::print("    {:<20} {}\n", p.name + "=" + p.defaultValue, p.help);
    }
    return 0;
  };
}

}  // namespace hsr::cli

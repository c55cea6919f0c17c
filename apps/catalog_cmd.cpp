// `hsr algorithms` and `hsr scenes`: the registries of visibility algorithms and built-in scenes,
// listed as text, JSON or (algorithms) the Markdown parameter tables of docs/algorithms/NAME.md.
// Set up by apps/main.cpp's table; `hsr help algorithms` prints the same listing.
#include <hsr/hsr.hpp>

#include <fmt/core.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <memory>
#include <sstream>
#include <string_view>
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

// Text for a Markdown table cell: '|' and the characters that would start emphasis, code or
// HTML escaped, line breaks as spaces.
std::string markdownText(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n') c = ' ';
    if (std::string_view("\\|*_`<").find(c) != std::string_view::npos) out += '\\';
    out += c;
  }
  return out;
}

// The values a parameter allows, for the Markdown table.
std::string markdownValues(const hsr::ParamSpec& p) {
  switch (p.type) {
    case hsr::ParamType::Choice: {
      std::string values;
      for (const std::string& c : p.choices) values += (values.empty() ? "`" : ", `") + c + "`";
      return values;
    }
    case hsr::ParamType::Bool: return "`on`, `off`";
    case hsr::ParamType::Size: return fmt::format("`WxH` (each {} to {}), `full`", p.min, p.max);
    case hsr::ParamType::Int:
    case hsr::ParamType::Real: break;
  }
  return fmt::format("{} to {}", p.min, p.max);
}

// An algorithm's parameters as a Markdown table: what docs/algorithms/NAME.md shows between its
// "params" markers (scripts/docs-params.sh; tests/cli_test.cpp checks they agree).
std::string markdownTable(const hsr::AlgorithmInfo& a) {
  if (a.params.empty()) return "None.\n";
  std::string table = "| `--param` | type | default | values | what |\n|---|---|---|---|---|\n";
  for (const hsr::ParamSpec& p : a.params)
    table += fmt::format("| `{}` | {} | `{}` | {} | {} |\n", p.name, hsr::paramTypeName(p.type), p.defaultValue,
                         markdownValues(p), markdownText(p.help));
  return table;
}

// `hsr algorithms --markdown [NAME]`: NAME's table, or every algorithm's under a heading.
void printMarkdown(const std::string& name) {
  if (!name.empty()) {
    const hsr::AlgorithmInfo* a = hsr::findAlgorithm(name);
    if (!a) throw InputError(fmt::format("algorithms '{}': unknown algorithm (known: {})", name, algorithmNames()));
    fmt::print("{}", markdownTable(*a));
    return;
  }
  const char* separator = "";
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) {
    fmt::print("{}## {}\n\n{}", separator, a.name, markdownTable(a));
    separator = "\n";
  }
}

}  // namespace

std::string algorithmNames() {
  std::string names;
  for (const hsr::AlgorithmInfo& a : hsr::algorithms()) names += (names.empty() ? "" : ", ") + a.name;
  return names;
}

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
  auto markdown = std::make_shared<bool>(false);
  auto name = std::make_shared<std::string>();
  CLI::Option* jsonFlag = cmd.add_flag("--json", *json, "Print a JSON array instead");
  CLI::Option* markdownFlag =
      cmd.add_flag("--markdown", *markdown,
                   "Print each algorithm's parameter table in Markdown (name, type, default, values, help), each "
                   "under a '## NAME' heading; with NAME, only that algorithm's table")
          ->excludes(jsonFlag);
  cmd.add_option("name", *name, "With --markdown: only this algorithm")->type_name("NAME")->needs(markdownFlag);
  cmd.footer(
      "docs/algorithms/NAME.md shows 'hsr algorithms --markdown NAME' between its params markers; "
      "scripts/docs-params.sh regenerates them.");
  return [json, markdown, name] {
    if (*json) fmt::print("{}\n", algorithmsJson().dump(2));
    else if (*markdown) printMarkdown(*name);
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

// `hsr precision`: how finely each depth format separates eye depths between near and far, how
// its stored values are spread over the range, and the source documents' claims about it.
#include <hsr/hsr.hpp>

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>

#include "commands.hpp"
#include "compare/study.hpp"

namespace hsr::cli {
namespace {

const char* const kAllFormats[] = {"u16:z", "u24:z", "u32:z", "f32:z", "u16:reversed", "u24:reversed",
                                   "u32:reversed", "f32:reversed", "u16:inv", "u24:inv", "u32:inv", "f32:inv",
                                   "u16:linear", "u24:linear", "u32:linear", "f32:linear"};
// Where in the range the table samples: fractions of far - near.
const double kRangePoints[] = {0.0, 0.01, 0.1, 0.5, 1.0};
const double kValueParts[] = {0.01, 0.02, 0.1, 0.5};

struct PrecisionFlags {
  double near = 1, far = 100;
  std::string formats;
  bool json = false;
};

std::vector<DepthFormat> formatsOf(const std::string& list) {
  std::vector<DepthFormat> formats;
  if (list.empty()) {
    for (const char* f : kAllFormats) formats.push_back(DepthFormat::parse(f));
    return formats;
  }
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');) formats.push_back(DepthFormat::parse(name));
  if (formats.empty()) throw InputError("--formats: no format given");
  return formats;
}

Json formatJson(const DepthPrecision& p) {
  Json steps = Json::array(), parts = Json::array();
  for (double x : kRangePoints) {
    const double d = p.near + x * (p.far - p.near);
    steps.push_back({{"eye_depth", d}, {"step", p.step(d)}, {"relative_step", p.step(d) / d}});
  }
  for (double x : kValueParts) parts.push_back({{"first_part", x}, {"value_fraction", p.valueFraction(x)}});
  return {{"format", p.format.name()},
          {"values", p.valuesBetween(p.near, p.far)},
          {"steps", steps},
          {"value_fractions", parts}};
}

void printTable(const PrecisionFlags& f, const std::vector<DepthFormat>& formats) {
  fmt::print("Depth precision, perspective, near {} far {} (far/near {}):\n", f.near, f.far, f.far / f.near);
  fmt::print("  smallest separable eye-depth difference at a depth (a fraction of the way from near to far), and\n"
             "  the share of the stored values lying in the first 1%, 2%, 10%, 50% of the range\n");
  fmt::print("{:<14}{:>13}", "format", "values");
  for (double x : kRangePoints) fmt::print("{:>12}", fmt::format("step@{:g}%", 100 * x));
  for (double x : kValueParts) fmt::print("{:>9}", fmt::format("{:g}%", 100 * x));
  fmt::print("\n");
  for (const DepthFormat& format : formats) {
    const DepthPrecision p{format, f.near, f.far};
    fmt::print("{:<14}{:>13}", format.name(), p.valuesBetween(f.near, f.far));
    for (double x : kRangePoints) fmt::print("{:>12.3e}", p.step(f.near + x * (f.far - f.near)));
    for (double x : kValueParts) fmt::print("{:>8.2f}%", 100 * p.valueFraction(x));
    fmt::print("\n");
  }
}

int runPrecision(const PrecisionFlags& f) {
  checkPrecisionPlanes(f.near, f.far, "--near/--far");
  const std::vector<DepthFormat> formats = formatsOf(f.formats);
  const Json claims = precisionClaims();
  if (f.json) {
    Json out = {{"near", f.near}, {"far", f.far}, {"formats", Json::array()}, {"claims", claims}};
    for (const DepthFormat& format : formats) out["formats"].push_back(formatJson({format, f.near, f.far}));
    fmt::print("{}\n", out.dump(2));
    return 0;
  }
  printTable(f, formats);
  fmt::print("\nClaims:\n");
  for (const Json& c : claims)
    fmt::print("  {} [{}]: {} - {}\n", c["claim"].get<std::string>(), c["source"].get<std::string>(),
               c["measured"].get<std::string>(), c["verdict"].get<std::string>());
  return 0;
}

}  // namespace

Runner setupPrecision(CLI::App& cmd) {
  auto f = std::make_shared<PrecisionFlags>();
  cmd.add_option("--near", f->near, "Near plane (eye depth)")->type_name("N")->capture_default_str();
  cmd.add_option("--far", f->far, "Far plane (eye depth)")->type_name("F")->capture_default_str();
  cmd.add_option("--formats", f->formats, "Depth formats, comma-separated (default: all 16)")->type_name("LIST");
  cmd.add_flag("--json", f->json, "Print one JSON object instead");
  cmd.footer(
      "A step is the width in eye depth of the depths stored as one value: two surfaces closer than that can be\n"
      "stored equal and z-fight. Computed exactly from each format's mapping and rounding (docs/precision.md).\n\n"
      "Examples:\n"
      "  hsr precision --near 1 --far 1000\n"
      "  hsr precision --near 0.1 --far 100 --formats u16:z,u24:z,f32:z,f32:reversed,u16:inv --json");
  return [f] { return runPrecision(*f); };
}

}  // namespace hsr::cli

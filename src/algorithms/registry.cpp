// The algorithm registry: one line per algorithm (each declares itself in its own file,
// src/algorithms/NAME.cpp), the parameter checks of --param, and the guarantee's wording.
// Read by Renderer, the command line (`hsr algorithms`) and the conformance tests.
#include <hsr/algorithm.hpp>
#include <hsr/common.hpp>

#include <charconv>
#include <cmath>
#include <stdexcept>

// The built-in algorithms, one line each, in the order `hsr algorithms` lists them: X(name) is
// `AlgorithmInfo name##Algorithm()`, defined in the algorithm's own file.
#define HSR_ALGORITHMS(X) \
  X(zbuffer)              \
  X(zbufferSliced)        \
  X(zbufferRegions)       \
  X(zbufferHalfRange)     \
  X(zbufferCulled)        \
  X(raycast)              \
  X(painter)              \
  X(reversePainter)       \
  X(sortedZbuffer)        \
  X(bsp)                  \
  X(hzb)                  \
  X(midpoint)             \
  X(newell)               \
  X(abuffer)              \
  X(csg)

namespace hsr {
namespace algo {
#define HSR_DECLARE_ALGORITHM(name) AlgorithmInfo name##Algorithm();
HSR_ALGORITHMS(HSR_DECLARE_ALGORITHM)
#undef HSR_DECLARE_ALGORITHM
}  // namespace algo

namespace {

void checkDeclaration(const AlgorithmInfo& a);

// A deque: registerAlgorithm appends without moving the entries findAlgorithm handed out.
std::deque<AlgorithmInfo>& registry() {
  static std::deque<AlgorithmInfo> list = [] {
#define HSR_LIST_ALGORITHM(name) algo::name##Algorithm(),
    std::deque<AlgorithmInfo> builtIn = {HSR_ALGORITHMS(HSR_LIST_ALGORITHM)};
#undef HSR_LIST_ALGORITHM
    for (const AlgorithmInfo& a : builtIn) checkDeclaration(a);
    return builtIn;
  }();
  return list;
}

std::string joined(const std::vector<std::string>& words, const char* separator) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : separator) + w;
  return out;
}

// A number as a person writes it: 64, 0.5, 1e+300.
std::string fmtNumber(double v) {
  if (v == std::floor(v) && std::abs(v) < 1e15) return std::to_string(int64_t(v));
  std::string s = std::to_string(v);
  while (s.size() > 1 && s.back() == '0') s.pop_back();
  return s;
}

bool parseNumber(const std::string& text, double& value) {
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return !text.empty() && ec == std::errc() && end == text.data() + text.size() && std::isfinite(value);
}

// The canonical text of `value` for parameter `p`, or an InputError naming the problem.
std::string checkedValue(const AlgorithmInfo& algorithm, const ParamSpec& p, const std::string& value) {
  auto fail = [&](const std::string& problem) -> std::string {
    throw InputError(Setting::Param, p.name + "=" + value, problem);
  };
  switch (p.type) {
    case ParamType::Choice:
      for (const std::string& c : p.choices)
        if (c == value) return value;
      return fail("not a value of " + algorithm.name + "'s " + p.name + " (one of " + joined(p.choices, ", ") + ")");
    case ParamType::Bool:
      if (value == "on" || value == "true" || value == "1") return "on";
      if (value == "off" || value == "false" || value == "0") return "off";
      return fail("expected on or off");
    case ParamType::Int:
    case ParamType::Real: {
      double v = 0;
      if (!parseNumber(value, v)) return fail("expected a finite number");
      if (p.type == ParamType::Int && v != std::floor(v)) return fail("expected a whole number");
      if (v < p.min || v > p.max) return fail("out of range (" + fmtNumber(p.min) + " to " + fmtNumber(p.max) + ")");
      return value;
    }
    case ParamType::Size: {
      if (value == "full") return value;
      const size_t x = value.find('x');
      double w = 0, h = 0;
      if (x == std::string::npos || !parseNumber(value.substr(0, x), w) || !parseNumber(value.substr(x + 1), h) ||
          w != std::floor(w) || h != std::floor(h))
        return fail("expected WIDTHxHEIGHT in whole pixels (e.g. 256x128) or full");
      if (w < p.min || w > p.max || h < p.min || h > p.max)
        return fail("out of range (each " + fmtNumber(p.min) + " to " + fmtNumber(p.max) + ")");
      return value;
    }
  }
  throw std::logic_error("checkedValue: unknown parameter type");
}

void checkDeclaration(const AlgorithmInfo& a) {
  if (a.name.empty() || !a.create)
    throw std::invalid_argument("registerAlgorithm: an algorithm needs a name and a create");
  for (const ParamSpec& p : a.params) {
    if (p.type == ParamType::Choice && p.choices.empty())
      throw std::invalid_argument("registerAlgorithm: " + a.name + "'s " + p.name + " has no choices");
    try {
      checkedValue(a, p, p.defaultValue);  // the default must be a value of its own
    } catch (const InputError& e) {
      throw std::invalid_argument("registerAlgorithm: " + a.name + "'s default: " + e.what());
    }
  }
  if (a.guarantee.kind == Guarantee::Kind::ExactWhen && !a.guarantee.holds)
    throw std::invalid_argument("registerAlgorithm: " + a.name + " is exact when ... but says not when");
  if (a.guarantee.kind == Guarantee::Kind::FailsByDesign && a.guarantee.failsOn.empty())
    throw std::invalid_argument("registerAlgorithm: " + a.name + " fails by design but names no scene");
}

}  // namespace

const char* paramTypeName(ParamType type) {
  switch (type) {
    case ParamType::Choice: return "choice";
    case ParamType::Int: return "int";
    case ParamType::Real: return "real";
    case ParamType::Bool: return "bool";
    case ParamType::Size: return "size";
  }
  return "?";
}

std::string Guarantee::describe() const {
  switch (kind) {
    case Kind::Exact: return "exact";
    case Kind::ExactWhen: return "exact when " + condition;
    case Kind::Approximate:
      return "approximate: " + condition + " (wrong pixels at most " + fmtNumber(100 * maxWrongFraction) +
             "% of those covered)";
    case Kind::FailsByDesign:
      return "fails by design on " + joined(failsOn, ", ") + (condition.empty() ? "" : " (" + condition + ")") +
             (exactWhen.empty() ? "" : "; exact when " + exactWhen);
  }
  return "?";
}

const std::string& AlgorithmParams::text(const std::string& name) const {
  for (const auto& [k, v] : entries_)
    if (k == name) return v;
  throw std::logic_error("AlgorithmParams: no parameter '" + name + "' declared");
}

int64_t AlgorithmParams::integer(const std::string& name) const { return int64_t(std::stod(text(name))); }
double AlgorithmParams::real(const std::string& name) const { return std::stod(text(name)); }
bool AlgorithmParams::flag(const std::string& name) const { return text(name) == "on"; }
std::pair<int64_t, int64_t> AlgorithmParams::size(const std::string& name) const {
  const std::string& value = text(name);
  if (value == "full") return {0, 0};
  const size_t x = value.find('x');
  return {int64_t(std::stod(value.substr(0, x))), int64_t(std::stod(value.substr(x + 1)))};
}

const std::deque<AlgorithmInfo>& algorithms() { return registry(); }

const AlgorithmInfo* findAlgorithm(const std::string& name) {
  for (const AlgorithmInfo& a : registry())
    if (a.name == name) return &a;
  return nullptr;
}

void registerAlgorithm(AlgorithmInfo info) {
  if (findAlgorithm(info.name)) throw std::invalid_argument("registerAlgorithm: '" + info.name + "' is taken");
  checkDeclaration(info);
  registry().push_back(std::move(info));
}

AlgorithmParams resolveParams(const AlgorithmInfo& algorithm, const std::map<std::string, std::string>& given) {
  for (const auto& [name, value] : given) {
    bool declared = false;
    for (const ParamSpec& p : algorithm.params) declared |= p.name == name;
    if (!declared) {
      std::vector<std::string> names, others;
      for (const ParamSpec& p : algorithm.params) names.push_back(p.name);
      for (const AlgorithmInfo& a : registry())  // where it lives instead (e.g. region: zbuffer-regions)
        for (const ParamSpec& p : a.params)
          if (p.name == name && a.name != algorithm.name) others.push_back(a.name);
      throw InputError(Setting::Param, name + "=" + value,
                       algorithm.name + " has no parameter '" + name + "' (" +
                           (names.empty() ? "it takes none" : "its parameters: " + joined(names, ", ")) +
                           (others.empty() ? "" : "; " + joined(others, ", ") + " take it") + ")");
    }
  }
  AlgorithmParams out;
  for (const ParamSpec& p : algorithm.params) {
    const auto it = given.find(p.name);
    out.entries_.emplace_back(p.name, checkedValue(algorithm, p, it == given.end() ? p.defaultValue : it->second));
  }
  return out;
}

}  // namespace hsr

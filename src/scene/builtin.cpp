// The registry of built-in scenes: their parameters (names, defaults, ranges), the parsing of
// "NAME?k=v&k=v" specs into checked arguments, and the shared helpers of the generators.
// Consumed by loadScene() ("builtin:..."), `hsr scenes` (builtinScenes()) and the tests.
#include <hsr/limits.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "scene/builtin_internal.hpp"

namespace hsr {
namespace builtin {
namespace {

// One declared parameter. Integers and reals carry an inclusive range; choices a list.
struct ParamDef {
  enum class Kind { Integer, Real, Choice };
  std::string name;
  std::string defaultValue;
  std::string help;
  Kind kind = Kind::Integer;
  int64_t intMin = 0, intMax = 0;
  double realMin = 0, realMax = 0;
  std::vector<std::string> choices;

  std::string expectation() const;  // "an integer in 1..50000000", for help and errors
};

ParamDef declare(std::string name, std::string def, std::string help, ParamDef::Kind kind) {
  ParamDef p;
  p.name = std::move(name);
  p.defaultValue = std::move(def);
  p.help = std::move(help);
  p.kind = kind;
  return p;
}
ParamDef integerParam(std::string name, int64_t def, int64_t lo, int64_t hi, std::string help) {
  ParamDef p =
      declare(std::move(name), std::to_string(def), std::move(help), ParamDef::Kind::Integer);
  p.intMin = lo;
  p.intMax = hi;
  return p;
}
ParamDef realParam(std::string name, std::string def, double lo, double hi, std::string help) {
  ParamDef p = declare(std::move(name), std::move(def), std::move(help), ParamDef::Kind::Real);
  p.realMin = lo;
  p.realMax = hi;
  return p;
}
ParamDef choiceParam(std::string name, std::vector<std::string> choices, std::string help) {
  ParamDef p = declare(std::move(name), choices.front(), std::move(help), ParamDef::Kind::Choice);
  p.choices = std::move(choices);
  return p;
}
ParamDef seedParam(std::string help = "random seed") {
  return integerParam("seed", 1, 0, std::numeric_limits<int64_t>::max(), std::move(help));
}

std::string joined(const std::vector<std::string>& items, const char* separator) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

// Shortest text that reads back as `v` ("0.001", "0.5", "1"), for ranges in messages.
std::string shortReal(double v) {
  char buffer[32];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, ec == std::errc() ? end : buffer);
}

std::string ParamDef::expectation() const {
  switch (kind) {
    case Kind::Integer:
      return "an integer in " + std::to_string(intMin) + ".." + std::to_string(intMax);
    case Kind::Real:
      return "a number in [" + shortReal(realMin) + ", " + shortReal(realMax) + "]";
    case Kind::Choice:
      return "one of " + joined(choices, ", ");
  }
  return {};
}

struct SceneDef {
  std::string name;
  std::string summary;
  std::vector<ParamDef> params;
  Scene (*generate)(const Args&);
  /// At least the triangles it generates, for the memory check before generating (none: a few).
  double (*triangles)(const Args&) = nullptr;
};

// Bytes a generated scene holds per triangle, finalized (positions, polygons, colours,
// triangulation, clusters), rounded up from `hsr info`'s peak resident size for random, city
// and clutter scenes of millions of triangles (about 115-120 bytes each).
constexpr double kSceneBytesPerTriangle = 128;

// The registry, in the order `hsr scenes` lists it. Ranges keep every scene below
// kMaxTriangles triangles.
const std::vector<SceneDef>& sceneDefs() {
  static const std::vector<SceneDef> defs = {
      {"cubes",
       "four cubes at different depths, partly occluding each other (KTH thesis, 24 quads)",
       {},
       makeCubes},
      {"random",
       "N random triangles of random orientation in a box, many intersecting (KTH report, KTH thesis)",
       {integerParam("n", 5000, 1, kMaxTriangles, "number of triangles"), seedParam(),
        realParam("size", "0.15", 0.001, 1,
                  "triangle circumradius as a fraction of the box height (box 2.67 x 2 x 2)")},
       makeRandom, [](const Args& a) { return double(a.integer("n")); }},
      {"sphere",
       "a geodesic sphere (subdivided icosahedron) of about N triangles",
       {integerParam("n", 1'000'000, 1, kMaxTriangles,
                     "target triangle count; the actual count is 20 k^2 nearest to it")},
       makeSphere, [](const Args& a) { return double(a.integer("n")); }},
      {"layers",
       "N screen-filling quads at evenly spaced depths (depth complexity N)",
       {integerParam("n", 64, 1, 100'000, "number of layers"),
        choiceParam("order", {"back-to-front", "front-to-back", "random"},
                    "submission (face) order of the layers"),
        seedParam("random seed of order=random")},
       makeLayers, [](const Args& a) { return 2.0 * double(a.integer("n")); }},
      {"city",
       "a city of box buildings seen from street level (heavy occlusion)",
       {integerParam("blocks", 30, 1, 1000, "the city is blocks x blocks blocks of 4 buildings"),
        seedParam()},
       makeCity, [](const Args& a) { return 48.0 * double(a.integer("blocks")) * double(a.integer("blocks")); }},
      {"clutter",
       "N rounded objects (stretched geodesic spheres) on a floor, seen at eye height (occlusion of curved meshes)",
       {integerParam("n", 400, 1, 5000, "number of objects"),
        integerParam("detail", 7, 1, 16, "each object has 20 detail^2 triangles"), seedParam()},
       makeClutter,
       [](const Args& a) { return 20.0 * double(a.integer("n")) * double(a.integer("detail") * a.integer("detail")); }},
      {"painter-midpoint",
       "a long tilted polygon in front of a square although its midpoint is behind (KTH report Fig. 2/3)",
       {},
       makePainterMidpoint},
      {"painter-cycle",
       "three bars overlapping cyclically, none intersecting (KTH report Fig. 4)",
       {},
       makePainterCycle},
      {"interpenetrate", "two quads passing through each other", {}, makeInterpenetrate},
      {"glass",
       "transparent polygons over an opaque floor: three bars overlapping cyclically and two quads through "
       "each other (opacity 0.5 to 0.7)",
       {},
       makeGlass},
      {"zfight",
       "two nearly coplanar polygons, far/near = 10^4: u16 depth fights, f32:reversed does not",
       {realParam("gap", "1e-4", 0, 0.5, "distance between the surfaces relative to eye depth")},
       makeZfight},
      {"csg",
       "closed solids and a CSG tree over them: a cube minus a sphere, a cube and a sphere intersected or "
       "united, or the rounded cube minus three crossed bars",
       {choiceParam("op", {"difference", "intersection", "union", "mixed"},
                    "the tree: cube - sphere, cube & sphere, cube | sphere, or (cube & sphere) - (three bars)"),
        integerParam("detail", 12, 1, 200, "each sphere has 20 detail^2 triangles")},
       makeCsg, [](const Args& a) { return 20.0 * double(a.integer("detail") * a.integer("detail")) + 36; }},
  };
  return defs;
}

// Parses `text` as a value of `def` or throws InputError prefixed with `where`.
Args::Value parseValue(const ParamDef& def, const std::string& text, const std::string& where) {
  const auto bad = [&] {
    return InputError(where + "bad value '" + text + "' for '" + def.name + "' (expected " +
                      def.expectation() + ")");
  };
  Args::Value value;
  value.text = text;
  const char* first = text.data();
  const char* last = first + text.size();
  switch (def.kind) {
    case ParamDef::Kind::Integer: {
      auto [end, ec] = std::from_chars(first, last, value.integer);
      if (text.empty() || ec != std::errc() || end != last || value.integer < def.intMin ||
          value.integer > def.intMax)
        throw bad();
      break;
    }
    case ParamDef::Kind::Real: {
      auto [end, ec] = std::from_chars(first, last, value.real);
      if (text.empty() || ec != std::errc() || end != last || !std::isfinite(value.real) ||
          value.real < def.realMin || value.real > def.realMax)
        throw bad();
      break;
    }
    case ParamDef::Kind::Choice:
      if (std::find(def.choices.begin(), def.choices.end(), text) == def.choices.end()) throw bad();
      break;
  }
  return value;
}

std::vector<std::string> names(const std::vector<ParamDef>& params) {
  std::vector<std::string> out;
  for (const auto& p : params) out.push_back(p.name);
  return out;
}

}  // namespace

const Args::Value& Args::at(std::string_view name) const {
  auto it = values.find(name);
  if (it == values.end())
    throw std::logic_error("builtin scene asked for undeclared parameter " + std::string(name));
  return it->second;
}

dvec3 Random::unitVector() {
  for (;;) {
    dvec3 p;  // one draw per statement: argument evaluation order is unspecified
    for (int axis = 0; axis < 3; ++axis) p[axis] = uniform(-1, 1);
    const double length2 = glm::dot(p, p);
    if (length2 > 1e-6 && length2 <= 1) return p / std::sqrt(length2);
  }
}

Rgba8 paletteColor(uint64_t index, double saturation, double value) {
  // Golden-ratio hue sequence (0.618... is the most irrational step: hues never cluster).
  const double turns = 0.13 + double(index) * 0.6180339887498949;
  const double hue = (turns - std::floor(turns)) * 6;  // exact fractional part
  const int sector = int(hue);
  const double f = hue - sector;
  const double p = value * (1 - saturation), q = value * (1 - saturation * f),
               t = value * (1 - saturation * (1 - f));
  double r = value, g = t, b = p;
  switch (sector) {
    case 1:
      r = q, g = value, b = p;
      break;
    case 2:
      r = p, g = value, b = t;
      break;
    case 3:
      r = p, g = q, b = value;
      break;
    case 4:
      r = t, g = p, b = value;
      break;
    case 5:
      r = value, g = p, b = q;
      break;
    default:
      break;
  }
  const auto byte = [](double c) { return uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255)); };
  return {byte(r), byte(g), byte(b), 255};
}

Rgba8 shade(Rgba8 color, double factor) {
  const auto scale = [&](uint8_t c) { return uint8_t(std::lround(c * factor)); };
  return {scale(color.r), scale(color.g), scale(color.b), color.a};
}

dmat3 rotationY(double c, double s) {
  // glm matrices are column-major: each dvec3 below is a column.
  return dmat3(dvec3(c, 0, -s), dvec3(0, 1, 0), dvec3(s, 0, c));
}
dmat3 rotationX(double c, double s) {
  return dmat3(dvec3(1, 0, 0), dvec3(0, c, s), dvec3(0, -s, c));
}

void addPolygon(Scene& scene, std::initializer_list<dvec3> corners, Rgba8 color) {
  uint32_t indices[8];
  if (corners.size() > 8) throw std::logic_error("addPolygon: more than 8 corners");
  uint32_t count = 0;
  for (const dvec3& corner : corners) {
    indices[count++] = uint32_t(scene.positions.size());
    scene.positions.push_back(corner);
  }
  scene.addFace(std::span<const uint32_t>(indices, count), color);
}

CameraSpec perspectiveCamera(const dvec3& eye, const dvec3& target, double fovyDeg, double near,
                             double far) {
  CameraSpec camera;
  camera.eye = eye;
  camera.target = target;
  camera.up = dvec3(0, 1, 0);
  camera.fovyDeg = fovyDeg;
  camera.near = near;
  camera.far = far;
  return camera;
}

}  // namespace builtin

const std::vector<BuiltinInfo>& builtinScenes() {
  static const std::vector<BuiltinInfo> infos = [] {
    std::vector<BuiltinInfo> out;
    for (const auto& def : builtin::sceneDefs()) {
      BuiltinInfo info{def.name, def.summary, {}};
      for (const auto& p : def.params)
        info.params.push_back({p.name, p.defaultValue, p.help + " (" + p.expectation() + ")"});
      out.push_back(std::move(info));
    }
    return out;
  }();
  return infos;
}

Scene makeBuiltin(const std::string& spec) {
  using namespace builtin;
  const size_t question = spec.find('?');
  const std::string name = spec.substr(0, question);
  const std::string where = "builtin:" + name + ": ";

  const auto& defs = sceneDefs();
  const auto def = std::find_if(defs.begin(), defs.end(), [&](auto& d) { return d.name == name; });
  if (def == defs.end()) {
    std::vector<std::string> known;
    for (const auto& d : defs) known.push_back(d.name);
    throw InputError(where + "unknown built-in scene (known: " + joined(known, ", ") + ")");
  }
  const auto findParam = [&](const std::string& key) {
    return std::find_if(def->params.begin(), def->params.end(),
                        [&](auto& p) { return p.name == key; });
  };

  // Given parameters: "k=v" items separated by '&'; empty items (a trailing '&') are ignored.
  Args args;
  if (question != std::string::npos) {
    const std::string query = spec.substr(question + 1);
    size_t begin = 0;
    while (begin <= query.size()) {
      size_t end = query.find('&', begin);
      if (end == std::string::npos) end = query.size();
      const std::string item = query.substr(begin, end - begin);
      begin = end + 1;
      if (item.empty()) continue;
      const size_t equals = item.find('=');
      const std::string key = item.substr(0, equals);
      const auto param = findParam(key);
      if (param == def->params.end()) {
        const std::string known = def->params.empty() ? std::string("this scene has none")
                                                      : joined(names(def->params), ", ");
        throw InputError(where + "unknown parameter '" + key + "' (known: " + known + ")");
      }
      if (equals == std::string::npos)
        throw InputError(where + "parameter '" + key + "' needs a value (" + key + "=...)");
      if (args.values.count(key)) throw InputError(where + "parameter '" + key + "' given twice");
      args.values[key] = parseValue(*param, item.substr(equals + 1), where);
    }
  }
  for (const auto& p : def->params)
    if (!args.values.count(p.name)) args.values[p.name] = parseValue(p, p.defaultValue, where);

  if (def->triangles) checkMemory(def->triangles(args) * kSceneBytesPerTriangle, "builtin:" + spec);
  Scene scene = def->generate(args);
  scene.source = "builtin:" + spec;
  scene.finalize();
  return scene;
}

}  // namespace hsr

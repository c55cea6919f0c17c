// Scene JSON: a list of meshes (files or built-in scenes), each placed by a transform and
// optionally recoloured, plus an optional camera and light. Produces an unfinalized Scene for
// loadScene() (load.cpp); the format is documented in docs/scene-json.md.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>

#include "core/json_util.hpp"
#include "scene/loaders.hpp"

namespace hsr::loaders {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Scene files may include scene files; a deeper nest is almost surely a mistake, and a bound
// keeps repeated inclusion from growing exponentially.
constexpr size_t kMaxNesting = 8;

/// Reads one mesh entry's fields, with errors "file: meshes[i].key: problem".
class EntryReader {
 public:
  EntryReader(const std::string& path, size_t index, const json& entry)
      : where_(path + ": meshes[" + std::to_string(index) + "]"), entry_(entry) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw InputError(at(key) + problem);
  }
  /// "file: meshes[i].key: "
  std::string at(const std::string& key) const { return where_ + (key.empty() ? "" : "." + key) + ": "; }

  bool has(const char* key) const { return entry_.contains(key); }

  std::string string(const char* key) const {
    const json& v = entry_.at(key);
    if (!v.is_string()) fail(key, "must be a string");
    return v.get<std::string>();
  }

  double number(const json& v, const char* key) const {
    if (!v.is_number()) fail(key, "must be a number");
    double d = v.get<double>();
    if (!std::isfinite(d)) fail(key, "must be finite");
    return d;
  }
  double number(const char* key) const { return number(entry_.at(key), key); }

  /// An array of `n` numbers.
  std::vector<double> numbers(const json& v, const char* key, size_t minCount, size_t maxCount) const {
    std::string count = minCount == maxCount ? std::to_string(minCount)
                                             : std::to_string(minCount) + " or " + std::to_string(maxCount);
    if (!v.is_array() || v.size() < minCount || v.size() > maxCount)
      fail(key, "must be an array of " + count + " numbers");
    std::vector<double> out;
    for (const json& x : v) out.push_back(number(x, key));
    return out;
  }
  dvec3 vec3(const char* key) const {
    std::vector<double> v = numbers(entry_.at(key), key, 3, 3);
    return {v[0], v[1], v[2]};
  }

  /// worldFromMesh: either "transform" (4x4 row-major, affine) or translate * rotate * scale.
  dmat4 transform() const {
    const bool trs = has("translate") || has("rotate_deg") || has("scale");
    if (has("transform")) {
      if (trs) fail("transform", "give either 'transform' or 'translate'/'rotate_deg'/'scale', not both");
      const json& rows = entry_.at("transform");
      if (!rows.is_array() || rows.size() != 4) fail("transform", "must be 4 rows of 4 numbers (row-major)");
      dmat4 m;
      for (int r = 0; r < 4; ++r) {
        std::vector<double> row = numbers(rows[size_t(r)], "transform", 4, 4);
        for (int c = 0; c < 4; ++c) m[c][r] = row[size_t(c)];
      }
      if (m[0][3] != 0 || m[1][3] != 0 || m[2][3] != 0 || m[3][3] != 1)
        fail("transform", "the last row must be [0, 0, 0, 1] (affine transforms only)");
      return m;
    }
    dmat4 m(1.0);
    if (has("translate")) m = glm::translate(m, vec3("translate"));
    if (has("rotate_deg")) {
      // Rotation about x first, then y, then z (world axes): R = Rz * Ry * Rx.
      dvec3 deg = vec3("rotate_deg");
      m = glm::rotate(m, glm::radians(deg.z), dvec3(0, 0, 1));
      m = glm::rotate(m, glm::radians(deg.y), dvec3(0, 1, 0));
      m = glm::rotate(m, glm::radians(deg.x), dvec3(1, 0, 0));
    }
    if (has("scale")) {
      const json& s = entry_.at("scale");
      m = glm::scale(m, s.is_array() ? vec3("scale") : dvec3(number("scale")));
    }
    return m;
  }

  /// "color": [r, g, b(, a)], all in [0, 1] or else all in [0, 255].
  Rgba8 color() const {
    std::vector<double> c = numbers(entry_.at("color"), "color", 3, 4);
    const bool unit = std::all_of(c.begin(), c.end(), [](double v) { return v <= 1.0; });
    for (double v : c)
      if (v < 0 || v > 255) fail("color", "components must be in [0, 1] or [0, 255]");
    auto channel = [&](size_t i) { return unitToByte(unit ? c[i] : c[i] / 255.0); };
    return Rgba8{channel(0), channel(1), channel(2), c.size() == 4 ? channel(3) : uint8_t(255)};
  }

  uint8_t opacity() const {
    double v = number("opacity");
    if (v < 0 || v > 1) fail("opacity", "must be in [0, 1]");
    return unitToByte(v);
  }

  void checkKeys() const {
    static constexpr std::string_view kKnown[] = {"file", "builtin", "name", "transform", "translate",
                                                  "rotate_deg", "scale", "color", "opacity"};
    if (!entry_.is_object()) fail("", "must be an object");
    for (const auto& item : entry_.items())
      if (std::find(std::begin(kKnown), std::end(kKnown), item.key()) == std::end(kKnown))
        fail("", "unknown key " + quote(item.key()));
    if (has("file") == has("builtin")) fail("", "needs exactly one of 'file' and 'builtin'");
  }

 private:
  std::string where_;
  const json& entry_;
};

/// Appends `sub` to `scene`: positions through worldFromMesh, faces in order, mesh ranges
/// renamed under `prefix` (when given), colours overridden where asked.
void append(Scene& scene, const Scene& sub, const dmat4& worldFromMesh, const std::string& prefix,
            const std::optional<Rgba8>& color, const std::optional<uint8_t>& alpha) {
  if (scene.positions.size() + sub.positions.size() > std::numeric_limits<uint32_t>::max())
    throw InputError(scene.source + ": more than 2^32 vertices");
  const uint32_t base = uint32_t(scene.positions.size());
  for (const dvec3& p : sub.positions) scene.positions.push_back(dvec3(worldFromMesh * dvec4(p, 1.0)));

  // Mesh ranges of the sub-scene (it is not finalized: faces before its first range get one).
  std::vector<MeshRange> ranges = sub.meshes;
  if (ranges.empty() || ranges.front().firstFace != 0)
    ranges.insert(ranges.begin(), MeshRange{fs::path(sub.source).stem().string(), 0, 0, {}, 0, 0, 0, 0, 0, 0});
  auto rangeName = [&](const MeshRange& r) {
    if (prefix.empty()) return r.name;
    return ranges.size() == 1 ? prefix : prefix + "/" + r.name;
  };

  std::vector<uint32_t> indices;
  size_t nextRange = 0;
  for (size_t f = 0; f < sub.faceCount(); ++f) {
    for (; nextRange < ranges.size() && ranges[nextRange].firstFace <= f; ++nextRange)
      scene.beginMesh(rangeName(ranges[nextRange]));
    indices.clear();
    for (uint32_t v : sub.face(f)) indices.push_back(base + v);
    Rgba8 c = color ? *color : sub.faceColors[f];
    if (alpha) c.a = *alpha;
    scene.addFace(indices, c);
  }
  scene.problems.notes.insert(scene.problems.notes.end(), sub.problems.notes.begin(), sub.problems.notes.end());
}

// The line (from 1) of the first key "name" in `text`, or 0 when it is not found.
size_t keyLine(std::string_view text, std::string_view name) {
  std::string quoted(1, '"');
  quoted.append(name).push_back('"');
  for (size_t at = text.find(quoted); at != std::string_view::npos; at = text.find(quoted, at + 1)) {
    size_t after = at + quoted.size();
    while (after < text.size() && std::isspace(static_cast<unsigned char>(text[after]))) ++after;
    if (after < text.size() && text[after] == ':') return 1 + size_t(std::count(text.begin(), text.begin() + long(at), '\n'));
  }
  return 0;
}

/// "light": {"direction": [x, y, z]} (the direction the light travels) or {"position": [x, y, z]},
/// with errors "file:line: light: problem".
Light readLight(const json& v, const std::string& path, std::string_view text) {
  const size_t line = keyLine(text, "light");
  std::string where = path;
  if (line) where.append(":").append(std::to_string(line));
  where.append(": light");
  auto fail = [&](const std::string& problem) -> Light { throw InputError(where + ": " + problem); };
  if (!v.is_object()) return fail("must be an object with 'direction' or 'position'");
  for (const auto& item : v.items())
    if (item.key() != "direction" && item.key() != "position")
      return fail("unknown key " + quote(item.key()) + " (expected 'direction' or 'position')");
  if (v.contains("direction") == v.contains("position")) return fail("needs exactly one of 'direction' and 'position'");
  const char* key = v.contains("direction") ? "direction" : "position";
  const json& a = v.at(key);
  if (!a.is_array() || a.size() != 3) return fail(std::string(key) + " must be an array of 3 numbers");
  Light light;
  light.kind = v.contains("direction") ? Light::Kind::Directional : Light::Kind::Point;
  for (size_t i = 0; i < 3; ++i) {
    if (!a[i].is_number()) return fail(std::string(key) + " must be an array of 3 numbers");
    light.vector[int(i)] = a[i].get<double>();
  }
  if (!std::isfinite(light.vector.x) || !std::isfinite(light.vector.y) || !std::isfinite(light.vector.z))
    return fail(std::string(key) + " must be finite");
  if (std::max({std::abs(light.vector.x), std::abs(light.vector.y), std::abs(light.vector.z)}) > 1e30)
    return fail(std::string(key) + " has a coordinate beyond 1e30 in magnitude");
  if (light.kind == Light::Kind::Directional && light.vector == dvec3(0.0))
    return fail("direction must not be zero (it is the direction the light travels)");
  return light;
}

// The faces of one mesh entry in the merged scene, and the name it was given.
struct EntryFaces {
  uint32_t first = 0, count = 0;
  std::string name;
};

// Scene JSON's "csg": a node is a mesh entry, by its index in "meshes" or its "name", or an object
// {"union" | "intersection" | "difference": [two or more nodes]} (a difference takes the rest from
// the first). Appended to Scene::csg in postfix order, root last; errors "file:line: csg: problem".
class CsgReader {
 public:
  CsgReader(const std::string& path, std::string_view text, const std::vector<EntryFaces>& entries, Scene& scene)
      : entries_(entries), scene_(scene), used_(entries.size(), false) {
    const size_t line = keyLine(text, "csg");
    where_ = path + (line ? ":" + std::to_string(line) : "") + ": csg: ";
  }

  void read(const json& root) { node(root, 0); }

 private:
  static constexpr int kMaxDepth = 64;

  [[noreturn]] void fail(const std::string& problem) const { throw InputError(where_ + problem); }

  uint32_t node(const json& v, int depth) {
    if (depth > kMaxDepth) fail("nested more than " + std::to_string(kMaxDepth) + " deep");
    if (v.is_number_integer() || v.is_number_unsigned() || v.is_string()) return solid(entryOf(v));
    if (!v.is_object() || v.size() != 1)
      fail("a node must be a mesh entry (its index or name) or an object with one key: 'union', 'intersection' "
           "or 'difference'");
    const auto item = v.items().begin();
    const std::string& op = item.key();
    CsgNode::Op kind;
    if (op == "union") kind = CsgNode::Op::Union;
    else if (op == "intersection") kind = CsgNode::Op::Intersection;
    else if (op == "difference") kind = CsgNode::Op::Difference;
    else fail("unknown operation " + quote(op) + " (expected 'union', 'intersection' or 'difference')");
    const json& operands = item.value();
    if (!operands.is_array() || operands.size() < 2) fail("'" + op + "' needs an array of two or more nodes");
    uint32_t acc = node(operands[0], depth + 1);
    if (kind == CsgNode::Op::Difference && operands.size() > 2) {  // first - (rest united)
      uint32_t rest = node(operands[1], depth + 1);
      for (size_t k = 2; k < operands.size(); ++k) rest = push({CsgNode::Op::Union, 0, 0, rest, node(operands[k], depth + 1)});
      return push({kind, 0, 0, acc, rest});
    }
    for (size_t k = 1; k < operands.size(); ++k) acc = push({kind, 0, 0, acc, node(operands[k], depth + 1)});
    return acc;
  }

  size_t entryOf(const json& v) const {
    if (v.is_string()) {
      const std::string name = v.get<std::string>();
      size_t found = entries_.size();
      for (size_t i = 0; i < entries_.size(); ++i)
        if (!name.empty() && entries_[i].name == name) {
          if (found != entries_.size()) fail("two mesh entries are named " + quote(name) + " (name it by index)");
          found = i;
        }
      if (found == entries_.size()) fail("no mesh entry is named " + quote(name));
      return found;
    }
    if (v.is_number_unsigned() && v.get<uint64_t>() < entries_.size()) return size_t(v.get<uint64_t>());
    fail("mesh index " + v.dump() + " is not one of meshes[0.." + std::to_string(entries_.size() - 1) + "]");
  }

  uint32_t solid(size_t entry) {
    if (used_[entry]) fail("meshes[" + std::to_string(entry) + "] is named twice (each mesh is one solid)");
    used_[entry] = true;
    if (entries_[entry].count == 0) fail("meshes[" + std::to_string(entry) + "] has no faces");
    if (++solids_ > kMaxCsgSolids) fail("more than " + std::to_string(kMaxCsgSolids) + " solids");
    return push({CsgNode::Op::Solid, entries_[entry].first, entries_[entry].count, 0, 0});
  }

  uint32_t push(const CsgNode& n) {
    scene_.csg.push_back(n);
    return uint32_t(scene_.csg.size() - 1);
  }

  const std::vector<EntryFaces>& entries_;
  Scene& scene_;
  std::vector<bool> used_;
  size_t solids_ = 0;
  std::string where_;
};

// The file's root object, checked: its keys, and a non-empty list of meshes.
json sceneRoot(const std::string& path, std::string_view bytes) {
  json root;
  try {
    root = parseJsonOrThrow(std::string(bytes), path);
  } catch (const json::out_of_range&) {  // a number too large for a double: no position given
    throw InputError(path + ": JSON number out of range");
  }
  if (!root.is_object()) throw InputError(path + ": a scene file must be a JSON object");
  for (const auto& item : root.items())
    if (item.key() != "meshes" && item.key() != "camera" && item.key() != "light" && item.key() != "csg")
      throw InputError(path + ": unknown key " + quote(item.key()) +
                       " (expected 'meshes', 'camera', 'light' and 'csg')");
  if (!root.contains("meshes") || !root.at("meshes").is_array() || root.at("meshes").empty())
    throw InputError(path + ": 'meshes' must be a non-empty array");
  return root;
}

}  // namespace

std::vector<double> sceneJsonEntryWeights(const std::string& path, std::string_view bytes) {
  const json root = sceneRoot(path, bytes);
  const fs::path folder = fs::path(path).parent_path();
  std::vector<double> weights;
  double fileBytes = 0;
  size_t files = 0;
  for (const json& entry : root.at("meshes")) {
    double w = -1;  // a built-in entry, weighed below
    if (entry.is_object() && entry.contains("file") && entry.at("file").is_string()) {
      const fs::path file = entry.at("file").get<std::string>();
      std::error_code ec;
      const auto size = fs::file_size(file.is_absolute() ? file : folder / file, ec);
      w = ec ? 0.0 : double(size);  // an unreadable file fails where it is loaded
      fileBytes += w;
      ++files;
    }
    weights.push_back(w);
  }
  const double builtinWeight = files && fileBytes > 0 ? fileBytes / double(files) : 1.0;
  for (double& w : weights)
    if (w < 0) w = builtinWeight;
  return weights;
}

Scene loadSceneJson(const std::string& path, std::string_view bytes, LoadContext& context, EntryRange entries) {
  std::error_code ec;
  std::string canonical = fs::weakly_canonical(path, ec).string();
  if (ec) canonical = path;
  if (std::find(context.openJsonFiles.begin(), context.openJsonFiles.end(), canonical) != context.openJsonFiles.end())
    throw InputError(path + ": the scene file includes itself");
  if (context.openJsonFiles.size() >= kMaxNesting)
    throw InputError(path + ": scene files nested more than " + std::to_string(kMaxNesting) + " deep");
  context.openJsonFiles.push_back(canonical);
  struct Pop {
    LoadContext& c;
    ~Pop() { c.openJsonFiles.pop_back(); }
  } pop{context};

  const json root = sceneRoot(path, bytes);
  Scene scene;
  scene.source = path;
  const fs::path folder = fs::path(path).parent_path();
  const json& meshes = root.at("meshes");
  const bool csg = root.contains("csg");
  if (csg && (entries.first > 0 || entries.end < meshes.size()))
    throw InputError(path + ": a 'csg' tree needs every mesh entry: the file cannot be loaded in shares");
  std::vector<EntryFaces> entryFaces;
  for (size_t i = entries.first; i < std::min(entries.end, meshes.size()); ++i) {
    EntryReader entry(path, i, meshes[i]);
    entry.checkKeys();
    const dmat4 worldFromMesh = entry.transform();
    std::optional<Rgba8> color;
    std::optional<uint8_t> alpha;
    if (entry.has("color")) color = entry.color();
    if (entry.has("opacity")) alpha = entry.opacity();
    std::string name = entry.has("name") ? entry.string("name") : "";

    Scene sub;
    if (entry.has("file")) {
      std::string file = entry.string("file");
      if (file.empty()) entry.fail("file", "is empty");
      sub = loadAny(fs::path(file).is_absolute() ? file : (folder / file).string(), context);
    } else {
      const std::string spec = "builtin:" + entry.string("builtin");
      try {
        sub = loadAny(spec, context);
      } catch (const InputError& e) {  // a built-in scene is no file: say where it was named
        if (e.setting() == Setting::MaxMemory)  // still keyed: each front end names its limit
          throw InputError(Setting::MaxMemory, entry.at("builtin") + e.subject(), e.detail());
        entry.fail("builtin", e.what());
      }
      sub.problems = {};  // generated finalized: the merged scene's finalize() redoes its findings
    }
    const uint32_t firstFace = uint32_t(scene.faceCount());
    append(scene, sub, worldFromMesh, name, color, alpha);
    entryFaces.push_back({firstFace, uint32_t(scene.faceCount()) - firstFace, name});
  }
  if (csg) CsgReader(path, bytes, entryFaces, scene).read(root.at("csg"));

  if (root.contains("camera")) {
    if (!root.at("camera").is_object()) throw InputError(path + ": 'camera' must be an object");
    scene.camera = parseCameraJson(root.at("camera").dump(), path);
  }
  if (root.contains("light")) scene.light = readLight(root.at("light"), path, bytes);
  return scene;
}

}  // namespace hsr::loaders

// Wavefront OBJ loader (with its MTL material libraries): positions in double, faces in file
// order, colours from vertex colours or materials. Produces an unfinalized Scene for
// loadScene() (load.cpp); formats and colour rules are described in docs/loaders.md.
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <unordered_map>

#include "scene/loaders.hpp"

namespace hsr::loaders {
namespace {

namespace fs = std::filesystem;

/// Reads the materials of an MTL file: diffuse colour Kd and opacity (d, or 1 - Tr when there
/// is no d). Later definitions of a name replace earlier ones.
void readMtl(const std::string& path, std::string_view text, std::unordered_map<std::string, Rgba8>& materials) {
  struct Entry {
    dvec3 diffuse = dvec3(kDefaultColor.r, kDefaultColor.g, kDefaultColor.b) / 255.0;
    std::optional<double> dissolve, transparency;
  };
  std::vector<std::pair<std::string, Entry>> entries;
  TextScanner sc(text, path, /*hashComments=*/true, /*lineContinuation=*/true);
  do {
    std::string_view keyword = sc.token();
    if (keyword == "newmtl") {
      std::string name(sc.restOfLine());
      if (name.empty()) sc.fail("newmtl without a name");
      entries.emplace_back(std::move(name), Entry{});
    } else if (entries.empty()) {
      continue;  // statements before the first newmtl have no material to apply to
    } else if (keyword == "Kd") {
      // "Kd r [g b]"; the spectral and CIE XYZ forms are left at the default colour.
      std::string_view first = sc.token();
      if (first == "spectral" || first == "xyz") continue;
      double rgb[3];
      if (!parseDouble(first, rgb[0])) sc.fail("bad Kd value " + quote(first) + " (not a finite number)");
      std::string_view more = sc.token();
      if (more.empty()) {
        rgb[1] = rgb[2] = rgb[0];
      } else {
        if (!parseDouble(more, rgb[1])) sc.fail("bad Kd value " + quote(more) + " (not a finite number)");
        rgb[2] = sc.number("Kd blue value");
      }
      entries.back().second.diffuse = {rgb[0], rgb[1], rgb[2]};
    } else if (keyword == "d") {
      std::string_view tok = sc.token();
      if (tok == "-halo") tok = sc.token();
      double d;
      if (!parseDouble(tok, d)) sc.fail("bad d (opacity) value " + quote(tok));
      entries.back().second.dissolve = d;
    } else if (keyword == "Tr") {
      entries.back().second.transparency = sc.number("Tr (transparency) value");
    }
  } while (sc.nextLine());

  for (auto& [name, e] : entries) {
    double opacity = e.dissolve ? *e.dissolve : e.transparency ? 1.0 - *e.transparency : 1.0;
    materials[name] = Rgba8{unitToByte(e.diffuse.r), unitToByte(e.diffuse.g), unitToByte(e.diffuse.b),
                            unitToByte(opacity)};
  }
}

class ObjReader {
 public:
  ObjReader(const std::string& path, std::string_view text)
      : path_(path), sc_(text, path, /*hashComments=*/true, /*lineContinuation=*/true) {
    scene_.source = path;
  }

  Scene run() {
    do {
      std::string_view keyword = sc_.token();
      if (keyword == "v") vertex();
      else if (keyword == "f") face();
      else if (keyword == "o" || keyword == "g") meshName(keyword);
      else if (keyword == "usemtl") useMaterial();
      else if (keyword == "mtllib") materialLibrary();
      else if (keyword == "l" || keyword == "p") ++skippedPrimitives_;
      // Anything else (vt, vn, s, free-form geometry, ...) does not affect visibility.
    } while (sc_.nextLine());

    if (maxIndex_ && *maxIndex_ >= scene_.positions.size())
      throw InputError(path_ + ":" + std::to_string(maxIndexLine_) + ": vertex index " +
                       std::to_string(*maxIndex_ + 1) + " out of range (the file has " +
                       std::to_string(scene_.positions.size()) + " vertices)");
    if (skippedPrimitives_)
      scene_.problems.notes.push_back(path_ + ": " + std::to_string(skippedPrimitives_) +
                                      " line/point statements ignored (only faces are drawn)");
    assignColors();
    return std::move(scene_);
  }

 private:
  // "v x y z", "v x y z w" (w ignored) or "v x y z r g b [a]" (colour channels in [0, 1]).
  void vertex() {
    if (scene_.positions.size() >= std::numeric_limits<uint32_t>::max()) sc_.fail("more than 2^32 vertices");
    dvec3 p;
    p.x = sc_.number("x coordinate");
    p.y = sc_.number("y coordinate");
    p.z = sc_.number("z coordinate");
    double extra[4];
    int n = 0;
    for (std::string_view tok = sc_.token(); !tok.empty(); tok = sc_.token()) {
      if (n == 4) sc_.fail("too many numbers after 'v' (expected x y z [w] or x y z r g b)");
      if (!parseDouble(tok, extra[n++])) sc_.fail("bad vertex value " + quote(tok) + " (not a finite number)");
    }
    if (n == 2) sc_.fail("expected x y z [w] or x y z r g b after 'v', found 5 numbers");
    if (const char* huge = hugeCoordinate(p))
      sc_.fail("vertex " + std::to_string(scene_.positions.size() + 1) + " has " + huge);
    scene_.positions.push_back(p);
    if (n >= 3) {
      // The first coloured vertex starts the colour array; earlier vertices have no colour.
      if (vertexColors_.empty()) vertexColors_.resize(scene_.positions.size() - 1, kNoColor);
      vertexColors_.push_back({float(extra[0]), float(extra[1]), float(extra[2])});
    } else if (!vertexColors_.empty()) {
      vertexColors_.push_back(kNoColor);
    }
  }

  // "f v1 v2 v3 ...", each vertex "v", "v/vt", "v//vn" or "v/vt/vn"; negative indices count back
  // from the last vertex read. Only the position index matters here.
  void face() {
    indices_.clear();
    const long long count = (long long)scene_.positions.size();
    for (std::string_view tok = sc_.token(); !tok.empty(); tok = sc_.token()) {
      long long i;
      if (!parseInt(tok.substr(0, tok.find('/')), i)) sc_.fail("bad face vertex " + quote(tok));
      if (i == 0) sc_.fail("vertex index 0 (OBJ indices start at 1)");
      long long index = i > 0 ? i - 1 : count + i;
      if (index < 0)
        sc_.fail("relative vertex index " + std::to_string(i) + " refers before the first vertex (" +
                 std::to_string(count) + " read so far)");
      if (index >= (long long)std::numeric_limits<uint32_t>::max())
        sc_.fail("vertex index " + std::to_string(i) + " out of range");
      // Vertices may legally follow the faces that use them: check forward references at the end.
      if (index >= count && (!maxIndex_ || uint64_t(index) > *maxIndex_)) {
        maxIndex_ = uint64_t(index);
        maxIndexLine_ = sc_.line();
      }
      indices_.push_back(uint32_t(index));
    }
    if (indices_.size() < 3)
      sc_.fail("a face needs at least 3 vertices, found " + std::to_string(indices_.size()));
    if (pendingMesh_) {
      scene_.beginMesh(std::move(*pendingMesh_));
      pendingMesh_.reset();
    }
    scene_.addFace(indices_, kDefaultColor);
    faceMaterial_.push_back(currentMaterial_);
  }

  // "o name" / "g name ...": the next face starts a new mesh range (none if no face follows).
  void meshName(std::string_view keyword) {
    std::string_view name = sc_.restOfLine();
    pendingMesh_ = std::string(name.empty() ? (keyword == "o" ? "object" : "default") : name);
  }

  void useMaterial() {
    std::string name(sc_.restOfLine());
    auto [it, added] = materialSlot_.try_emplace(name, int(materialNames_.size()));
    if (added) materialNames_.push_back(name);
    currentMaterial_ = it->second;
  }

  // "mtllib a.mtl [b.mtl ...]", relative to the OBJ file's folder. A file name may contain
  // spaces, so the whole rest of the line is tried first.
  void materialLibrary() {
    std::string_view rest = sc_.restOfLine();
    const fs::path folder = fs::path(path_).parent_path();
    std::vector<std::string> names;
    std::error_code ec;
    if (fs::is_regular_file(folder / std::string(rest), ec)) {
      names.emplace_back(rest);
    } else {
      TextScanner words(rest, path_, false, false);
      for (std::string_view w = words.token(); !w.empty(); w = words.token()) names.emplace_back(w);
    }
    for (const std::string& name : names) {
      if (!seenLibraries_.insert(name).second) continue;
      std::string file = (folder / name).string();
      if (!fs::is_regular_file(file, ec)) {
        scene_.problems.notes.push_back(path_ + ":" + std::to_string(sc_.line()) + ": material library " +
                                        quote(name) + " not found; its materials use the default grey");
        continue;
      }
      anyLibraryRead_ = true;
      if (fs::file_size(file, ec) == 0) continue;  // an empty library defines nothing
      readMtl(file, skipBom(readFile(file)), materials_);
    }
  }

  // Face colours, now that every vertex and material library is known: the average of the
  // face's vertex colours when all its vertices have one, else the material's diffuse colour,
  // else the default grey. Opacity always comes from the material.
  void assignColors() {
    std::vector<Rgba8> slotColor(materialNames_.size(), kDefaultColor);
    for (size_t s = 0; s < materialNames_.size(); ++s) {
      auto it = materials_.find(materialNames_[s]);
      if (it != materials_.end()) slotColor[s] = it->second;
      else if (anyLibraryRead_)
        scene_.problems.notes.push_back(path_ + ": material " + quote(materialNames_[s]) +
                                        " is not defined; its faces use the default grey");
    }
    for (size_t f = 0; f < scene_.faceCount(); ++f) {
      Rgba8 color = faceMaterial_[f] >= 0 ? slotColor[size_t(faceMaterial_[f])] : kDefaultColor;
      if (!vertexColors_.empty()) {
        glm::vec3 sum(0.0f);
        bool all = true;
        for (uint32_t v : scene_.face(f)) {
          all = all && vertexColors_[v].r >= 0;
          sum += vertexColors_[v];
        }
        if (all) {
          sum /= float(scene_.face(f).size());
          color = Rgba8{unitToByte(sum.r), unitToByte(sum.g), unitToByte(sum.b), color.a};
        }
      }
      scene_.faceColors[f] = color;
    }
  }

  static constexpr glm::vec3 kNoColor{-1.0f, -1.0f, -1.0f};

  std::string path_;
  TextScanner sc_;
  Scene scene_;
  std::vector<uint32_t> indices_;               // scratch for one face
  std::optional<uint64_t> maxIndex_;            // largest forward-referenced vertex index
  size_t maxIndexLine_ = 0;
  std::optional<std::string> pendingMesh_;
  std::vector<glm::vec3> vertexColors_;         // empty until a vertex has a colour
  std::vector<int> faceMaterial_;               // material slot per face, -1 none
  int currentMaterial_ = -1;
  std::unordered_map<std::string, int> materialSlot_;
  std::vector<std::string> materialNames_;
  std::unordered_map<std::string, Rgba8> materials_;
  std::set<std::string> seenLibraries_;
  bool anyLibraryRead_ = false;
  uint64_t skippedPrimitives_ = 0;
};

}  // namespace

Scene loadObj(const std::string& path, std::string_view bytes) { return ObjReader(path, bytes).run(); }

}  // namespace hsr::loaders

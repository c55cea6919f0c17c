// Stanford PLY loader (ascii, binary little and big endian): vertex positions in double, faces
// in file order, face or vertex colours; other elements skipped. Produces an unfinalized Scene
// for loadScene() (load.cpp); behaviour documented in docs/loaders.md.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

#include "scene/loaders.hpp"

namespace hsr::loaders {
namespace {

enum class PlyType : uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
enum class PlyFormat : uint8_t { Ascii, BinaryLittleEndian, BinaryBigEndian };

size_t typeSize(PlyType t) {
  static constexpr size_t kSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSize[int(t)];
}
bool isFloat(PlyType t) { return t == PlyType::Float32 || t == PlyType::Float64; }

std::optional<PlyType> parseType(std::string_view name) {
  static constexpr std::pair<std::string_view, PlyType> kNames[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},     {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},   {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16}, {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},   {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (auto& [n, t] : kNames)
    if (n == name) return t;
  return std::nullopt;
}

struct PlyProperty {
  std::string name;
  PlyType type;               // the value type, or a list's item type
  bool isList = false;
  PlyType countType = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> props;

  int find(std::initializer_list<std::string_view> names) const {
    for (size_t i = 0; i < props.size(); ++i)
      for (std::string_view n : names)
        if (props[i].name == n) return int(i);
    return -1;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  size_t bodyOffset = 0;  // first byte after end_header's line
  size_t bodyLine = 1;    // its line number (ascii)
  // Lines of no PLY keyword ("Created by ...", as some exporters write): skipped, as assimp does.
  size_t unknownLines = 0, firstUnknownLine = 0;
  std::string firstUnknown;
};

PlyHeader readHeader(const std::string& path, std::string_view bytes) {
  TextScanner sc(bytes, path, /*hashComments=*/false, /*lineContinuation=*/false);
  if (sc.token() != "ply") sc.fail("not a PLY file (the first line must be 'ply')");
  sc.expectLineEnd("'ply'");
  PlyHeader h;
  bool haveFormat = false;
  while (true) {
    if (!sc.nextLine()) sc.fail("the header has no 'end_header' line");
    std::string_view keyword = sc.token();
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      sc.expectLineEnd("'end_header'");
      h.bodyLine = sc.line() + 1;
      sc.nextLine();
      h.bodyOffset = sc.offset();
      break;
    }
    if (keyword == "format") {
      std::string_view format = sc.token();
      if (format == "ascii") h.format = PlyFormat::Ascii;
      else if (format == "binary_little_endian") h.format = PlyFormat::BinaryLittleEndian;
      else if (format == "binary_big_endian") h.format = PlyFormat::BinaryBigEndian;
      else sc.fail("unknown PLY format " + quote(format));
      if (sc.token() != "1.0") sc.fail("unsupported PLY version (expected 1.0)");
      haveFormat = true;
    } else if (keyword == "element") {
      PlyElement e;
      e.name = std::string(sc.token());
      if (e.name.empty()) sc.fail("element without a name");
      long long count = sc.integer("element count");
      if (count < 0) sc.fail("negative element count " + std::to_string(count));
      e.count = uint64_t(count);
      for (const PlyElement& other : h.elements)
        if (other.name == e.name) sc.fail("element " + quote(e.name) + " declared twice");
      h.elements.push_back(std::move(e));
    } else if (keyword == "property") {
      if (h.elements.empty()) sc.fail("property before any element");
      PlyProperty p;
      std::string_view type = sc.token();
      if (type == "list") {
        std::string_view countType = sc.token(), itemType = sc.token();
        auto c = parseType(countType), t = parseType(itemType);
        if (!c || isFloat(*c)) sc.fail("bad list count type " + quote(countType));
        if (!t) sc.fail("unknown property type " + quote(itemType));
        p.isList = true;
        p.countType = *c;
        p.type = *t;
      } else {
        auto t = parseType(type);
        if (!t) sc.fail("unknown property type " + quote(type));
        p.type = *t;
      }
      p.name = std::string(sc.token());
      if (p.name.empty()) sc.fail("property without a name");
      h.elements.back().props.push_back(std::move(p));
    } else {
      if (h.unknownLines++ == 0) {
        h.firstUnknownLine = sc.line();
        h.firstUnknown = quote(keyword);
      }
      sc.restOfLine();
      continue;
    }
    sc.expectLineEnd(("'" + std::string(keyword) + "' line").c_str());
  }
  if (!haveFormat) throw InputError(path + ": the PLY header has no 'format' line");
  return h;
}

/// Checks the header's counts against the bytes that follow it, so that a lying header gives
/// a clear error instead of a huge allocation or a long loop.
void checkCounts(const std::string& path, const PlyHeader& h, size_t bodyBytes) {
  uint64_t left = bodyBytes;
  for (const PlyElement& e : h.elements) {
    if (e.props.empty() || e.count == 0) continue;
    // Binary: each row takes at least its scalar sizes and list counts. Ascii: each property
    // is at least one character and a separator (the last one may lack the separator).
    uint64_t rowMin = 0;
    for (const PlyProperty& p : e.props)
      rowMin += h.format == PlyFormat::Ascii ? 2 : typeSize(p.isList ? p.countType : p.type);
    uint64_t available = h.format == PlyFormat::Ascii ? left + 1 : left;
    if (e.count > available / rowMin)
      throw InputError(path + ": the header declares " + std::to_string(e.count) + " " + quote(e.name) +
                       " elements, more than the " + std::to_string(bodyBytes) +
                       " bytes after the header can hold");
    left = available - e.count * rowMin;
  }
}

/// Binary body: values read at a moving byte offset.
class BinarySource {
 public:
  BinarySource(const std::string& path, std::string_view bytes, size_t offset, bool bigEndian)
      : path_(path), bytes_(bytes), pos_(offset), swap_(bigEndian) {}

  double read(PlyType t) {
    size_t n = typeSize(t);
    if (bytes_.size() - pos_ < n) fail("unexpected end of file (truncated)");
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, n);
    if (swap_) std::reverse(b, b + n);
    pos_ += n;
    switch (t) {
      case PlyType::Int8: return double(int8_t(b[0]));
      case PlyType::UInt8: return double(b[0]);
      case PlyType::Int16: return double(load<int16_t>(b));
      case PlyType::UInt16: return double(load<uint16_t>(b));
      case PlyType::Int32: return double(load<int32_t>(b));
      case PlyType::UInt32: return double(load<uint32_t>(b));
      case PlyType::Float32: return double(load<float>(b));
      case PlyType::Float64: return load<double>(b);
    }
    return 0;
  }
  /// Skips `count` items of type t.
  void skip(uint64_t count, PlyType t) {
    if (count > (bytes_.size() - pos_) / typeSize(t)) fail("unexpected end of file (truncated)");
    pos_ += size_t(count * typeSize(t));
  }
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(path_ + ": " + problem + " (byte offset " + std::to_string(pos_) + ")");
  }

 private:
  template <class T>
  static T load(const unsigned char* b) {
    T v;
    std::memcpy(&v, b, sizeof v);
    return v;
  }
  const std::string& path_;
  std::string_view bytes_;
  size_t pos_;
  bool swap_;
};

/// Ascii body: whitespace-separated values, errors with line numbers.
class AsciiSource {
 public:
  AsciiSource(const std::string& path, std::string_view bytes, size_t offset, size_t firstLine)
      : sc_(bytes.substr(offset), path, false, false, firstLine) {}

  double read(PlyType t) {
    std::string_view tok = sc_.anyToken();
    if (tok.empty()) fail("unexpected end of file (truncated)");
    double v;
    if (!parseDouble(tok, v)) fail("bad value " + quote(tok) + " (not a finite number)");
    if (!isFloat(t) && v != std::floor(v)) fail("bad value " + quote(tok) + " (expected an integer)");
    return v;
  }
  void skip(uint64_t count, PlyType t) {
    for (uint64_t i = 0; i < count; ++i) read(t);
  }
  [[noreturn]] void fail(const std::string& problem) const { sc_.fail(problem); }

 private:
  TextScanner sc_;
};

/// A colour channel in 0..255: floats are in [0, 1], 16-bit integers in [0, 65535], other
/// integers in [0, 255].
uint8_t channel(double v, PlyType t) {
  if (isFloat(t)) return unitToByte(v);
  if (t == PlyType::Int16 || t == PlyType::UInt16) v /= 257.0;
  return uint8_t(std::lround(std::clamp(v, 0.0, 255.0)));
}

struct ColorProps {
  int r = -1, g = -1, b = -1, a = -1;
  explicit ColorProps(const PlyElement& e)
      : r(e.find({"red", "diffuse_red", "r"})), g(e.find({"green", "diffuse_green", "g"})),
        b(e.find({"blue", "diffuse_blue", "b"})), a(e.find({"alpha", "diffuse_alpha", "a"})) {}
  bool present() const { return r >= 0 && g >= 0 && b >= 0; }
  Rgba8 color(const PlyElement& e, const std::vector<double>& v) const {
    return Rgba8{channel(v[size_t(r)], e.props[size_t(r)].type), channel(v[size_t(g)], e.props[size_t(g)].type),
                 channel(v[size_t(b)], e.props[size_t(b)].type),
                 a >= 0 ? channel(v[size_t(a)], e.props[size_t(a)].type) : uint8_t(255)};
  }
};

template <class Source>
class PlyBodyReader {
 public:
  PlyBodyReader(const std::string& path, const PlyHeader& h, Source& src, Scene& scene)
      : path_(path), h_(h), src_(src), scene_(scene) {}

  void run() {
    const PlyElement* vertex = nullptr;
    for (const PlyElement& e : h_.elements)
      if (e.name == "vertex") vertex = &e;
    if (!vertex) throw InputError(path_ + ": the PLY header declares no 'vertex' element");
    if (vertex->count > std::numeric_limits<uint32_t>::max())
      throw InputError(path_ + ": more than 2^32 vertices");
    vertexCount_ = vertex->count;

    bool faceColors = false;
    for (const PlyElement& e : h_.elements) {
      if (e.props.empty()) continue;  // nothing to read, however large the count
      if (e.name == "vertex") readVertices(e);
      else if (e.name == "face") faceColors = readFaces(e);
      else skipElement(e);
    }
    if (!faceColors && !vertexColors_.empty()) averageVertexColors(scene_, vertexColors_);
  }

 private:
  /// Reads one row: scalar values into values_ (lists are read through `onList`).
  template <class OnList>
  void readRow(const PlyElement& e, OnList&& onList) {
    values_.resize(e.props.size());
    for (size_t k = 0; k < e.props.size(); ++k) {
      const PlyProperty& p = e.props[k];
      if (!p.isList) {
        values_[k] = src_.read(p.type);
        continue;
      }
      double n = src_.read(p.countType);
      if (n < 0 || n > double(std::numeric_limits<uint32_t>::max()))
        src_.fail("bad list length " + numberText(n) + " in " + quote(e.name) + " " + std::to_string(row_));
      onList(k, uint64_t(n));
    }
  }

  void readVertices(const PlyElement& e) {
    const int x = e.find({"x"}), y = e.find({"y"}), z = e.find({"z"});
    if (x < 0 || y < 0 || z < 0) throw InputError(path_ + ": the 'vertex' element lacks an x, y or z property");
    for (int k : {x, y, z})
      if (e.props[size_t(k)].isList) throw InputError(path_ + ": vertex coordinates must not be lists");
    const ColorProps color(e);
    scene_.positions.reserve(size_t(e.count));
    for (row_ = 0; row_ < e.count; ++row_) {
      readRow(e, [&](size_t k, uint64_t n) { src_.skip(n, e.props[k].type); });
      dvec3 p{values_[size_t(x)], values_[size_t(y)], values_[size_t(z)]};
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        src_.fail("vertex " + std::to_string(row_) + " has a non-finite coordinate");
      if (const char* huge = hugeCoordinate(p)) src_.fail("vertex " + std::to_string(row_) + " has " + huge);
      scene_.positions.push_back(p);
      if (color.present()) vertexColors_.push_back(color.color(e, values_));
    }
  }

  /// Reads the faces; returns whether they carry their own colours.
  bool readFaces(const PlyElement& e) {
    const int list = e.find({"vertex_indices", "vertex_index"});
    if (list < 0 || !e.props[size_t(list)].isList)
      throw InputError(path_ + ": the 'face' element has no 'vertex_indices' list");
    const ColorProps color(e);
    const PlyType itemType = e.props[size_t(list)].type;
    for (row_ = 0; row_ < e.count; ++row_) {
      indices_.clear();
      readRow(e, [&](size_t k, uint64_t n) {
        if (int(k) != list) return src_.skip(n, e.props[k].type);
        if (n < 3) src_.fail("face " + std::to_string(row_) + " has " + std::to_string(n) + " vertices (at least 3 needed)");
        for (uint64_t j = 0; j < n; ++j) {
          double v = src_.read(itemType);
          if (!(v >= 0 && v < double(vertexCount_)) || v != std::floor(v))
            src_.fail("face " + std::to_string(row_) + ": vertex index " + numberText(v) +
                      " out of range (" + std::to_string(vertexCount_) + " vertices)");
          indices_.push_back(uint32_t(v));
        }
      });
      scene_.addFace(indices_, color.present() ? color.color(e, values_) : kDefaultColor);
    }
    return color.present();
  }

  void skipElement(const PlyElement& e) {
    for (row_ = 0; row_ < e.count; ++row_) readRow(e, [&](size_t k, uint64_t n) { src_.skip(n, e.props[k].type); });
  }

  const std::string& path_;
  const PlyHeader& h_;
  Source& src_;
  Scene& scene_;
  uint64_t vertexCount_ = 0;
  uint64_t row_ = 0;                 // row being read, for messages
  std::vector<double> values_;       // scalar property values of the current row
  std::vector<uint32_t> indices_;    // the current face
  std::vector<Rgba8> vertexColors_;  // empty when the vertices have no colour
};

}  // namespace

Scene loadPly(const std::string& path, std::string_view bytes) {
  PlyHeader header = readHeader(path, bytes);
  checkCounts(path, header, bytes.size() - header.bodyOffset);
  Scene scene;
  scene.source = path;
  if (header.unknownLines)
    scene.problems.notes.push_back(path + ":" + std::to_string(header.firstUnknownLine) + ": " +
                                   std::to_string(header.unknownLines) + " header line(s) of no PLY keyword skipped (the first " +
                                   header.firstUnknown + ")");
  if (header.format == PlyFormat::Ascii) {
    AsciiSource src(path, bytes, header.bodyOffset, header.bodyLine);
    PlyBodyReader<AsciiSource>(path, header, src, scene).run();
  } else {
    BinarySource src(path, bytes, header.bodyOffset, header.format == PlyFormat::BinaryBigEndian);
    PlyBodyReader<BinarySource>(path, header, src, scene).run();
  }
  return scene;
}

}  // namespace hsr::loaders

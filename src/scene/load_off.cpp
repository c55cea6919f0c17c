// Geomview OFF loader (OFF, COFF, NOFF, CNOFF, STOFF, ...; ASCII only): positions in double,
// faces in file order, face or vertex colours. Produces an unfinalized Scene for loadScene()
// (load.cpp); behaviour documented in docs/loaders.md.
#include <limits>

#include "scene/loaders.hpp"

namespace hsr::loaders {
namespace {

/// What the header keyword says each vertex line carries after x y z.
struct OffLayout {
  bool textureCoords = false;  // ST: s t at the end
  bool colors = false;         // C: r g b [a]
  bool normals = false;        // N: nx ny nz right after the position
};

/// Parses "[ST][C][N]OFF"; the 4D and n-dimensional variants are refused.
bool parseKeyword(std::string_view word, OffLayout& layout) {
  if (word.starts_with("ST")) {
    layout.textureCoords = true;
    word.remove_prefix(2);
  }
  if (word.starts_with("C")) {
    layout.colors = true;
    word.remove_prefix(1);
  }
  if (word.starts_with("N")) {
    layout.normals = true;
    word.remove_prefix(1);
  }
  return word == "OFF";
}

class OffReader {
 public:
  OffReader(const std::string& path, std::string_view text)
      : path_(path), sc_(text, path, /*hashComments=*/true, /*lineContinuation=*/false) {
    scene_.source = path;
  }

  Scene run() {
    // Header: the keyword, then the counts "vertices faces [edges]" on the same line or the
    // next line that has any.
    std::string_view keyword = sc_.anyToken();
    if (keyword.empty()) sc_.fail("no OFF header (the file holds only comments or blanks)");
    OffLayout layout;
    if (!parseKeyword(keyword, layout))
      sc_.fail(keyword.find("OFF") != std::string_view::npos
                   ? "unsupported OFF variant " + quote(keyword) + " (OFF, COFF, NOFF, CNOFF, STOFF are read)"
                   : "not an OFF file (expected 'OFF', found " + quote(keyword) + ")");
    std::string_view first = sc_.token();
    if (first == "BINARY") sc_.fail("binary OFF is not supported");
    if (first.empty()) first = nextContentLine();
    if (first.empty()) sc_.fail("the file ends before the vertex and face counts");
    long long vertexCount, faceCount;
    if (!parseInt(first, vertexCount) || vertexCount < 0) sc_.fail("bad vertex count " + quote(first));
    faceCount = sc_.integer("face count");
    if (faceCount < 0) sc_.fail("bad face count " + std::to_string(faceCount));
    if (std::string_view edges = sc_.token(); !edges.empty()) {
      long long e;
      if (!parseInt(edges, e)) sc_.fail("bad edge count " + quote(edges));
    }
    sc_.expectLineEnd("the counts");
    if (uint64_t(vertexCount) > std::numeric_limits<uint32_t>::max()) sc_.fail("more than 2^32 vertices");

    // The counts are not trusted for allocation: the arrays grow as lines are read, so a
    // lying header ends in a "file ends early" error, not a huge reservation.
    for (long long v = 0; v < vertexCount; ++v) vertex(layout, v, vertexCount);
    for (long long f = 0; f < faceCount; ++f) face(f, faceCount);
    if (!vertexColors_.empty() && !anyFaceColor_) averageVertexColors(scene_, vertexColors_);
    return std::move(scene_);
  }

 private:
  /// Moves to the next line that has a token and returns it; empty at the end of the file.
  std::string_view nextContentLine() {
    while (sc_.nextLine()) {
      std::string_view tok = sc_.token();
      if (!tok.empty()) return tok;
    }
    return {};
  }

  [[noreturn]] void endsEarly(const char* what, long long index, long long count) const {
    sc_.fail("the file ends at " + std::string(what) + " " + std::to_string(index) + " of " + std::to_string(count) +
             " declared in the header");
  }

  /// Reads the rest of the line as numbers into numbers_.
  void restAsNumbers(std::string_view first) {
    numbers_.clear();
    tokens_.clear();
    for (std::string_view tok = first; !tok.empty(); tok = sc_.token()) {
      double v;
      if (!parseDouble(tok, v)) sc_.fail("bad number " + quote(tok) + " (not a finite number)");
      numbers_.push_back(v);
      tokens_.push_back(tok);
    }
  }

  /// A colour of 3 or 4 components: integers in 0..255, or (when any has a '.' or exponent)
  /// floats in 0..1, as Geomview reads them.
  Rgba8 color(size_t begin, size_t count) const {
    bool floats = false;
    for (size_t i = begin; i < begin + count; ++i)
      floats = floats || tokens_[i].find_first_of(".eE") != std::string_view::npos;
    double c[4] = {0, 0, 0, floats ? 1.0 : 255.0};
    for (size_t i = 0; i < count; ++i) c[i] = numbers_[begin + i];
    if (floats) return Rgba8{unitToByte(c[0]), unitToByte(c[1]), unitToByte(c[2]), unitToByte(c[3])};
    return Rgba8{unitToByte(c[0] / 255), unitToByte(c[1] / 255), unitToByte(c[2] / 255), unitToByte(c[3] / 255)};
  }

  void vertex(const OffLayout& layout, long long v, long long count) {
    std::string_view first = nextContentLine();
    if (first.empty()) endsEarly("vertex", v, count);
    restAsNumbers(first);
    // Whatever is not position, normal or texture coordinate is the colour.
    long long colorCount = (long long)numbers_.size() - 3 - (layout.normals ? 3 : 0) - (layout.textureCoords ? 2 : 0);
    if (numbers_.size() < 3 || (layout.colors ? colorCount != 3 && colorCount != 4 : colorCount != 0)) sc_.fail("vertex " + std::to_string(v) + ": expected x y z" + (layout.normals ? " nx ny nz" : "") +
                      (layout.colors ? " r g b [a]" : "") + (layout.textureCoords ? " s t" : "") + ", found " +
                      std::to_string(numbers_.size()) + " numbers");
    const dvec3 p{numbers_[0], numbers_[1], numbers_[2]};
    if (const char* huge = hugeCoordinate(p)) sc_.fail("vertex " + std::to_string(v) + " has " + huge);
    scene_.positions.push_back(p);
    if (layout.colors) vertexColors_.push_back(color(layout.normals ? 6 : 3, size_t(colorCount)));
  }

  // "n i0 ... i(n-1) [colour]"; the colour is absent, a colour-map index (ignored), or 3 or 4
  // components.
  void face(long long f, long long count) {
    std::string_view first = nextContentLine();
    if (first.empty()) endsEarly("face", f, count);
    long long n;
    if (!parseInt(first, n) || n < 3)
      sc_.fail("face " + std::to_string(f) + ": bad vertex count " + quote(first) + " (at least 3 needed)");
    indices_.clear();
    for (long long k = 0; k < n; ++k) {
      long long i = sc_.integer("vertex index");
      if (i < 0 || uint64_t(i) >= scene_.positions.size())
        sc_.fail("face " + std::to_string(f) + ": vertex index " + std::to_string(i) + " out of range (" +
                 std::to_string(scene_.positions.size()) + " vertices)");
      indices_.push_back(uint32_t(i));
    }
    restAsNumbers(sc_.token());
    Rgba8 c = kDefaultColor;
    if (numbers_.size() == 3 || numbers_.size() == 4) {
      c = color(0, numbers_.size());
      anyFaceColor_ = true;
    } else if (numbers_.size() > 4) {
      sc_.fail("face " + std::to_string(f) + ": expected " + std::to_string(n) +
               " vertex indices and an optional colour, found " + std::to_string(numbers_.size()) + " extra numbers");
    }
    scene_.addFace(indices_, c);
  }

  std::string path_;
  TextScanner sc_;
  Scene scene_;
  std::vector<double> numbers_;
  std::vector<std::string_view> tokens_;
  std::vector<uint32_t> indices_;
  std::vector<Rgba8> vertexColors_;
  bool anyFaceColor_ = false;
};

}  // namespace

Scene loadOff(const std::string& path, std::string_view bytes) { return OffReader(path, bytes).run(); }

}  // namespace hsr::loaders

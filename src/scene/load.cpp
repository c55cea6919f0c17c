// loadScene(): picks the loader for a scene name (builtin:, scene JSON, OBJ/PLY/STL/OFF, else
// assimp) and finalizes the result; plus the file reading, number parsing and text scanning the
// loaders share (loaders.hpp). Called by the CLI, the front end and the tests.
#include <hsr/builtin.hpp>
#include <hsr/io.hpp>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <fstream>

#include "scene/loaders.hpp"

namespace hsr {
namespace loaders {
namespace {

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
bool isSpace(char c) { return isBlank(c) || c == '\n'; }

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

/// Size of a readable, non-empty regular file; throws InputError otherwise.
uintmax_t checkFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw InputError(path + ": file not found");
  if (fs::is_directory(status)) throw InputError(path + ": is a directory, not a file");
  uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read file (" + ec.message() + ")");
  if (size == 0) throw InputError(path + ": file is empty");
  return size;
}

}  // namespace

std::string readFile(const std::string& path) {
  uintmax_t size = checkFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file (" + std::strerror(errno) + ")");
  std::string bytes(size_t(size), '\0');
  in.read(bytes.data(), std::streamsize(size));
  if (size_t(in.gcount()) != size) throw InputError(path + ": cannot read file");
  return bytes;
}

std::string_view skipBom(std::string_view bytes) {
  if (bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);
  return bytes;
}

const char* hugeCoordinate(const dvec3& p) {
  return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > kMaxCoordinate
             ? "a coordinate beyond 1e30 in magnitude"
             : nullptr;
}

std::string numberText(double v) {
  char text[32];
  if (v == std::floor(v) && std::abs(v) < 1e15) std::snprintf(text, sizeof text, "%.0f", v);
  else std::snprintf(text, sizeof text, "%g", v);
  return text;
}

uint8_t unitToByte(double v) {
  if (!(v > 0)) return 0;  // also NaN
  if (v >= 1) return 255;
  return uint8_t(std::lround(v * 255.0));
}

void averageVertexColors(Scene& scene, const std::vector<Rgba8>& vertexColors) {
  for (size_t f = 0; f < scene.faceCount(); ++f) {
    glm::uvec4 sum(0);
    for (uint32_t v : scene.face(f)) {
      const Rgba8& c = vertexColors[v];
      sum += glm::uvec4(c.r, c.g, c.b, c.a);
    }
    const uint32_t n = uint32_t(scene.face(f).size());
    auto mean = [n](uint32_t total) { return uint8_t((total + n / 2) / n); };
    scene.faceColors[f] = Rgba8{mean(sum.r), mean(sum.g), mean(sum.b), mean(sum.a)};
  }
}

bool parseDouble(std::string_view token, double& value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value, std::chars_format::general);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    // Underflow (a negative exponent) is zero for any model; overflow is an error.
    size_t e = token.find_first_of("eE");
    if (e == std::string_view::npos || e + 1 >= token.size() || token[e + 1] != '-') return false;
    value = token[0] == '-' ? -0.0 : 0.0;
    return true;
  }
  return ec == std::errc() && std::isfinite(value);
}

bool parseInt(std::string_view token, long long& value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

std::string quote(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < kMax; ++i) {
    unsigned char c = static_cast<unsigned char>(token[i]);
    out += (c >= 0x20 && c < 0x7f) ? char(c) : '?';
  }
  if (token.size() > kMax) out += "...";
  return out + "'";
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

// --- TextScanner ----------------------------------------------------------------------------

TextScanner::TextScanner(std::string_view text, std::string file, bool hashComments,
                         bool lineContinuation, size_t firstLine)
    : text_(text), file_(std::move(file)), hashComments_(hashComments),
      lineContinuation_(lineContinuation), line_(firstLine), tokenLine_(firstLine) {}

void TextScanner::skipBlanks(bool crossLines) {
  while (pos_ < text_.size()) {
    char c = text_[pos_];
    if (isBlank(c)) {
      ++pos_;
    } else if (c == '\n' && crossLines) {
      ++pos_;
      ++line_;
    } else if (c == '\\' && lineContinuation_ &&
               (text_.substr(pos_ + 1, 1) == "\n" || text_.substr(pos_ + 1, 2) == "\r\n")) {
      pos_ = text_.find('\n', pos_) + 1;
      ++line_;
    } else if (c == '#' && hashComments_) {
      // A comment runs to the end of the line (the newline itself is left for the caller).
      size_t eol = text_.find('\n', pos_);
      pos_ = eol == std::string_view::npos ? text_.size() : eol;
    } else {
      return;
    }
  }
}

std::string_view TextScanner::token() {
  skipBlanks(false);
  tokenLine_ = line_;
  size_t start = pos_;
  while (pos_ < text_.size() && !isSpace(text_[pos_])) {
    // A continuation backslash ends the token ("f 1 2 3\" continues the face).
    if (text_[pos_] == '\\' && lineContinuation_ &&
        (text_.substr(pos_ + 1, 1) == "\n" || text_.substr(pos_ + 1, 2) == "\r\n"))
      break;
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

std::string_view TextScanner::anyToken() {
  const size_t previousLine = tokenLine_;
  skipBlanks(true);
  std::string_view tok = token();
  if (tok.empty()) tokenLine_ = previousLine;  // at the end of the text: blame the last token's line
  return tok;
}

std::string_view TextScanner::restOfLine() {
  skipBlanks(false);
  tokenLine_ = line_;
  size_t start = pos_;
  size_t eol = text_.find('\n', pos_);
  if (eol == std::string_view::npos) eol = text_.size();
  size_t end = eol;
  // A comment starts at a '#' that begins a word.
  if (hashComments_)
    for (size_t i = start; i < eol; ++i)
      if (text_[i] == '#' && (i == start || isBlank(text_[i - 1]))) {
        end = i;
        break;
      }
  while (end > start && isBlank(text_[end - 1])) --end;
  pos_ = eol;
  return text_.substr(start, end - start);
}

bool TextScanner::nextLine() {
  size_t eol = text_.find('\n', pos_);
  if (eol == std::string_view::npos || eol + 1 == text_.size()) {
    pos_ = text_.size();  // the newline ending the last line starts no new line
    return false;
  }
  pos_ = eol + 1;
  tokenLine_ = ++line_;
  return true;
}

double TextScanner::number(const char* what) {
  std::string_view tok = token();
  if (tok.empty()) fail(std::string("expected ") + what);
  double value;
  if (!parseDouble(tok, value)) fail(std::string("bad ") + what + " " + quote(tok) + " (not a finite number)");
  return value;
}

long long TextScanner::integer(const char* what) {
  std::string_view tok = token();
  if (tok.empty()) fail(std::string("expected ") + what);
  long long value;
  if (!parseInt(tok, value)) fail(std::string("bad ") + what + " " + quote(tok) + " (not an integer)");
  return value;
}

void TextScanner::expectLineEnd(const char* after) {
  std::string_view tok = token();
  if (!tok.empty()) fail(std::string("unexpected ") + quote(tok) + " after " + after);
}

void TextScanner::fail(const std::string& problem) const {
  throw InputError(file_ + ":" + std::to_string(tokenLine_) + ": " + problem);
}

// --- Dispatch -------------------------------------------------------------------------------

Scene loadAny(const std::string& path, LoadContext& context) {
  static constexpr std::string_view kBuiltin = "builtin:";
  if (path.starts_with(kBuiltin)) return makeBuiltin(path.substr(kBuiltin.size()));

  const std::string ext = lowerExtension(path);
  Scene scene;
  if (ext == ".json") {
    scene = loadSceneJson(path, skipBom(readFile(path)), context);
  } else if (ext == ".obj") {
    scene = loadObj(path, skipBom(readFile(path)));
  } else if (ext == ".ply") {
    scene = loadPly(path, skipBom(readFile(path)));
  } else if (ext == ".stl") {
    scene = loadStl(path, readFile(path));  // (a binary STL's header may start with any bytes: see loadStl)
  } else if (ext == ".off") {
    scene = loadOff(path, skipBom(readFile(path)));
  } else {
    checkFile(path);  // assimp reads the file itself; our messages for missing or empty files
    scene = loadAssimp(path);
  }
  scene.source = path;
  return scene;
}

}  // namespace loaders

namespace {

// Mesh entries [first, end) of run `part` when `weights` are cut into `parts` contiguous runs of
// about equal weight: an entry goes to the run its weight's midpoint falls in. An empty run
// starts where the next one does, so the runs in order cover the entries in order.
loaders::EntryRange entryRun(const std::vector<double>& weights, int part, int parts) {
  double total = 0;
  for (double w : weights) total += w;
  loaders::EntryRange range{weights.size(), weights.size()};
  double before = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    const double middle = total > 0 ? (before + weights[i] / 2) / total : (double(i) + 0.5) / double(weights.size());
    const int run = std::min(parts - 1, int(middle * parts));
    before += weights[i];
    if (run >= part && range.first == weights.size()) range.first = i;
    if (run > part) {
      range.end = i;
      break;
    }
  }
  return range;
}

}  // namespace

ScenePart loadScenePart(const std::string& path, int part, int parts) {
  if (parts < 1 || part < 0 || part >= parts) throw std::invalid_argument("loadScenePart: part outside 0..parts-1");
  ScenePart out;
  if (parts == 1 || loaders::lowerExtension(path) != ".json" || path.starts_with("builtin:")) {
    out.scene = loadScene(path);
    out.whole = true;
    return out;
  }
  const std::string bytes = loaders::readFile(path);
  const std::vector<double> weights = loaders::sceneJsonEntryWeights(path, loaders::skipBom(bytes));
  if (weights.size() < 2) {
    out.scene = loadScene(path);
    out.whole = true;
    return out;
  }
  const loaders::EntryRange run = entryRun(weights, part, parts);
  out.firstEntry = run.first;
  out.entryCount = run.end - run.first;
  out.entriesInFile = weights.size();
  loaders::LoadContext context;
  out.scene = loaders::loadSceneJson(path, loaders::skipBom(bytes), context, run);
  out.scene.finalize();
  return out;
}

Scene loadScene(const std::string& path) {
  loaders::LoadContext context;
  Scene scene = loaders::loadAny(path, context);
  if (path.starts_with("builtin:")) return scene;  // generated finalized
  if (scene.faceCount() == 0) throw InputError(path + ": no polygon faces to render");
  scene.finalize();
  return scene;
}

}  // namespace hsr

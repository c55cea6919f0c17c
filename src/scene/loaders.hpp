// Internal interface of the scene loaders: one entry point per format (load_*.cpp), the file
// reading and text scanning they share, and the "file:line: problem" error helpers.
// Consumed only by the loaders themselves (load*.cpp); the public entry point is loadScene().
#pragma once
#include <hsr/scene.hpp>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace hsr::loaders {

/// Colour of faces whose file gives none.
inline constexpr Rgba8 kDefaultColor{200, 200, 200, 255};

/// Scene JSON nesting: the files being loaded (outermost first), to catch a JSON that includes
/// itself and to bound the nesting depth.
struct LoadContext {
  std::vector<std::string> openJsonFiles;  // canonical paths
};

/// Loads any scene (builtin:, .json, mesh file). Not finalized unless it comes from a
/// generator that finalizes (builtin:). loadScene() is this plus finalize().
Scene loadAny(const std::string& path, LoadContext& context);

// The format loaders. Each fills positions, faces (in file order), colours, mesh ranges and
// loader notes; none finalizes. `bytes` is the whole file.
Scene loadObj(const std::string& path, std::string_view bytes);
Scene loadPly(const std::string& path, std::string_view bytes);
Scene loadStl(const std::string& path, std::string_view bytes);
Scene loadOff(const std::string& path, std::string_view bytes);
Scene loadAssimp(const std::string& path);
/// Mesh entries [first, end) of a scene JSON.
struct EntryRange {
  size_t first = 0, end = SIZE_MAX;
};
/// A scene JSON's mesh entries in `entries` (all by default), with the file's camera and light.
Scene loadSceneJson(const std::string& path, std::string_view bytes, LoadContext& context, EntryRange entries = {});
/// Per mesh entry of a scene JSON, its weight for sharing the entries among processes: a file's
/// size in bytes (0 if it cannot be read: its loader reports that), a built-in entry the mean of
/// the files' (1 when there are none).
std::vector<double> sceneJsonEntryWeights(const std::string& path, std::string_view bytes);

/// Reads a whole file. Throws InputError "path: file not found", "path: is a directory, not a
/// file", "path: file is empty" or "path: cannot open file (reason)".
std::string readFile(const std::string& path);

/// `bytes` without a leading UTF-8 byte-order mark (text formats may start with one).
std::string_view skipBom(std::string_view bytes);
/// Coordinates beyond this magnitude are refused (Scene::finalize checks too): squared lengths
/// and cross products of such values overflow. The loaders check each vertex as they read it,
/// so the message names the file's line and the format's own vertex number.
inline constexpr double kMaxCoordinate = 1e30;
/// "a coordinate beyond 1e30 in magnitude" if `p` has one, else nullptr (p is finite).
const char* hugeCoordinate(const dvec3& p);
/// A number read from a file, for a message: an integer without decimals, else %g.
std::string numberText(double v);
/// Maps a colour channel in [0, 1] to 0..255 (clamped, NaN -> 0).
uint8_t unitToByte(double v);
/// Sets every face's colour to the mean of its vertices' colours (one per position).
void averageVertexColors(Scene& scene, const std::vector<Rgba8>& vertexColors);

/// Parses a whole token as a finite double (also accepts a leading '+', which from_chars does
/// not). Returns false for anything else, including nan, inf and out-of-range values.
bool parseDouble(std::string_view token, double& value);
/// Parses a whole token as a decimal integer (optional sign).
bool parseInt(std::string_view token, long long& value);
/// A token for an error message: quoted, shortened, non-printable bytes replaced.
std::string quote(std::string_view token);
/// Case-insensitive ASCII comparison.
bool iequals(std::string_view a, std::string_view b);

/// A cursor over a text file for the line-oriented formats (OBJ, MTL, OFF, ASCII PLY, ASCII
/// STL), tracking line numbers for "file:line: problem" errors.
class TextScanner {
 public:
  /// hashComments: '#' starts a comment that runs to the end of the line.
  /// lineContinuation: a backslash right before the end of a line joins the next line (OBJ).
  TextScanner(std::string_view text, std::string file, bool hashComments, bool lineContinuation,
              size_t firstLine = 1);

  /// The next token on the current line; empty at the end of the line.
  std::string_view token();
  /// The rest of the current line, trimmed (comment removed); the line is consumed.
  std::string_view restOfLine();
  /// The next token anywhere after the cursor (crossing line ends); empty at the end of text.
  std::string_view anyToken();
  /// Moves to the start of the next line. False at the end of the text.
  bool nextLine();
  /// Byte offset of the cursor (where binary data starts after a PLY header).
  size_t offset() const { return pos_; }

  /// Line number of the last token returned (or of the cursor before any token on this line).
  size_t line() const { return tokenLine_; }
  const std::string& file() const { return file_; }

  /// The next token on the line as a finite double / integer; throws "file:line: expected
  /// WHAT" when the line has ended, or "file:line: bad WHAT 'token'".
  double number(const char* what);
  long long integer(const char* what);
  /// Throws unless the line has no more tokens.
  void expectLineEnd(const char* after);
  /// Throws InputError "file:line: problem" at line().
  [[noreturn]] void fail(const std::string& problem) const;

 private:
  void skipBlanks(bool crossLines);

  std::string_view text_;
  std::string file_;
  bool hashComments_, lineContinuation_;
  size_t pos_ = 0;
  size_t line_;       // line of pos_
  size_t tokenLine_;  // line of the last token
};

}  // namespace hsr::loaders

// The algorithm contract: every visibility algorithm is declared once, with its name, summary,
// source document, parameters and guarantee, in a registry that the command line (`hsr
// algorithms`, `--param`), render(), the statistics and the conformance tests all read. The
// registry's entry makes the algorithm as an object for one scene (Algorithm), which renders any
// camera and owns what it keeps from view to view. Declared in src/algorithms/NAME.cpp; listed by
// one line in src/algorithms/registry.cpp.
#pragma once
#include <hsr/frame.hpp>

#include <cstdint>
#include <functional>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hsr {

struct Scene;
struct Camera;
struct RenderOptions;

/// The type of an algorithm parameter, as `--param key=value` parses it.
enum class ParamType : uint8_t {
  Choice,  // one of ParamSpec::choices
  Int,     // a whole number in [min, max]
  Real,    // a finite number in [min, max]
  Bool,    // on|off (also true|false, 1|0)
  Size,    // WxH, each a whole number in [min, max], or "full" (the whole image)
};

/// One parameter of an algorithm.
struct ParamSpec {
  std::string name;          // lower case, words joined by '-': "sort-key"
  ParamType type = ParamType::Choice;
  std::string defaultValue;  // as the user would write it
  std::vector<std::string> choices;  // Choice: the allowed values
  double min = -1e300, max = 1e300;  // Int, Real: the allowed range (inclusive)
  std::string help;
};

/// What an algorithm promises about its image against the exact reference (raycast): the
/// conformance tests check exactly this, and `hsr algorithms` prints it.
struct Guarantee {
  enum class Kind : uint8_t {
    Exact,          // no wrong pixel (differences only where verify finds them ambiguous)
    ExactWhen,      // exact whenever `holds` is true; otherwise wrong pixels are reported, not failed
    Approximate,    // wrong pixels at most maxWrongFraction of the covered pixels
    FailsByDesign,  // wrong pixels > 0 on each scene of failsOn (with its own camera); elsewhere 0,
                    // wherever `holds` is true when it is given (the condition under which it is exact)
  };
  Kind kind = Kind::Exact;
  /// ExactWhen: the condition; Approximate: what is bounded; FailsByDesign: why it fails.
  std::string condition;
  /// ExactWhen (and optionally FailsByDesign, off its failure scenes): whether the condition
  /// under which it is exact holds for a scene, camera and options.
  std::function<bool(const Scene&, const Camera&, const RenderOptions&)> holds;
  std::string exactWhen;  // FailsByDesign with `holds`: that condition, in words
  double maxWrongFraction = 0;        // Approximate
  std::vector<std::string> failsOn;   // FailsByDesign: scene names as loadScene takes them

  /// One line: "exact", "exact when ...", "approximate: ...", "fails by design on ...".
  std::string describe() const;
};

/// The parameters an algorithm runs with: every declared parameter, given or defaulted, checked
/// against its ParamSpec, in declaration order.
class AlgorithmParams {
 public:
  AlgorithmParams() = default;
  /// The value of parameter `name` as text (throws std::logic_error for an undeclared name).
  const std::string& text(const std::string& name) const;
  int64_t integer(const std::string& name) const;
  double real(const std::string& name) const;
  bool flag(const std::string& name) const;
  /// A Size parameter as (width, height); (0, 0) for "full".
  std::pair<int64_t, int64_t> size(const std::string& name) const;
  /// (name, value) in declaration order: what the statistics record as "params".
  const std::vector<std::pair<std::string, std::string>>& entries() const { return entries_; }

 private:
  friend AlgorithmParams resolveParams(const struct AlgorithmInfo&, const std::map<std::string, std::string>&);
  std::vector<std::pair<std::string, std::string>> entries_;
};

/// A visibility algorithm made for one scene and one set of parameters (AlgorithmInfo::create):
/// pbrt's Integrator in this toolkit. It owns what it keeps from one view to the next (a BSP
/// tree, the tiled z-buffer's bins and buffers, the half-range depth buffer), so "build once, view
/// many" is one object rendering many cameras. The scene must outlive it; one thread renders with
/// it at a time (each render may use the thread pool inside).
class Algorithm {
 public:
  virtual ~Algorithm() = default;
  /// Fills frame.faceId/triangleId/depth/color (those sized) and frame.stats for `camera`.
  /// render() has sized the frame (not cleared), started its statistics (image size, scene counts)
  /// and checked the options; the algorithm writes every pixel of the buffers present. Fills
  /// Frame::writes when RenderOptions::countWrites is set (the overdraw picture), or throws
  /// InputError when it cannot with its parameters.
  virtual void render(const Camera& camera, const RenderOptions& options, Frame& frame) = 0;
};

/// What an algorithm can do besides rendering a frame, declared in its registry entry.
enum class Capability : uint8_t {
  None = 0,
  PaintsInOrder = 1,  // paints polygons back to front, so --svg can write them as vector polygons
  Csg = 2,            // shows a scene's CSG tree (Scene::csg) as its result; the conformance suite
                      // judges only these on CSG scenes (the others draw the solids as plain meshes)
};

/// Makes the algorithm for a finalized scene with checked parameters.
using AlgorithmFactory = std::function<std::unique_ptr<Algorithm>(const Scene&, const AlgorithmParams&)>;

/// An algorithm as the registry holds it.
struct AlgorithmInfo {
  std::string name;     // what --algorithm takes
  std::string summary;  // one line
  std::string source;   // the documents it comes from (docs/references.md names)
  std::vector<ParamSpec> params;
  Guarantee guarantee;  // at its default parameters
  /// When the guarantee depends on the parameters (a sort key, an order): the guarantee with
  /// these; unset: `guarantee` for all.
  std::function<Guarantee(const AlgorithmParams&)> guaranteeFor;
  Guarantee guaranteeWith(const AlgorithmParams& params) const {
    return guaranteeFor ? guaranteeFor(params) : guarantee;
  }
  Capability capability = Capability::None;
  /// Makes the algorithm for one scene (Algorithm).
  AlgorithmFactory create;
};

/// Every registered algorithm, in the order `hsr algorithms` lists them. Entries never move:
/// a pointer from findAlgorithm stays valid after registerAlgorithm.
const std::deque<AlgorithmInfo>& algorithms();
/// The algorithm named `name`, or null.
const AlgorithmInfo* findAlgorithm(const std::string& name);
/// Adds an algorithm to the registry (for tests and embedders; call before rendering, from one
/// thread). Throws std::invalid_argument when the name is taken or the declaration is malformed.
void registerAlgorithm(AlgorithmInfo info);
/// Checks `given` (parameter name -> text) against the algorithm's declaration and fills in the
/// defaults. Throws InputError keyed Setting::Param, subject "NAME=VALUE", for an unknown name or
/// a bad value.
AlgorithmParams resolveParams(const AlgorithmInfo& algorithm, const std::map<std::string, std::string>& given);
/// "choice", "int", "real", "bool", "size".
const char* paramTypeName(ParamType type);

}  // namespace hsr

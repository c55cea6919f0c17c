// The comparison study behind `hsr compare`: scenes at image sizes, each rendered by every
// algorithm variant, timed, counted and checked against the exact reference (raycast), with
// pictures; its results are one JSON document (docs/compare.md, docs/compare-results.schema.json).
#pragma once
#include <hsr/hsr.hpp>

#include <nlohmann/json.hpp>

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace hsr::cli {

using Json = nlohmann::ordered_json;

/// One scene at one image size, and why the study renders it.
struct StudyCase {
  std::string id;     // unique, file-name safe: "kth-report-n50-640x480"
  std::string group;  // the experiment it belongs to: "KTH report", "painter failures", ...
  std::string scene;  // as loadScene takes it
  int width = 0, height = 0;
  bool pictures = false;  // write the images of every algorithm (small sizes only)
};

/// An algorithm with parameters: "bsp" or "zbuffer:raster=halfspace[:KEY=VALUE...]" on the command line.
struct Variant {
  std::string label;      // "zbuffer raster=halfspace"
  std::string algorithm;  // "zbuffer"
  std::map<std::string, std::string> params;
};

/// The default study: the source documents' scenarios on built-in scenes; `quick` shrinks it to
/// small sizes for the test suite.
std::vector<StudyCase> defaultStudy(bool quick);
/// Cases for scenes given on the command line, at each of `sizes`.
std::vector<StudyCase> casesOf(const std::vector<std::string>& scenes, const std::vector<std::pair<int, int>>& sizes);
/// Every registered algorithm at its defaults, plus the textbook z-buffer on the service's
/// rasterizers (the forms the documents' claims are about).
std::vector<Variant> defaultVariants();
/// Parses "name" or "name:key=value:key=value" (throws InputError naming `text`).
Variant parseVariant(const std::string& text);

struct StudySettings {
  int frames = 3;         // timed frames per run (one when the first takes over 2 s)
  int threads = 0;
  std::string outDir;     // images go to outDir/img/CASE/
  std::atomic<bool>* interrupted = nullptr;  // set from a signal handler: stop after the current run
  /// Called before each run (case index, variant index, totals) and once at the end with done.
  std::function<void(size_t run, size_t runs, const StudyCase&, const std::string& what)> progress;
};

/// Runs the cases (each variant on each) and returns the results document; after each case
/// `caseDone(results so far)` is called, so a caller can keep a consistent report on disk.
Json runStudy(const std::vector<StudyCase>& cases, const std::vector<Variant>& variants, const StudySettings& settings,
              const std::function<void(const Json&)>& caseDone);

/// The run of `variant` in case `c` of the results, if it ran without error (claims.cpp).
const Json* runIn(const Json& c, const std::string& variant);
/// A case's name: its scene and size.
std::string caseName(const Json& c);

/// Z-fighting: the nearly coplanar built-in scene at several gaps, pixels whose face differs from
/// the reference per depth format, with pictures.
Json zfightExperiment(const StudySettings& settings, bool quick);
/// Temporal coherence: zbuffer-culled with and without temporal=on over an orbit of the city (one
/// algorithm object per orbit): triangles set up and time per frame, and whether every
/// frame's face ids are the same with it as without.
Json coherenceExperiment(const StudySettings& settings, bool quick);
/// Lossless depth compression (hsr/depth_compression.hpp) of the final depth buffer of scenes at
/// 1920x1080 in three formats: bytes against the buffer as allocated, the blocks of each kind, and
/// the round trip checked bit for bit.
Json depthCompressionExperiment(const StudySettings& settings, bool quick);
/// Shadow maps (docs/shadows.md): the city and the clutter under a sun, one 4096 map against four
/// cascades of 2048 (the same texels), each pixel's verdict checked against an exact shadow ray.
Json shadowExperiment(const StudySettings& settings, bool quick);
/// The buffers' bytes per depth format and image size: packed (as the documents count) and as
/// hsr allocates them.
Json memoryTable();
/// The depth-precision curves of the report: per format, step and value fraction over the range.
Json precisionCurves(double near, double far);
/// The claims of the documents, each with its source, what was measured and a verdict.
Json evaluateClaims(const Json& results);
/// The KTH thesis's claims on how perspective depth values crowd near the camera (hsr precision).
Json precisionClaims();
/// Writes DIR/index.html (and chart.min.js beside it) for the results document.
void writeReport(const std::string& dir, const Json& results);

}  // namespace hsr::cli

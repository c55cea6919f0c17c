// The study's HTML report (study.hpp): static tables and pictures written here, charts drawn in
// the page by Chart.js (Debian's libjs-chart.js, copied beside the page) from the results
// embedded in it, so the report opens from disk with no network.
#include "study.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hsr::cli {
namespace {

const char* const kChartJsPaths[] = {"/usr/share/javascript/chart.js/chart.min.js",
                                     "/usr/share/nodejs/chart.js/dist/chart.min.js"};

std::string esc(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string verdictClass(const std::string& verdict) {
  if (verdict == "holds" || verdict.rfind("holds (", 0) == 0) return "ok";
  if (verdict == "does not hold") return "bad";
  if (verdict == "not measured") return "na";
  return "partly";
}

std::string checkClass(const std::string& check) {
  return check.find("VIOLATES") != std::string::npos ? "bad" : check.rfind("fails", 0) == 0 ? "partly" : "ok";
}

std::string num(const Json& v) {
  if (v.is_number_unsigned()) {
    std::string s = std::to_string(v.get<uint64_t>()), out;
    for (size_t i = 0; i < s.size(); ++i) out += (i && (s.size() - i) % 3 == 0 ? "," : "") + std::string(1, s[i]);
    return out;
  }
  if (v.is_number()) return fmt::format("{:.3g}", v.get<double>());
  return v.is_null() ? "" : esc(v.dump());
}

void writeHead(std::ostream& o, const Json& results) {
  const Json& m = results["machine"];
  o << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>hsr compare</title>\n<style>\n"
       "body{font:14px/1.45 system-ui,sans-serif;margin:1.5em auto;max-width:1400px;padding:0 1em;color:#222}\n"
       "table{border-collapse:collapse;margin:.5em 0 1.5em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\n"
       "th{background:#f3f3f3}td.l,th.l{text-align:left}.ok{background:#dff5df}.bad{background:#fbd5d5}\n"
       ".partly{background:#fdf1c7}.na{background:#eee;color:#777}.charts{display:grid;grid-template-columns:repeat("
       "auto-fill,minmax(600px,1fr));gap:1.5em}.chart{height:360px}figure{margin:0;display:inline-block;text-align:"
       "center;font-size:12px}figure img{max-width:240px;image-rendering:pixelated;border:1px solid #aaa;display:"
       "block}.row{display:flex;gap:6px;flex-wrap:wrap;align-items:flex-end;margin-bottom:8px}.banner{padding:.5em 1em;"
       "background:#fdf1c7;border:1px solid #e0c060}h3{margin-bottom:.3em}.lbl{width:170px;font-weight:600}\n"
       "</style></head><body>\n";
  o << "<h1>Hidden-surface removal, compared</h1>\n<p>The source documents' comparisons, measured by "
       "<code>hsr compare</code> on scenes anyone can regenerate, every image checked against the exact ray-cast "
       "reference. Machine: "
    << esc(m.value("cpu", "")) << ", " << m.value("threads", 0) << " threads, SIMD " << esc(m.value("kernel_isa", ""))
    << ", build " << esc(m.value("build_type", "")) << ", commit <code>" << esc(m.value("commit", "")) << "</code>; "
    << results.value("frames", 0) << " timed frames per run (median).</p>\n";
  if (!results.value("complete", false))
    o << "<p class=\"banner\">This report is partial: the study was interrupted; what ran is shown.</p>\n";
}

void writeClaims(std::ostream& o, const Json& results) {
  o << "<h2 id=\"claims\">Claims of the documents</h2>\n<table><tr><th class=l>claim</th><th class=l>source</th>"
       "<th class=l>measured</th><th class=l>verdict</th></tr>\n";
  for (const Json& c : results["claims"])
    o << "<tr><td class=l>" << esc(c["claim"]) << "</td><td class=l>" << esc(c["source"]) << "</td><td class=l>"
      << esc(c["measured"]) << "</td><td class=\"l " << verdictClass(c["verdict"]) << "\">" << esc(c["verdict"])
      << "</td></tr>\n";
  o << "</table>\n";
}

void writeResultsTable(std::ostream& o, const Json& results) {
  o << "<h2 id=\"table\">Every run</h2>\n<p>Time: median wall-clock ms of whole frames. Overdraw: colour writes per "
       "covered pixel. Wrong: pixels whose face differs from the reference with nothing to explain it; ambiguous: "
       "differences explained by depth precision or a pixel centre on an edge (docs/reference.md).</p>\n";
  o << "<table><tr><th class=l>scene</th><th>size</th><th class=l>algorithm</th><th>ms</th><th>z tests</th><th>depth "
       "writes</th><th>colour writes</th><th>overdraw</th><th>memory (bytes)</th><th>wrong</th><th>ambiguous</th>"
       "<th class=l>against its guarantee</th></tr>\n";
  for (const Json& c : results["cases"])
    for (const Json& r : c["runs"]) {
      o << "<tr><td class=l>" << esc(c["scene"]) << "</td><td>" << c["width"] << "x" << c["height"] << "</td><td class=l>"
        << esc(r["variant"]) << "</td>";
      if (r.contains("error")) {
        o << "<td class=\"l bad\" colspan=9>" << esc(r["error"]) << "</td></tr>\n";
        continue;
      }
      o << "<td>" << num(r["median_ms"]) << "</td><td>" << num(r["depth_tests"]) << "</td><td>" << num(r["depth_writes"])
        << "</td><td>" << num(r["color_writes"]) << "</td><td>" << num(r["overdraw"]) << "</td><td>"
        << num(r["memory_bytes"]) << "</td><td>" << num(r["wrong_pixels"]) << "</td><td>" << num(r["ambiguous_pixels"])
        << "</td><td class=\"l " << checkClass(r["check"]) << "\">" << esc(r["check"]) << "</td></tr>\n";
    }
  o << "</table>\n";
}

// Each algorithm's own counters (Stats::details: Newell's tests by kind, the BSP tree's fragments,
// the pyramid's levels, ...), one table per algorithm variant, a row per case.
void writeDetails(std::ostream& o, const Json& results) {
  o << "<h2 id=\"details\">Each algorithm's own counters</h2>\n<p>What each algorithm counts of its own work "
       "(<code>docs/algorithms/NAME.md</code> says what each counter means).</p>\n";
  std::vector<std::string> variants;
  for (const Json& c : results["cases"])
    for (const Json& r : c["runs"])
      if (std::find(variants.begin(), variants.end(), r["variant"].get<std::string>()) == variants.end())
        variants.push_back(r["variant"]);
  for (const std::string& v : variants) {
    std::vector<std::string> keys;  // the numeric counters, in the order the algorithm reports them
    for (const Json& c : results["cases"])
      for (const Json& r : c["runs"])
        if (r["variant"] == v && r.contains("stats") && r["stats"].contains(r["algorithm"].get<std::string>()))
          for (const auto& [key, value] : r["stats"][r["algorithm"].get<std::string>()].items())
            if (value.is_number() && std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
    if (keys.empty()) continue;
    o << "<h3>" << esc(v) << "</h3>\n<table><tr><th class=l>scene</th><th>size</th>";
    for (const std::string& k : keys) o << "<th>" << esc(k) << "</th>";
    o << "</tr>\n";
    for (const Json& c : results["cases"])
      for (const Json& r : c["runs"]) {
        if (r["variant"] != v || !r.contains("stats")) continue;
        const Json& d = r["stats"].value(r["algorithm"].get<std::string>(), Json::object());
        o << "<tr><td class=l>" << esc(c["scene"]) << "</td><td>" << c["width"] << "x" << c["height"] << "</td>";
        for (const std::string& k : keys) o << "<td>" << (d.contains(k) ? num(d[k]) : "") << "</td>";
        o << "</tr>\n";
      }
    o << "</table>\n";
  }
}

void writePictures(std::ostream& o, const Json& results) {
  o << "<h2 id=\"pictures\">Pictures</h2>\n<p>Per algorithm: the image, its depth (the KTH report's grey z-buffer "
       "picture, near white), its overdraw (fragments written per pixel: black 0, blue 1, green 2, yellow 3, orange 4, "
       "red 5, magenta 6, white 7 or more) and its error against the reference (red wrong, yellow ambiguous).</p>\n";
  for (const Json& c : results["cases"]) {
    bool any = false;
    for (const Json& r : c["runs"]) any |= r.contains("images");
    if (!any) continue;
    o << "<h3>" << esc(c["scene"]) << " " << c["width"] << "x" << c["height"] << " <small>(" << esc(c["group"])
      << ")</small></h3>\n";
    for (const Json& r : c["runs"]) {
      if (!r.contains("images")) continue;
      o << "<div class=row><div class=lbl>" << esc(r["variant"]) << "<br><small>" << num(r["wrong_pixels"])
        << " wrong</small></div>";
      for (const char* kind : {"color", "depth", "overdraw", "error"})
        if (r["images"].contains(kind))
          o << "<figure><img loading=\"eager\" src=\"" << esc(r["images"][kind]) << "\" alt=\"" << esc(r["variant"]) << " "
            << kind << "\">" << kind << "</figure>";
      o << "</div>\n";
    }
  }
}

void writeZfight(std::ostream& o, const Json& results) {
  if (!results.contains("zfight")) return;
  o << "<h2 id=\"zfight\">Z-fighting</h2>\n<p>Two nearly coplanar polygons (<code>builtin:zfight</code>, far/near = "
       "10<sup>4</sup>) at relative gaps 10<sup>-2</sup> to 10<sup>-5</sup>: pixels showing the wrong one per depth "
       "format (chart above), and the pictures at each gap. \"In N parts\" is the KTH thesis's mitigation: the depth "
       "range drawn in N parts of equal far/near ratio, farthest first, each with the format's whole precision "
       "(<code>zbuffer-sliced --param slices=N</code>); its cost is the time beside it.</p>\n";
  std::string gap;
  for (const Json& z : results["zfight"]) {
    const std::string g = fmt::format("{:g}", z["gap"].get<double>());
    if (g != gap) o << (gap.empty() ? "" : "</div>\n") << "<div class=row><div class=lbl>gap " << g << "</div>";
    gap = g;
    o << "<figure><img src=\"" << esc(z["image"]) << "\" alt=\"zfight " << g << "\">" << esc(z["format"]) << ": "
      << num(z["fighting_pixels"]) << " px, " << fmt::format("{:.1f}", z["ms"].get<double>()) << " ms</figure>";
  }
  if (!gap.empty()) o << "</div>\n";
}

// A section of the report that is one table: heading, a paragraph (HTML), the column names, and
// each row of `rows` as its cells (HTML) by `cells`.
template <class Cells>
void writeTableSection(std::ostream& o, const char* id, const char* title, const char* intro,
                       std::initializer_list<const char*> columns, const Json& rows, Cells&& cells) {
  o << "<h2 id=\"" << id << "\">" << title << "</h2>\n<p>" << intro << "</p>\n<table><tr>";
  for (const char* c : columns) o << "<th>" << c << "</th>";
  o << "</tr>\n";
  for (const Json& r : rows) {
    o << "<tr>";
    for (const std::string& cell : cells(r)) o << "<td>" << cell << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";
}

// The painter's family on both rasterizers, each against the z-buffer on the same one: per
// case and algorithm that ran as "NAME" (the scalar binned service) and "NAME raster=tiled" (the
// SIMD tile kernel), beside "zbuffer raster=binned" and "zbuffer".
void writeBothRasterizers(std::ostream& o, const Json& results) {
  Json rows = Json::array();
  for (const Json& c : results["cases"]) {
    const Json *zScalar = runIn(c, "zbuffer raster=binned"), *zKernel = runIn(c, "zbuffer");
    if (!zScalar || !zKernel) continue;
    for (const Json& r : c["runs"]) {
      const std::string variant = r["variant"];
      const size_t at = variant.rfind(" raster=tiled");
      if (at == std::string::npos || at + 13 != variant.size() || r.contains("error")) continue;
      const Json* scalar = runIn(c, variant.substr(0, at));
      if (!scalar) continue;
      const auto ms = [](const Json& run) { return run["median_ms"].get<double>(); };
      rows.push_back({{"case", caseName(c)},
                      {"algorithm", variant.substr(0, at)},
                      {"scalar_ms", ms(*scalar)},
                      {"scalar_ratio", ms(*scalar) / ms(*zScalar)},
                      {"kernel_ms", ms(r)},
                      {"kernel_ratio", ms(r) / ms(*zKernel)},
                      {"same_wrong", (*scalar)["wrong_pixels"] == r["wrong_pixels"]}});
    }
  }
  if (rows.empty()) return;
  writeTableSection(
      o, "rasterizers", "The painter's family on both rasterizers",
      "Each algorithm against the z-buffer on the same rasterizer, so that the difference is the algorithm's: "
      "<code>NAME</code> and <code>zbuffer raster=binned</code> on the scalar binned service, "
      "<code>NAME raster=tiled</code> and <code>zbuffer</code> on the SIMD tile kernel (a list-priority order drawn "
      "on priority keys: the same image, docs/kernel.md). Median frame times; ratio = the algorithm's time / the "
      "z-buffer's on that rasterizer.",
      {"case", "algorithm", "binned ms", "/ zbuffer binned", "tiled ms", "/ zbuffer", "same wrong pixels"}, rows,
      [](const Json& r) {
        return std::vector<std::string>{esc(r["case"]),
                                        esc(r["algorithm"]),
                                        fmt::format("{:.2f}", r["scalar_ms"].get<double>()),
                                        fmt::format("{:.2f}", r["scalar_ratio"].get<double>()),
                                        fmt::format("{:.2f}", r["kernel_ms"].get<double>()),
                                        fmt::format("{:.2f}", r["kernel_ratio"].get<double>()),
                                        r["same_wrong"].get<bool>() ? "yes" : "no"};
      });
}

void writeCoherence(std::ostream& o, const Json& results) {
  if (!results.contains("coherence")) return;
  writeTableSection(
      o, "coherence", "Temporal coherence",
      "Occlusion culling over an orbit (<code>zbuffer-culled</code>, one algorithm object per orbit): with "
      "<code>temporal=on</code> the meshes that showed in the previous frame are drawn first, untested, as occluders, "
      "and every other mesh is tested against them. Triangles set up and time per frame, and the frames whose face ids "
      "equal those without it.",
      {"scene", "size", "poses", "temporal", "triangles set up a frame", "meshes carried a frame", "median ms",
       "frames identical"},
      results["coherence"], [](const Json& r) {
        return std::vector<std::string>{
            esc(r["scene"]), esc(r["size"]), std::to_string(r["poses"].get<int>()), esc(r["temporal"]),
            fmt::format("{:.0f}", r["set_up_triangles_per_frame"].get<double>()),
            fmt::format("{:.1f}", r["meshes_carried_per_frame"].get<double>()),
            fmt::format("{:.2f}", r["median_ms"].get<double>()),
            r.contains("frames_identical") ? std::to_string(r["frames_identical"].get<uint64_t>()) : ""};
      });
}

void writeDepthCompression(std::ostream& o, const Json& results) {
  if (!results.contains("depth_compression")) return;
  writeTableSection(
      o, "depth-compression", "Lossless depth compression",
      "The final depth buffer in 8x8 blocks, each kept as the smallest of: clear (1 byte), a plane in the stored "
      "values' bits with each value's residual packed in the fewest bits, or raw "
      "(<code>hsr/depth_compression.hpp</code>); decompressed and compared bit for bit. Traffic saved: a tiled "
      "renderer loads and stores each tile's depth once a frame, twice the buffer.",
      {"scene", "size", "format", "buffer bytes", "compressed", "ratio", "blocks clear / plane / residuals / raw",
       "traffic saved a frame", "exact"},
      results["depth_compression"], [](const Json& r) {
        return std::vector<std::string>{
            esc(r["scene"]), esc(r["size"]), esc(r["format"]), num(r["buffer_bytes"]), num(r["compressed_bytes"]),
            fmt::format("{:.1f}", r["ratio"].get<double>()),
            num(r["clear_blocks"]) + " / " + num(r["plane_blocks"]) + " / " + num(r["residual_blocks"]) + " / " +
                num(r["raw_blocks"]),
            num(r["traffic_saved_bytes"]), r["round_trip_exact"].get<bool>() ? "yes" : "no"};
      });
}

void writeShadows(std::ostream& o, const Json& results) {
  if (!results.contains("shadows")) return;
  writeTableSection(
      o, "shadows", "Shadow maps",
      "The z-buffer from the light (<code>--shadows</code>, docs/shadows.md): one map over "
      "the scene against four cascades fitted to what the view shows (the same texels), every visible pixel's verdict "
      "checked against an exact shadow ray. Wrong pixels away from edges are away from shadow and face edges at the "
      "view's pixels; unexplained ones are not at a texel edge either.",
      {"scene", "size", "method", "maps", "map size", "wrong", "away from edges", "unexplained", "ms"},
      results["shadows"], [](const Json& r) {
        return std::vector<std::string>{esc(r["scene"]),          esc(r["size"]),
                                        esc(r["method"]),         std::to_string(r["maps"].get<int>()),
                                        std::to_string(r["map_size"].get<int>()), num(r["wrong_pixels"]),
                                        num(r["wrong_away_from_edges"]), num(r["wrong_unexplained"]),
                                        fmt::format("{:.0f}", r["ms"].get<double>())};
      });
}

// Chart.js charts built from the embedded results; the page records what rendered (and any
// error) on <body> for the browser test (tests/report_check.py).
const char* kChartScript = R"JS(
const data = JSON.parse(document.getElementById('results').textContent);
const errors = [];
window.addEventListener('error', e => { errors.push(String(e.message)); document.body.dataset.errors = errors.join(' | '); });
const palette = ['#1f77b4','#d62728','#2ca02c','#ff7f0e','#9467bd','#8c564b','#e377c2','#7f7f7f','#bcbd22','#17becf','#000000','#aec7e8'];
let charts = 0;
function chart(id, title, config) {
  const box = document.createElement('div'); box.className = 'chart';
  const canvas = document.createElement('canvas'); canvas.id = id; box.appendChild(canvas);
  document.getElementById('charts').appendChild(box);
  config.options = Object.assign({animation: false, maintainAspectRatio: false, responsive: true,
    plugins: {title: {display: true, text: title}}}, config.options || {});
  new Chart(canvas, config); charts++;
}
const variants = [...new Set(data.cases.flatMap(c => c.runs.map(r => r.variant)))];
const color = v => palette[variants.indexOf(v) % palette.length];
function runsOf(group, pick) { return data.cases.filter(c => c.group.startsWith(group)).filter(pick || (() => true)); }
function linePerVariant(id, title, cases, x, xLabel, logX) {
  const datasets = variants.map(v => ({label: v, borderColor: color(v), backgroundColor: color(v),
    data: cases.map(c => { const r = c.runs.find(r => r.variant === v && !r.error); return r ? {x: x(c), y: r.median_ms} : null; })
               .filter(p => p).sort((a, b) => a.x - b.x)})).filter(d => d.data.length > 0);
  chart(id, title, {type: 'line', data: {datasets}, options: {scales: {
    x: {type: logX ? 'logarithmic' : 'linear', title: {display: true, text: xLabel}},
    y: {type: 'logarithmic', title: {display: true, text: 'median ms per frame'}}}}});
}
const report = runsOf('KTH report');
const sizes = [...new Set(report.map(c => c.width + 'x' + c.height))];
for (const s of sizes)
  linePerVariant('poly-' + s, 'Time against polygon count at ' + s + ' (KTH report)',
                 report.filter(c => c.width + 'x' + c.height === s), c => c.faces, 'polygons', true);
const few = report.filter(c => c.faces === Math.min(...report.map(c => c.faces)));
linePerVariant('res', 'Time against resolution, ' + (few[0] ? few[0].faces : '') + ' polygons (KTH report)', few,
               c => c.width * c.height, 'pixels', true);
const thesis = runsOf('KTH thesis');
for (const scene of [...new Set(thesis.map(c => c.scene))])
  linePerVariant('thesis-' + scene, 'Time against resolution: ' + scene + ' (KTH thesis)',
                 thesis.filter(c => c.scene === scene), c => c.width * c.height, 'pixels', true);
function barPerCase(id, title, cases, value, yLabel, logY) {
  const datasets = variants.map(v => ({label: v, backgroundColor: color(v),
    data: cases.map(c => { const r = c.runs.find(r => r.variant === v && !r.error); return r ? value(r) : null; })}));
  chart(id, title, {type: 'bar', data: {labels: cases.map(c => c.scene.replace('builtin:', '') + ' ' + c.width + 'x' + c.height), datasets},
    options: {scales: {y: {type: logY ? 'logarithmic' : 'linear', title: {display: true, text: yLabel}}}}});
}
barPerCase('ztests', 'z comparisons per algorithm, 800x600 (the Ukrainian paper\'s table)', runsOf('Ukrainian'),
           r => r.depth_tests || null, 'z comparisons', true);
barPerCase('ztime', 'Time per algorithm, 800x600 (the Ukrainian paper\'s table)', runsOf('Ukrainian'), r => r.median_ms, 'ms', true);
barPerCase('overdraw', 'Overdraw: colour writes per covered pixel', data.cases.filter(c => c.width * c.height <= 800 * 600),
           r => r.overdraw, 'writes per covered pixel', false);
barPerCase('wrong', 'Wrong pixels against the exact reference', data.cases.filter(c => c.width * c.height <= 800 * 600),
           r => r.wrong_pixels, 'wrong pixels', false);
const memSizes = [...new Set(data.memory.map(m => m.size))];
chart('memory', 'Depth buffer memory per format and resolution (as hsr allocates it; u24 is kept in 32 bits)', {type: 'bar',
  data: {labels: memSizes, datasets: ['u16', 'u24', 'u32', 'f32'].map((f, i) => ({label: f, backgroundColor: palette[i],
    data: memSizes.map(s => data.memory.find(m => m.size === s && m.format === f).depth_bytes_hsr / 1048576)}))},
  options: {scales: {y: {title: {display: true, text: 'MiB'}}}}});
const pc = data.precision.curves;
chart('precision-step', 'Smallest separable depth difference / eye depth (near ' + data.precision.near + ', far ' + data.precision.far + ')',
  {type: 'line', data: {datasets: pc.map((c, i) => ({label: c.format, borderColor: palette[i], backgroundColor: palette[i], pointRadius: 0,
    data: c.steps.map(s => ({x: s.eye_depth, y: s.relative_step}))}))},
   options: {scales: {x: {type: 'logarithmic', title: {display: true, text: 'eye depth'}},
                      y: {type: 'logarithmic', title: {display: true, text: 'step / depth'}}}}});
chart('precision-share', 'Share of the stored values in the first part of the depth range', {type: 'line',
  data: {datasets: pc.map((c, i) => ({label: c.format, borderColor: palette[i], backgroundColor: palette[i], pointRadius: 0,
    data: c.fractions.map(s => ({x: 100 * s.range_part, y: 100 * s.value_fraction}))}))},
  options: {scales: {x: {type: 'linear', title: {display: true, text: '% of the range from near'}},
                     y: {title: {display: true, text: '% of the values'}}}}});
if (data.zfight) {
  const formats = [...new Set(data.zfight.map(z => z.format))];
  chart('zfight', 'Z-fighting pixels against the gap between the surfaces', {type: 'line',
    data: {datasets: formats.map((f, i) => ({label: f, borderColor: palette[i], backgroundColor: palette[i],
      data: data.zfight.filter(z => z.format === f).map(z => ({x: z.gap, y: z.fighting_pixels + 1}))}))},
    options: {scales: {x: {type: 'logarithmic', reverse: true, title: {display: true, text: 'gap / eye depth'}},
                       y: {type: 'logarithmic', title: {display: true, text: 'wrong-surface pixels + 1'}}}}});
}
document.body.dataset.charts = charts;
function countImages() {
  const imgs = [...document.images];
  document.body.dataset.images = imgs.filter(i => i.complete && i.naturalWidth > 0).length + '/' + imgs.length;
}
window.addEventListener('load', countImages);
countImages();
)JS";

void copyChartJs(const std::string& dir) {
  for (const char* path : kChartJsPaths)
    if (std::filesystem::exists(path)) {
      std::ifstream in(path, std::ios::binary);
      std::stringstream text;
      text << in.rdbuf();
      writeTextFile(text.str(), dir + "/chart.min.js");
      return;
    }
  throw std::runtime_error("hsr compare: Chart.js not found (install Debian's libjs-chart.js; scripts/install-deps.sh does)");
}

}  // namespace

void writeReport(const std::string& dir, const Json& results) {
  copyChartJs(dir);
  std::ostringstream o;
  writeHead(o, results);
  o << "<p><a href=\"#claims\">claims</a> · <a href=\"#charts-h\">charts</a> · <a href=\"#table\">every run</a> · "
       "<a href=\"#details\">counters</a> · <a href=\"#pictures\">pictures</a> · <a href=\"#zfight\">z-fighting</a> · <a href=\"#rasterizers\">rasterizers</a> · <a href=\"results.json\">results.json"
       "</a></p>\n";
  writeClaims(o, results);
  o << "<h2 id=\"charts-h\">Charts</h2>\n<div id=\"charts\" class=\"charts\"></div>\n";
  writeResultsTable(o, results);
  writeDetails(o, results);
  writePictures(o, results);
  writeZfight(o, results);
  writeBothRasterizers(o, results);
  writeCoherence(o, results);
  writeDepthCompression(o, results);
  writeShadows(o, results);
  std::string embedded = results.dump();
  for (size_t p = 0; (p = embedded.find("</", p)) != std::string::npos; p += 3) embedded.replace(p, 2, "<\\/");
  o << "<script id=\"results\" type=\"application/json\">" << embedded << "</script>\n"
    << "<script src=\"chart.min.js\"></script>\n<script>" << kChartScript << "</script>\n</body></html>\n";
  writeTextFile(o.str(), dir + "/index.html");
}

}  // namespace hsr::cli

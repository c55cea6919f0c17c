// The source documents' claims, each measured on the study's results and given a verdict:
// holds, does not hold, or holds only when a stated condition does (docs/compare.md).
#include "study.hpp"

#include <fmt/core.h>

#include <cmath>
#include <optional>

namespace hsr::cli {

const Json* runIn(const Json& c, const std::string& variant) {
  for (const Json& r : c["runs"])
    if (r["variant"] == variant && !r.contains("error")) return &r;
  return nullptr;
}

std::string caseName(const Json& c) {
  return fmt::format("{} {}x{}", c["scene"].get<std::string>(), c["width"].get<int>(), c["height"].get<int>());
}

namespace {

// The run of `variant` on the case of `scene` at `width` x `height`, if it ran without error.
const Json* findRun(const Json& results, const std::string& scene, int width, int height, const std::string& variant) {
  for (const Json& c : results["cases"])
    if (c["scene"] == scene && c["width"] == width && c["height"] == height)
      for (const Json& r : c["runs"])
        if (r["variant"] == variant && !r.contains("error")) return &r;
  return nullptr;
}

// Every case of a group, by its scene and size.
std::vector<const Json*> casesOfGroup(const Json& results, const std::string& prefix) {
  std::vector<const Json*> out;
  for (const Json& c : results["cases"])
    if (c["group"].get<std::string>().rfind(prefix, 0) == 0) out.push_back(&c);
  return out;
}


double excessWrites(const Json& run) {
  return double(run["color_writes"].get<uint64_t>()) - double(run["covered_pixels"].get<uint64_t>());
}

Json claim(const std::string& text, const std::string& source, const std::string& measured, const std::string& verdict) {
  return {{"claim", text}, {"source", source}, {"measured", measured}, {"verdict", verdict}};
}

Json notMeasured(const std::string& text, const std::string& source, const std::string& why) {
  return claim(text, source, why, "not measured");
}


// KTH thesis: on unsorted input the z-buffer overdraws about 50 % less than the painter's.
Json overdrawClaim(const Json& results) {
  const char* text = "Unsorted input: the z-buffer overdraws about 50 % less than the painter's";
  std::string measured;
  int about = 0, total = 0;
  for (const Json* c : casesOfGroup(results, "KTH thesis")) {
    const Json *z = runIn(*c, "zbuffer raster=binned"), *p = runIn(*c, "painter");
    if (!z || !p || excessWrites(*p) <= 0) continue;
    const double less = 1 - excessWrites(*z) / excessWrites(*p);
    measured += fmt::format("{}{}: {:.0f} % less", measured.empty() ? "" : "; ", caseName(*c), 100 * less);
    total += 1;
    about += less >= 0.35 && less <= 0.65;
  }
  if (total == 0) return notMeasured(text, "KTH thesis", "needs zbuffer raster=binned and painter on the KTH thesis cases");
  measured += " (overdraw = colour writes beyond one per covered pixel)";
  return claim(text, "KTH thesis", measured,
               about == total ? "holds" : about == 0 ? "does not hold" : "holds only on some scenes");
}

// KTH report and thesis: sorting front to back before the z-buffer never overdraws, but is
// slower than the plain z-buffer.
Json combinationClaims(const Json& results, Json& out) {
  uint64_t extra = 0;
  int slower = 0, total = 0;
  std::string times;
  for (const Json& c : results["cases"]) {
    const Json *s = runIn(c, "sorted-zbuffer"), *z = runIn(c, "zbuffer raster=binned");
    if (!s || !z) continue;
    ++total;
    extra += uint64_t(std::max(0.0, excessWrites(*s)));
    const double ratio = (*s)["median_ms"].get<double>() / (*z)["median_ms"].get<double>();
    slower += ratio > 1;
    if (times.size() < 400) times += fmt::format("{}{}: {:.2f}x", times.empty() ? "" : "; ", caseName(c), ratio);
  }
  if (total == 0) return out;
  out.push_back(claim("Sorting front to back before the z-buffer: a pixel is never painted over", "KTH report, KTH thesis",
                      fmt::format("{} colour writes beyond one per covered pixel over {} cases", extra, total),
                      extra == 0 ? "holds" : "holds only when one sort key orders every pixel (intersecting or "
                                             "cyclic faces are painted over)"));
  out.push_back(claim("The combination is slower than the plain z-buffer (the sort must finish first)",
                      "KTH report, KTH thesis", "time of sorted-zbuffer / zbuffer on the same rasterizer: " + times,
                      slower == total ? "holds" : slower == 0 ? "does not hold" : "holds only on some scenes"));
  return out;
}

// KTH report: the painter's suffers with polygon count, the z-buffer with resolution.
Json scalingClaim(const Json& results) {
  const char* text = "The painter's algorithm suffers with polygon count, the z-buffer with resolution";
  const std::string few = "builtin:random?n=50";
  std::string many;
  for (const Json* c : casesOfGroup(results, "KTH report"))
    if ((*c)["scene"] != few) many = (*c)["scene"];
  std::vector<int> widths;
  for (const Json* c : casesOfGroup(results, "KTH report")) widths.push_back((*c)["width"].get<int>());
  if (many.empty() || widths.empty()) return notMeasured(text, "KTH report", "needs the KTH report cases");
  const auto [lo, hi] = std::minmax_element(widths.begin(), widths.end());
  int loH = 0, hiH = 0;
  for (const Json* c : casesOfGroup(results, "KTH report")) {
    if ((*c)["width"] == *lo) loH = (*c)["height"];
    if ((*c)["width"] == *hi) hiH = (*c)["height"];
  }
  auto ms = [&](const std::string& scene, int w, int h, const char* v) -> std::optional<double> {
    const Json* r = findRun(results, scene, w, h, v);
    return r ? std::optional((*r)["median_ms"].get<double>()) : std::nullopt;
  };
  const auto pf = ms(few, *lo, loH, "painter"), pm = ms(many, *lo, loH, "painter");
  const auto zf = ms(few, *lo, loH, "zbuffer raster=binned"), zm = ms(many, *lo, loH, "zbuffer raster=binned");
  const auto pl = ms(few, *hi, hiH, "painter"), zl = ms(few, *hi, hiH, "zbuffer raster=binned");
  if (!pf || !pm || !zf || !zm || !pl || !zl) return notMeasured(text, "KTH report", "needs painter and zbuffer raster=binned");
  const double pPoly = *pm / *pf, zPoly = *zm / *zf, pRes = *pl / *pf, zRes = *zl / *zf;
  const std::string measured = fmt::format(
      "more polygons ({} -> {}, at {}x{}): painter {:.1f}x slower, z-buffer {:.1f}x; higher resolution ({}x{} -> {}x{}, "
      "50 polygons): painter {:.1f}x slower, z-buffer {:.1f}x (same rasterizer)",
      few.substr(8), many.substr(8), *lo, loH, pPoly, zPoly, *lo, loH, *hi, hiH, pRes, zRes);
  const bool polygons = pPoly > zPoly, resolution = zRes > pRes;
  return claim(text, "KTH report", measured,
               polygons && resolution ? "holds"
               : polygons             ? "holds for polygon count only"
               : resolution           ? "holds for resolution only"
                                      : "does not hold");
}

// Java chapter: a z-buffer is 2-3x slower than plain filling when every pixel is tested.
Json fillClaim(const Json& results) {
  const char* text = "A z-buffer is 2-3x slower than plain filling when every pixel is tested";
  std::string measured;
  int inRange = 0, total = 0;
  for (const Json& c : results["cases"]) {
    if (c["scene"].get<std::string>().rfind("builtin:layers", 0) != 0) continue;
    const Json *z = runIn(c, "zbuffer raster=binned"), *p = runIn(c, "painter");
    if (!z || !p || !(*z)["stages_ms"].contains("raster") || !(*p)["stages_ms"].contains("raster")) continue;
    const double ratio = (*z)["stages_ms"]["raster"].get<double>() / (*p)["stages_ms"]["raster"].get<double>();
    measured += fmt::format("{}{}: {:.2f}x", measured.empty() ? "" : "; ", caseName(c), ratio);
    ++total;
    inRange += ratio >= 2 && ratio <= 3;
  }
  if (total == 0) return notMeasured(text, "Java chapter", "needs zbuffer raster=binned and painter on builtin:layers");
  measured = "drawing time, depth-tested / overwriting, same rasterizer and order of work: " + measured;
  return claim(text, "Java chapter", measured, inRange == total ? "holds" : inRange == 0 ? "does not hold" : "holds on some scenes");
}

// Ukrainian paper: midpoint subdivision makes 0.62 of the hierarchical z-buffer's z comparisons
// in 0.89 of its time (800x600, two initial splits).
Json midpointClaim(const Json& results) {
  const char* text = "Midpoint subdivision: about 40 % fewer z comparisons and 10 % less time than the hierarchical z-buffer";
  std::string measured;
  int fewer = 0, total = 0;
  for (const Json* c : casesOfGroup(results, "Ukrainian paper")) {
    const Json *m = runIn(*c, "midpoint"), *h = runIn(*c, "hzb");
    if (!m || !h || (*h)["depth_tests"].get<uint64_t>() == 0) continue;
    const double tests = double((*m)["depth_tests"].get<uint64_t>()) / double((*h)["depth_tests"].get<uint64_t>());
    const double time = (*m)["median_ms"].get<double>() / (*h)["median_ms"].get<double>();
    measured += fmt::format("{}{}: {:.2f} of the comparisons, {:.2f} of the time, {} wrong pixels", measured.empty() ? "" : "; ",
                            caseName(*c), tests, time, (*m)["wrong_pixels"].get<uint64_t>());
    ++total;
    fewer += tests < 1 && time < 1;
  }
  if (total == 0) return notMeasured(text, "Ukrainian paper", "needs the hzb and midpoint algorithms (not registered in this build)");
  return claim(text, "Ukrainian paper", measured + " (paper: 0.62 and 0.89)",
               fewer == total ? "holds" : fewer == 0 ? "does not hold" : "holds on some scenes");
}

// Java chapter: the reverse painter's never draws a pixel twice.
Json reversePainterClaim(const Json& results) {
  uint64_t extra = 0;
  int total = 0;
  for (const Json& c : results["cases"])
    if (const Json* r = runIn(c, "reverse-painter")) {
      extra += uint64_t(std::max(0.0, excessWrites(*r)));
      ++total;
    }
  if (total == 0) return Json();
  return claim("The reverse painter's algorithm never draws a pixel twice", "Java chapter",
               fmt::format("{} colour writes beyond one per covered pixel over {} cases", extra, total),
               extra == 0 ? "holds" : "does not hold");
}

// KTH report and thesis: the painter's fails on its failure figures; splitting (BSP) fixes it.
Json failureClaim(const Json& results) {
  std::string measured;
  bool painterFails = true, bspExact = true;
  int total = 0;
  for (const Json* c : casesOfGroup(results, "The painter's failures")) {
    const Json *p = runIn(*c, "painter"), *b = runIn(*c, "bsp");
    if (!p || !b) continue;
    ++total;
    painterFails &= (*p)["wrong_pixels"].get<uint64_t>() > 0;
    bspExact &= (*b)["wrong_pixels"].get<uint64_t>() == 0;
    measured += fmt::format("{}{}: painter {} wrong pixels, bsp {}", measured.empty() ? "" : "; ", (*c)["scene"].get<std::string>(),
                            (*p)["wrong_pixels"].get<uint64_t>(), (*b)["wrong_pixels"].get<uint64_t>());
  }
  if (total == 0) return Json();
  return claim("One depth per polygon misorders a long tilted polygon, cyclic overlaps and interpenetration; "
               "splitting by planes (a BSP tree) orders them right", "KTH report, KTH thesis", measured,
               painterFails && bspExact ? "holds" : "does not hold");
}

// KTH thesis: z-fighting, mitigated by rendering the depth range in smaller parts.
Json zfightClaim(const Json& results) {
  const char* text = "Z-fighting where precision is insufficient; rendering the depth range in smaller parts mitigates it";
  if (!results.contains("zfight")) return notMeasured(text, "KTH thesis", "the z-fighting experiment did not run");
  std::string measured;
  bool fights = false, mitigated = true;
  for (const Json& once : results["zfight"]) {
    if (once["format"] != "u16:z") continue;
    const uint64_t a = once["fighting_pixels"];
    fights |= a > 0;
    measured += fmt::format("{}gap {:g}: {} px at once ({:.1f} ms)", measured.empty() ? "" : "; ", once["gap"].get<double>(), a,
                            once["ms"].get<double>());
    for (const Json& parts : results["zfight"])
      if (parts["gap"] == once["gap"] && parts["depth_slices"].get<int>() > 1 &&
          parts["format"].get<std::string>().rfind("u16:z", 0) == 0) {
        const uint64_t b = parts["fighting_pixels"];
        mitigated &= b <= a;
        measured += fmt::format(", {} in {} parts ({:.1f} ms)", b, parts["depth_slices"].get<int>(), parts["ms"].get<double>());
      }
  }
  return claim(text, "KTH thesis", "u16:z, pixels showing the wrong surface: " + measured,
               fights && mitigated ? "holds" : "does not hold");
}

// Ukrainian paper: temporal coherence among the z-buffer's improvements.
Json coherenceClaim(const Json& results) {
  const char* text = "Temporal coherence: the previous frame's visible objects drawn first as occluders let occlusion "
                     "culling set up fewer triangles, with the same image";
  if (!results.contains("coherence")) return notMeasured(text, "Ukrainian paper", "the coherence experiment did not run");
  std::string measured;
  bool fewer = true, same = true;
  const Json& rows = results["coherence"];
  for (size_t i = 0; i + 1 < rows.size(); i += 2) {
    const Json &off = rows[i], &on = rows[i + 1];
    const double a = off["set_up_triangles_per_frame"], b = on["set_up_triangles_per_frame"];
    fewer &= b < a;
    same &= on["frames_identical"] == on["poses"];
    measured += fmt::format("{}{} {}, {} poses: {:.0f} triangles set up a frame without, {:.0f} with ({:.1f} and {:.1f} "
                            "ms); {} of {} frames identical",
                            measured.empty() ? "" : "; ", on["scene"].get<std::string>(), on["size"].get<std::string>(),
                            on["poses"].get<int>(), a, b, off["median_ms"].get<double>(), on["median_ms"].get<double>(),
                            on["frames_identical"].get<uint64_t>(), on["poses"].get<int>());
  }
  return claim(text, "Ukrainian paper", "zbuffer-culled temporal=off/on over an orbit: " + measured,
               !same ? "does not hold" : fewer ? "holds" : "holds only in part (the same image, not fewer triangles)");
}

// Ukrainian paper: lossless z-buffer compression among the z-buffer's improvements.
Json compressionClaim(const Json& results) {
  const char* text = "Lossless z-buffer compression saves memory and bandwidth";
  if (!results.contains("depth_compression"))
    return notMeasured(text, "Ukrainian paper", "the compression experiment did not run");
  std::string measured;
  bool exact = true, smaller = true;
  for (const Json& r : results["depth_compression"]) {
    exact &= r["round_trip_exact"].get<bool>();
    smaller &= r["ratio"].get<double>() > 1;
    measured += fmt::format("{}{} {}: {:.1f}x", measured.empty() ? "" : "; ", r["scene"].get<std::string>(),
                            r["format"].get<std::string>(), r["ratio"].get<double>());
  }
  return claim(text, "Ukrainian paper",
               "8x8 blocks clear, a plane with packed residuals, or raw; the final buffer against its allocation, "
               "round trips bit for bit: " + measured,
               !exact ? "does not hold" : smaller ? "holds" : "holds only in part (some buffers do not shrink)");
}

// KTH report: shadows as one of the z-buffer's other uses (a depth buffer from the light).
Json shadowClaim(const Json& results) {
  const char* text = "Shadows by the z-buffer: a point is in shadow when the light's depth buffer holds something "
                     "nearer the light";
  if (!results.contains("shadows")) return notMeasured(text, "KTH report", "the shadow experiment did not run");
  std::string measured;
  bool explained = true;
  for (const Json& r : results["shadows"]) {
    explained &= r["wrong_unexplained"].get<uint64_t>() == 0;
    measured += fmt::format("{}{} {}, {} x {}: {} wrong, {} away from edges, {} unexplained",
                            measured.empty() ? "" : "; ", r["scene"].get<std::string>(), r["size"].get<std::string>(),
                            r["maps"].get<int>(), r["map_size"].get<int>(), r["wrong_pixels"].get<uint64_t>(),
                            r["wrong_away_from_edges"].get<uint64_t>(), r["wrong_unexplained"].get<uint64_t>());
  }
  return claim(text, "KTH report", "each pixel's verdict against an exact shadow ray: " + measured,
               explained ? "holds only at the map's resolution (every wrong pixel at a shadow, face or texel edge)"
                         : "does not hold");
}

// The bytes of the buffers a real frame of `scene` at w x h uses for the figure: the textbook
// z-buffer's depth buffer in `depthFormat` (if any) and the frame's colour (if asked), as its
// statistics name them (docs/memory.md).
uint64_t frameBufferBytes(const Scene& scene, int w, int h, const char* depthFormat, bool colour) {
  RenderOptions options;
  options.params = {{"raster", "halfspace"}};
  options.depthFormat = DepthFormat::parse(depthFormat ? depthFormat : "u24:z");
  options.outputs = colour ? FrameOutputs::Color : FrameOutputs::DepthOnly;
  options.threads = 1;
  const Frame frame = render(scene, resolveCamera(frameBounds(scene.bounds()), w, h, scene.bounds()), options);
  uint64_t bytes = 0;
  for (const auto& [name, n] : frame.stats.memory)
    if ((depthFormat && name == "depth_buffer") || (colour && name == "frame.color")) bytes += n;
  return bytes;
}

// The documents' memory figures: computed as they count (packed bits), and read off real frames.
void memoryClaims(Json& out) {
  struct Figure {
    const char* text;
    const char* source;
    int w, h;
    double bytesPerPixel, claimedMB;
    const char* depthFormat;  // the depth buffer counted, if any
    bool colour;              // the 32-bit colour buffer counted
  };
  const Figure figures[] = {
      {"1366x768 with a 32-bit framebuffer: about 4 MB", "KTH report", 1366, 768, 4, 4, nullptr, true},
      {"1366x768 with a 24-bit z-buffer: about 3 MB", "KTH report", 1366, 768, 3, 3, "u24:z", false},
      {"640x480 with 24-bit colour and depth buffers: 1.6 MB", "KTH report", 640, 480, 6, 1.6, "u24:z", true},
      {"1920x1080 with 24-bit colour and depth buffers: about 12 MB", "KTH report", 1920, 1080, 6, 12, "u24:z", true},
      {"1920x1080: about 8 MB of 32-bit colour", "KTH thesis", 1920, 1080, 4, 8, nullptr, true},
      {"1920x1080: about 4 MB of 16-bit depth", "KTH thesis", 1920, 1080, 2, 4, "u16:z", false},
      {"1920x1080: about 6 MB of 24-bit depth", "KTH thesis", 1920, 1080, 3, 6, "u24:z", false},
      {"8 bytes per pixel (32-bit colour and z): 6 MB at 1024x768", "lecture notes", 1024, 768, 8, 6, "u32:z", true},
      {"A 16-bit z-buffer at 1024x768: 1.5 MB", "Java chapter", 1024, 768, 2, 1.5, "u16:z", false},
  };
  const Scene scene = loadScene("builtin:cubes");
  for (const Figure& f : figures) {
    const double bytes = double(f.w) * f.h * f.bytesPerPixel;
    const double mb = bytes / 1e6, mib = bytes / (1 << 20);
    // Documents round, and mean 10^6 or 2^20 bytes: within 5 % of either holds.
    const bool holds = std::abs(mb - f.claimedMB) <= 0.05 * f.claimedMB || std::abs(mib - f.claimedMB) <= 0.05 * f.claimedMB;
    const uint64_t real = frameBufferBytes(scene, f.w, f.h, f.depthFormat, f.colour);
    Json c = claim(f.text, f.source,
                   fmt::format("{:.0f} bytes = {:.2f} MB = {:.2f} MiB as counted; hsr's {} in a real frame: {} bytes = "
                               "{:.2f} MiB",
                               bytes, mb, mib,
                               f.depthFormat && f.colour ? "depth buffer and colour"
                               : f.depthFormat           ? "depth buffer"
                                                         : "colour buffer",
                               real, double(real) / (1 << 20)),
                   holds ? "holds" : "does not hold");
    c["frame_bytes"] = real;
    out.push_back(c);
  }
}

}  // namespace

Json precisionClaims() {
  struct Claimed {
    double ratio, part, share;
  };
  Json out = Json::array();
  for (const Claimed c : {Claimed{100, 0.10, 0.90}, Claimed{1000, 0.02, 0.98}}) {
    const DepthPrecision p{DepthFormat::parse("u24:z"), 1.0, c.ratio};
    const double share = p.valueFraction(c.part);
    out.push_back(claim(fmt::format("far/near = {:g}: {:g} % of the depth values lie in the first {:g} % of the depth range",
                                    c.ratio, 100 * c.share, 100 * c.part),
                        "KTH thesis", fmt::format("{:.2f} % (u24:z, exact count of stored values)", 100 * share),
                        std::abs(share - c.share) <= 0.01 ? "holds" : share > c.share ? "holds (more than claimed)"
                                                                                      : "does not hold"));
    out.back()["value"] = share;
  }
  return out;
}

Json evaluateClaims(const Json& results) {
  Json out = Json::array();
  out.push_back(overdrawClaim(results));
  combinationClaims(results, out);
  out.push_back(scalingClaim(results));
  out.push_back(fillClaim(results));
  out.push_back(midpointClaim(results));
  for (Json c : {reversePainterClaim(results), failureClaim(results)})
    if (!c.is_null()) out.push_back(c);
  out.push_back(zfightClaim(results));
  out.push_back(coherenceClaim(results));
  out.push_back(compressionClaim(results));
  out.push_back(shadowClaim(results));
  memoryClaims(out);
  for (const Json& c : precisionClaims()) out.push_back(c);
  return out;
}

}  // namespace hsr::cli

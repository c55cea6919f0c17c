// The study's experiments beyond scene x algorithm: z-fighting per depth format, temporal
// coherence over an orbit, lossless depth compression, shadow maps, the memory of the buffers,
// and depth precision curves (study.hpp).
#include "study.hpp"

#include "../commands.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

namespace hsr::cli {

namespace {

// A depth format, and the number of parts the depth range is drawn in (1: at once).
struct ZfightSetting {
  const char* format;
  int slices;
};
const ZfightSetting kZfightSettings[] = {{"u16:z", 1}, {"u24:z", 1}, {"u32:z", 1}, {"f32:z", 1}, {"f32:reversed", 1},
                                         {"u16:inv", 1}, {"u24:linear", 1}, {"u16:z", 4}, {"u16:z", 16}};

}  // namespace

Json zfightExperiment(const StudySettings& settings, bool quick) {
  const int w = quick ? 160 : 480, h = quick ? 120 : 360;
  Json rows = Json::array();
  std::filesystem::create_directories(settings.outDir + "/img/zfight");
  for (const char* gap : {"1e-2", "1e-3", "1e-4", "1e-5"}) {
    const std::string name = std::string("builtin:zfight?gap=") + gap;
    Scene scene = loadScene(name);
    const CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
    const Camera camera = resolveCamera(spec, w, h, scene.bounds(), name);
    RenderOptions ref;
    ref.algorithm = "raycast";
    ref.threads = settings.threads;
    const Frame reference = render(scene, camera, ref);
    for (const ZfightSetting& z : kZfightSettings) {
      if (settings.interrupted && settings.interrupted->load()) return rows;
      RenderOptions options;
      options.depthFormat = DepthFormat::parse(z.format);
      options.threads = settings.threads;
      if (z.slices > 1) {
        options.algorithm = "zbuffer-sliced";
        options.params = {{"raster", "binned"}, {"slices", std::to_string(z.slices)}};
      }
      const auto start = std::chrono::steady_clock::now();
      const Frame frame = render(scene, camera, options);
      const double ms = millisecondsSince(start);
      uint64_t fighting = 0;
      for (size_t i = 0; i < frame.faceId.size(); ++i) fighting += frame.faceId[i] != reference.faceId[i];
      const std::string label = z.slices > 1 ? fmt::format("{} in {} parts", z.format, z.slices) : z.format;
      std::string file = fmt::format("img/zfight/gap{}-{}-{}.png", gap, z.format, z.slices);
      std::replace(file.begin(), file.end(), ':', '_');
      writeColorPng(frame, settings.outDir + "/" + file);
      rows.push_back({{"gap", std::stod(gap)}, {"format", label}, {"depth_slices", z.slices},
                      {"fighting_pixels", fighting}, {"covered_pixels", frame.stats.covered_pixels}, {"ms", ms},
                      {"image", file}});
    }
  }
  return rows;
}

Json coherenceExperiment(const StudySettings& settings, bool quick) {
  const int w = quick ? 160 : 640, h = quick ? 120 : 480, poses = quick ? 6 : 48;
  Json rows = Json::array();
  for (const char* name : {"builtin:city"}) {
    const Scene scene = loadScene(name);
    const CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
    const Camera camera = resolveCamera(spec, w, h, scene.bounds(), name);
    const std::vector<Camera> orbit = orbitCameras(camera, scene.bounds().center(), poses);
    std::vector<FrameBuffer<int32_t>> ids;  // temporal=off's face ids per pose, to compare with on's
    for (const char* temporal : {"off", "on"}) {
      if (settings.interrupted && settings.interrupted->load()) return rows;
      RenderOptions options;
      options.algorithm = "zbuffer-culled";
      options.params = {{"temporal", temporal}};
      options.threads = settings.threads;
      Renderer renderer(scene, options);  // one object over the whole orbit: the last frame's meshes are kept
      Frame frame;
      std::vector<double> ms;
      uint64_t setUp = 0, carried = 0, same = 0;
      for (size_t i = 0; i < orbit.size(); ++i) {
        const auto start = std::chrono::steady_clock::now();
        renderer.render(orbit[i], frame);
        ms.push_back(millisecondsSince(start));
        const Stats& st = frame.stats;
        setUp += st.triangles - st.culled_frustum - st.culled_occlusion;
        if (auto c = st.detailCount("objects_carried")) carried += *c;
        if (std::string(temporal) == "off") ids.push_back(frame.faceId);
        else same += frame.faceId == ids[i];
      }
      std::sort(ms.begin(), ms.end());
      Json row = {{"scene", name}, {"size", fmt::format("{}x{}", w, h)}, {"poses", poses}, {"temporal", temporal},
                  {"set_up_triangles_per_frame", double(setUp) / double(poses)}, {"median_ms", ms[ms.size() / 2]},
                  {"meshes_carried_per_frame", double(carried) / double(poses)}};
      if (std::string(temporal) == "on") row["frames_identical"] = same;
      rows.push_back(row);
    }
  }
  return rows;
}

Json depthCompressionExperiment(const StudySettings& settings, bool quick) {
  const int w = quick ? 160 : 1920, h = quick ? 120 : 1080;
  Json rows = Json::array();
  for (const char* name : {"builtin:city", "builtin:sphere", "builtin:random?n=5000", "builtin:layers?n=64&order=random",
                           "builtin:clutter"}) {
    const Scene scene = loadScene(name);
    const CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
    const Camera camera = resolveCamera(spec, w, h, scene.bounds(), name);
    for (const char* formatName : {"u16:z", "u24:z", "f32:reversed"}) {
      if (settings.interrupted && settings.interrupted->load()) return rows;
      const DepthFormat format = DepthFormat::parse(formatName);
      OcclusionBuffer buffer;
      OcclusionOptions options;
      options.depthFormat = format;
      options.threads = settings.threads;
      buffer.render(scene, camera, options);
      const std::vector<uint32_t> words = storedDepthWords(buffer, format);
      const auto start = std::chrono::steady_clock::now();
      const CompressedDepth c = compressDepth(words, w, h, clearDepthWord(format));
      const double ms = millisecondsSince(start);
      const bool exact = decompressDepth(c) == words;
      // As allocated (u16 in 2 bytes, u24 and 32-bit formats in 4): what the compressed bytes replace.
      const uint64_t allocated = uint64_t(w) * uint64_t(h) * uint64_t(format.bytesPerPixel());
      rows.push_back({{"scene", name}, {"size", fmt::format("{}x{}", w, h)}, {"format", formatName},
                      {"buffer_bytes", allocated}, {"compressed_bytes", c.bytes.size()},
                      {"ratio", double(allocated) / double(c.bytes.size())}, {"clear_blocks", c.clearBlocks},
                      {"plane_blocks", c.planeBlocks}, {"residual_blocks", c.residualBlocks},
                      {"raw_blocks", c.rawBlocks}, {"compress_ms", ms}, {"round_trip_exact", exact},
                      // A tiled renderer loads and stores each tile's depth once a frame: twice the buffer.
                      {"traffic_saved_bytes", 2 * (int64_t(allocated) - int64_t(c.bytes.size()))}});
    }
  }
  return rows;
}

Json shadowExperiment(const StudySettings& settings, bool quick) {
  const int w = quick ? 320 : 1920, h = quick ? 180 : 1080;
  struct Way {
    ShadowMethod method;
    int cascades, mapSize;
  };
  const Way ways[] = {{ShadowMethod::Single, 1, 4096}, {ShadowMethod::Cascaded, 4, 2048}};
  Json rows = Json::array();
  for (const auto& [name, direction] : {std::pair{"builtin:city", dvec3(0.6, -1, 0.4)},
                                        std::pair{"builtin:clutter", dvec3(-0.4, -1, 0.3)}}) {
    const Scene scene = loadScene(name);
    const CameraSpec spec = scene.camera ? *scene.camera : frameBounds(scene.bounds());
    const Camera camera = resolveCamera(spec, w, h, scene.bounds(), name);
    RenderOptions options;
    options.threads = settings.threads;
    options.outputs = FrameOutputs::FaceIds | FrameOutputs::TriangleIds;
    const Frame view = render(scene, camera, options);
    Light light;
    light.kind = Light::Kind::Directional;
    light.vector = direction;
    for (const Way& way : ways) {
      if (settings.interrupted && settings.interrupted->load()) return rows;
      ShadowOptions shadow;
      shadow.method = way.method;
      shadow.cascades = way.cascades;
      shadow.mapSize = way.mapSize;
      shadow.threads = settings.threads;
      Frame frame = view;
      const auto start = std::chrono::steady_clock::now();
      const ShadowComparison c = addShadows(scene, camera, frame, light, shadow, /*verify=*/true);
      rows.push_back({{"scene", name}, {"size", fmt::format("{}x{}", w, h)},
                      {"method", shadowMethodName(way.method)}, {"maps", way.cascades}, {"map_size", way.mapSize},
                      {"wrong_pixels", c.wrong}, {"wrong_away_from_edges", c.wrongAwayFromEdges},
                      {"wrong_unexplained", c.wrongUnexplained}, {"ms", millisecondsSince(start)}});
    }
  }
  return rows;
}

Json memoryTable() {
  Json rows = Json::array();
  for (const auto& [w, h] : {std::pair{640, 480}, std::pair{1024, 768}, std::pair{1366, 768}, std::pair{1920, 1080}})
    for (const char* storage : {"u16", "u24", "u32", "f32"}) {
      const DepthFormat f = DepthFormat::parse(storage);
      const uint64_t pixels = uint64_t(w) * uint64_t(h);
      rows.push_back({{"size", fmt::format("{}x{}", w, h)},
                      {"pixels", pixels},
                      {"format", storage},
                      {"depth_bits", f.bits()},
                      {"depth_bytes_packed", pixels * uint64_t(f.bits()) / 8},  // as the documents count
                      {"depth_bytes_hsr", pixels * uint64_t(f.bytesPerPixel())},  // as hsr allocates it
                      {"color_bytes", pixels * 4},
                      {"face_id_bytes", pixels * 4}});
    }
  return rows;
}

Json precisionCurves(double near, double far) {
  Json curves = Json::array();
  const char* formats[] = {"u16:z", "u24:z", "u32:z", "f32:z", "f32:reversed", "u16:inv", "u24:linear"};
  for (const char* name : formats) {
    const DepthPrecision p{DepthFormat::parse(name), near, far};
    Json steps = Json::array(), fractions = Json::array();
    constexpr int kPoints = 48;
    for (int i = 0; i <= kPoints; ++i) {
      const double d = near * std::pow(far / near, double(i) / kPoints);  // log-spaced eye depths
      steps.push_back({{"eye_depth", d}, {"relative_step", p.step(d) / d}});
      const double x = double(i) / kPoints;
      fractions.push_back({{"range_part", x}, {"value_fraction", p.valueFraction(x)}});
    }
    curves.push_back({{"format", name}, {"steps", steps}, {"fractions", fractions}});
  }
  return {{"near", near}, {"far", far}, {"curves", curves}};
}

}  // namespace hsr::cli

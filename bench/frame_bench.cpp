// Micro benchmarks of the parts of a z-buffer frame at 1920x1080: the front end (set-up), the
// binning, the tile pass per depth format, whole frames tiled vs the scalar reference, and the
// occlusion buffer's box queries.
// Google Benchmark; the context records the kernel's instruction set, tile size and threads.
// Run: build/bench/hsr_bench --benchmark_filter=Frame  (whole frames also via `hsr bench`).
#include <benchmark/benchmark.h>

#include <hsr/hsr.hpp>
#include <hsr/threads.hpp>
#include <map>
#include <memory>
#include <string>

#include "frontend/frontend.hpp"
#include "raster/tiled.hpp"

namespace hsr {
namespace {

constexpr int kWidth = 1920, kHeight = 1080;

struct Prepared {
  Scene scene;
  Camera camera;
  FrontEndOutput fe;
};

// Scenes are generated, framed and set up once per process.
const Prepared& prepared(const std::string& name) {
  static std::map<std::string, Prepared> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  Prepared& p = cache[name];
  p.scene = loadScene("builtin:" + name);
  p.camera = resolveCamera(p.scene.camera ? *p.scene.camera : frameBounds(p.scene.bounds()), kWidth, kHeight,
                           p.scene.bounds());
  const DepthSetup depth{DepthFormat{}, p.camera.near, p.camera.far, p.camera.orthographic};
  runFrontEnd(p.scene, p.camera, RenderOptions{}, p.fe, {}, {.nearestFor = &depth});
  return p;
}

const char* kScenes[] = {"sphere", "city", "random?n=10000", "layers?n=64", "cubes"};
const char* kFormats[] = {"u16:z", "u16:reversed", "u16:inv", "u16:linear", "u24:z", "u24:reversed",
                          "u24:inv", "u24:linear", "u32:z", "u32:reversed", "u32:inv", "u32:linear",
                          "f32:z", "f32:reversed", "f32:inv", "f32:linear"};

void BM_FrontEnd(benchmark::State& state) {
  const Prepared& p = prepared(kScenes[state.range(0)]);
  const DepthSetup depth{DepthFormat{}, p.camera.near, p.camera.far, p.camera.orthographic};
  FrontEndOutput fe;
  for (auto _ : state) {
    runFrontEnd(p.scene, p.camera, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    benchmark::DoNotOptimize(fe.chunks.data());
  }
  state.SetLabel(kScenes[state.range(0)]);
  state.counters["triangles"] = double(fe.triangleCount());
  state.counters["empty"] = double(fe.empty);  // dropped: covering no pixel centre
}
BENCHMARK(BM_FrontEnd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Binning alone (per-tile lists of a front end's output), chunk after chunk on one thread.
void binAll(const FrontEndOutput& fe, tiled::Bins& bins) {
  tiled::prepareBins(bins, kWidth, kHeight, fe.chunkCount);
  for (size_t c = 0; c < fe.chunkCount; ++c) tiled::binChunk(bins, c, fe.chunks[c]);
}

void BM_Bin(benchmark::State& state) {
  const Prepared& p = prepared(kScenes[state.range(0)]);
  tiled::Bins bins;
  for (auto _ : state) {
    binAll(p.fe, bins);
    benchmark::DoNotOptimize(bins.chunks.data());
  }
  size_t entries = 0;
  for (int t = 0; t < bins.tileCount(); ++t) entries += bins.entries(t);
  state.SetLabel(kScenes[state.range(0)]);
  state.counters["entries"] = double(entries);
}
BENCHMARK(BM_Bin)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The tile pass alone (no resolve), one thread, for scene range(0) and format range(1).
void BM_RasterTiles(benchmark::State& state) {
  const Prepared& p = prepared(kScenes[state.range(0)]);
  const DepthSetup depth{DepthFormat::parse(kFormats[state.range(1)]), p.camera.near, p.camera.far,
                         p.camera.orthographic};
  FrontEndOutput fe;  // the nearest bounds are the format's
  runFrontEnd(p.scene, p.camera, RenderOptions{}, fe, {}, {.nearestFor = &depth});
  tiled::Bins bins;
  binAll(fe, bins);
  auto scratch = std::make_unique<tiled::TileScratch>();
  tiled::TileOrder order;
  tiled::RasterCounters counters;
  for (auto _ : state) {
    counters = {};
    for (int tile = 0; tile < bins.tileCount(); ++tile)
      if (bins.entries(tile)) tiled::rasterizeTile(bins, tile, depth, true, *scratch, order, counters);
  }
  state.SetLabel(std::string(kScenes[state.range(0)]) + " " + kFormats[state.range(1)]);
  state.counters["tests"] = double(counters.depthTests);
  state.counters["writes"] = double(counters.depthWrites);
  state.counters["culled_tiles"] = double(counters.culledTiles);
  state.counters["blocks_full"] = double(counters.blocksFull);
  state.counters["blocks_partial"] = double(counters.blocksPartial);
  state.counters["blocks_culled"] = double(counters.blocksCulled);
  state.counters["tiles_whole"] = double(counters.tilesWhole);
  state.counters["blocks_whole"] = double(counters.blocksWhole);
}
BENCHMARK(BM_RasterTiles)
    ->ArgsProduct({{0, 1, 2, 3, 4}, benchmark::CreateDenseRange(0, 15, 1)})
    ->Unit(benchmark::kMillisecond);

// Whole frames through render(): scene range(0), raster range(1) (0 tiled, 1 halfspace),
// threads range(2), depth only range(3).
void BM_Frame(benchmark::State& state) {
  const Prepared& p = prepared(kScenes[state.range(0)]);
  RenderOptions options;
  options.params["raster"] = state.range(1) == 0 ? "tiled" : "halfspace";
  options.threads = int(state.range(2));
  if (state.range(3)) options.outputs = FrameOutputs::DepthOnly;
  Renderer renderer(p.scene, options);  // kept across frames, as a renderer would be
  for (auto _ : state) {
    Frame frame = renderer.render(p.camera);
    benchmark::DoNotOptimize(frame.depth.data());
  }
  state.SetLabel(std::string(kScenes[state.range(0)]) + (state.range(1) ? " halfspace" : " tiled") +
                 (state.range(3) ? " depth-only" : ""));
}
BENCHMARK(BM_Frame)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0}, {1, 2}, {0, 1}})
    ->ArgsProduct({{1, 2, 4}, {1}, {1}, {0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Occlusion queries: the scene range(0) rendered once into an OcclusionBuffer (2 threads), then
// a 40 x 40 grid of boxes over its ground (each 1/100 of the scene's extent, 2% of its height)
// tested with boxVisible; time per batch of 1600 queries, and how many may show.
void BM_OcclusionBoxes(benchmark::State& state) {
  const Prepared& p = prepared(kScenes[state.range(0)]);
  OcclusionBuffer buffer;
  buffer.render(p.scene, p.camera, {DepthFormat{}, Cull::None, 2});
  const Bounds3 b = p.scene.bounds();
  const dvec3 extent = b.hi - b.lo;
  std::vector<Bounds3> boxes;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      Bounds3 box;
      box.add(b.lo + dvec3((i + 0.25) / 40 * extent.x, 0.0, (j + 0.25) / 40 * extent.z));
      box.add(b.lo + dvec3((i + 0.75) / 40 * extent.x, 0.02 * extent.y, (j + 0.75) / 40 * extent.z));
      boxes.push_back(box);
    }
  int visible = 0;
  for (auto _ : state) {
    visible = 0;
    for (const Bounds3& box : boxes) visible += buffer.boxVisible(box);
    benchmark::DoNotOptimize(visible);
  }
  state.counters["boxes"] = double(boxes.size());
  state.counters["visible"] = double(visible);
  state.SetLabel(kScenes[state.range(0)]);
}
BENCHMARK(BM_OcclusionBoxes)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hsr

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::AddCustomContext("kernel_isa", hsr::tiled::kernelTarget());
  benchmark::AddCustomContext("tile_size", std::to_string(hsr::tiled::kTileSize));
  benchmark::AddCustomContext("hardware_threads", std::to_string(hsr::resolveThreads(0)));
  benchmark::AddCustomContext("size", std::to_string(hsr::kWidth) + "x" + std::to_string(hsr::kHeight));
  benchmark::AddCustomContext("build_type", HSR_BUILD_TYPE);
  benchmark::AddCustomContext("build_flags", HSR_BUILD_FLAGS);
#ifdef NDEBUG
  benchmark::AddCustomContext("assertions", "off");
#else
  benchmark::AddCustomContext("assertions", "on");
#endif
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

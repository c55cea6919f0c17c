// The tiled rasterizer (raster/tiled.hpp) against the scalar reference (--raster halfspace):
// every built-in scene, its own camera and random poses, image sizes that are not multiples of
// the tile, every depth format, 1-3 threads and every instruction set this machine runs. Face
// ids, triangle ids, depths and colours must be bit-identical, depth_writes and color_writes
// equal. On a mismatch the message names the pixel and a command that replays it.
#include <gtest/gtest.h>

#include <span>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstring>
#include <fstream>
#include <fmt/format.h>
#include <hwy/targets.h>
#include <memory>
#include <random>
#include <random>
#include <set>

#include "frontend/clusters.hpp"
#include "frontend/frontend.hpp"
#include "frontend/triangle_setup.hpp"
#include "raster/halfspace.hpp"
#include "raster/tiled.hpp"
#include "setup/edge.hpp"
#include "setup/fragment_depth.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

using test::firstDifference;

const char* kStorages[] = {"u16", "u24", "u32", "f32"};
const char* kMappings[] = {"z", "reversed", "inv", "linear"};

// A built-in scene through the front end (with the default depth format's nearest bounds) and
// binned, every chunk, for tests that drive the tile pass themselves. Not copyable: the bins
// point into the front end's chunks.
struct BinnedScene {
  Scene scene;
  Camera cam;
  DepthSetup depth;
  FrontEndOutput fe;
  tiled::Bins bins;
  BinnedScene(const std::string& spec, int width, int height)
      : scene(loadScene(spec)),
        cam(resolveCamera(*scene.camera, width, height, scene.bounds())),
        depth{DepthFormat{}, cam.near, cam.far, cam.orthographic} {
    runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
    for (size_t c = 0; c < fe.chunkCount; ++c) tiled::binChunk(bins, c, fe.chunks[c]);
  }
  BinnedScene(const BinnedScene&) = delete;
  BinnedScene& operator=(const BinnedScene&) = delete;
};

std::vector<DepthFormat> allFormats() {
  std::vector<DepthFormat> formats;
  for (const char* s : kStorages)
    for (const char* m : kMappings) formats.push_back(DepthFormat::parse(std::string(s) + ":" + m));
  return formats;
}

// The scene's own camera, then seeded random poses: outside looking in, some close enough to
// cross the near plane or with a far plane cutting the scene, some orthographic.
std::vector<CameraSpec> poses(const Scene& scene, int random, uint64_t seed) {
  std::vector<CameraSpec> list;
  const Bounds3 b = scene.bounds();
  list.push_back(scene.camera ? *scene.camera : frameBounds(b));
  const dvec3 c = b.center();
  const double r = glm::length(b.hi - b.lo) * 0.5;
  std::mt19937_64 rng(seed);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int i = 0; i < random; ++i) {
    CameraSpec p;
    const double z = u() * 2 - 1, phi = u() * 2 * M_PI, s = std::sqrt(1 - z * z);
    p.eye = c + dvec3(s * std::cos(phi), z, s * std::sin(phi)) * (r * (0.5 + 2.5 * u()));
    p.target = c + dvec3(u() - 0.5, u() - 0.5, u() - 0.5) * r * 0.5;
    p.up = glm::normalize(dvec3(u() - 0.5, 2, u() - 0.5));
    p.fovyDeg = 25 + 70 * u();
    const double eyeDist = glm::length(p.eye - c);
    p.near = std::max(r * 0.01, (eyeDist - r) * (0.5 + 0.6 * u()));
    p.far = (eyeDist + r) * (0.7 + 0.5 * u());
    if (i % 5 == 2) p.orthoHeight = r * (1 + u());
    list.push_back(p);
  }
  return list;
}

// A camera inside the scene's bounding box (for the sphere: looking at its far side, which faces
// away from it).
CameraSpec insideCamera(const Scene& scene) {
  CameraSpec inside;
  inside.eye = scene.bounds().center() + dvec3(0.1, 0.05, 0.2);
  inside.target = inside.eye + dvec3(0.2, -0.3, -1);
  inside.fovyDeg = 80;
  return inside;
}

// Cameras on one ray from the scene's centre, at these multiples of its bounding radius:
// close-ups with a 90-degree lens, those farther than 10 with a 3-degree one.
std::vector<CameraSpec> alongRay(const Scene& scene, std::initializer_list<double> distances) {
  const Bounds3 b = scene.bounds();
  const double r = glm::length(b.hi - b.lo) * 0.5;
  std::vector<CameraSpec> list;
  for (double d : distances) {
    CameraSpec p;
    p.eye = b.center() + glm::normalize(dvec3(0.3, 0.4, 1)) * (r * d);
    p.target = b.center() + dvec3(0.05 * r, 0, 0);
    p.fovyDeg = d > 10 ? 3 : 90;
    list.push_back(p);
  }
  return list;
}

Frame renderWith(const Scene& scene, const Camera& cam, DepthFormat format, RasterKind raster, int threads,
                 FrameOutputs outputs = FrameOutputs::All, TiledSwitches switches = {}) {
  RenderOptions o;
  o.tiled = switches;
  o.depthFormat = format;
  setRaster(o, raster);
  o.threads = threads;
  o.outputs = outputs;
  return render(scene, cam, o);
}

// Triangle `index` of `scene` set up alone (setupTriangle) from the vertex pass `vertices`, its
// vertices all inside the clip volume (asserted); `kept`: whether set-up kept it.
void setUpAlone(const Scene& scene, const FrontEndOutput& vertices, uint32_t index, const Camera& cam, Cull cull,
                FrontEndCounters& counters, SetupTriangle& st, bool& kept) {
  kept = false;
  const Triangle& t = scene.triangles[index];
  ProjectedVertex v[3];
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(vertices.outcodes[t.v[k]], 0) << "triangle " << index;
    v[k] = vertices.projected[t.v[k]];
  }
  kept = setupTriangle(v, index, t.face, cam, cull, counters, st);
}

// Expects `fast` bit-identical to `reference`; returns false (after one failure message with a
// replay command) when not.
bool expectIdentical(const Frame& reference, const Frame& fast, const std::string& what, const std::string& replay) {
  struct Check {
    const char* name;
    long at;
  } checks[] = {{"face id", firstDifference(reference.faceId, fast.faceId)},
                {"triangle id", firstDifference(reference.triangleId, fast.triangleId)},
                {"depth", firstDifference(reference.depth, fast.depth)},
                {"colour", firstDifference(reference.color, fast.color)}};
  for (const Check& c : checks)
    if (c.at >= 0) {
      const int x = int(c.at % reference.width), y = int(c.at / reference.width);
      ADD_FAILURE() << fmt::format(
          "{}: {} differs at pixel ({}, {}): reference face {} depth {}, tiled face {} depth {}\n{}", what, c.name, x,
          y, reference.faceId[size_t(c.at)], reference.depth[size_t(c.at)], fast.faceId[size_t(c.at)],
          fast.depth[size_t(c.at)], replay);
      return false;
    }
  // Counts of the work done: the tiled rasterizer visits each tile's triangles nearest first,
  // so it writes (and tests) fewer fragments than the reference in submission order, but every
  // covered pixel at least once.
  EXPECT_EQ(reference.stats.covered_pixels, fast.stats.covered_pixels) << what;
  EXPECT_LE(fast.stats.covered_pixels, fast.stats.depth_writes) << what;
  EXPECT_LE(fast.stats.depth_writes, fast.stats.depth_tests) << what;
  // (A frame through mesh culling also tests in its first pass what the frame then tests again.)
  if (!fast.stats.detailCount("occlusion_passes")) EXPECT_LE(fast.stats.depth_tests, reference.stats.depth_tests) << what;
  // One colour write per fragment that won; a frame through mesh culling also counts its
  // depth-only first pass's depth writes.
  if (!reference.stats.color_writes) EXPECT_EQ(fast.stats.color_writes, 0u) << what;
  else if (!fast.stats.detailCount("occlusion_passes")) EXPECT_EQ(fast.stats.color_writes, fast.stats.depth_writes) << what;
  else EXPECT_TRUE(fast.stats.covered_pixels <= fast.stats.color_writes && fast.stats.color_writes < fast.stats.depth_writes) << what;
  return true;
}

std::string replayCommand(const std::string& scene, const CameraSpec& pose, int w, int h, DepthFormat f, int threads) {
  return fmt::format(
      "Replay: save the camera as cam.json, then compare\n"
      "  hsr render '{0}' --camera cam.json --size {1}x{2} --depth-format {3} --threads {4} --ids a.npy --depth a.npy\n"
      "  with --param raster=halfspace --threads 1\n{5}",
      scene, w, h, f.name(), threads, cameraSpecToJson(pose));
}

struct SceneCase {
  std::string name;
  int randomPoses;
};

// Every built-in scene; the big ones with fewer poses to keep the suite to a few seconds.
const std::vector<SceneCase>& sceneCases() {
  static const std::vector<SceneCase> list = {
      {"builtin:sphere?n=20000", 4},  {"builtin:city", 4},           {"builtin:random?n=2000", 10},
      {"builtin:layers?n=16", 10},    {"builtin:cubes", 10},         {"builtin:painter-midpoint", 10},
      {"builtin:painter-cycle", 10},  {"builtin:interpenetrate", 10}, {"builtin:zfight", 10},
      {"builtin:layers?n=9&order=random", 4},
  };
  return list;
}

// Every scene x pose x size x format, one thread: bit-identical to the reference. Two formats
// again with 2 and 3 threads (the tile pass and binning split differently, the bits may not).
TEST(Tiled, IdenticalToHalfSpaceOnEveryBuiltinSceneFormatAndThreadCount) {
  const std::pair<int, int> sizes[] = {{200, 150}, {333, 97}};
  const DepthFormat threadFormats[] = {DepthFormat::parse("f32:reversed"), DepthFormat::parse("u16:z")};
  int compared = 0;
  for (const SceneCase& sc : sceneCases()) {
    const Scene scene = loadScene(sc.name);
    for (const CameraSpec& pose : poses(scene, sc.randomPoses, std::hash<std::string>{}(sc.name) & 0xffff))
      for (auto [w, h] : sizes) {
        const Camera cam = resolveCamera(pose, w, h, scene.bounds());
        for (const DepthFormat& format : allFormats()) {
          const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
          std::vector<int> threadCounts = {1};
          for (const DepthFormat& tf : threadFormats)
            if (tf.name() == format.name()) threadCounts = {1, 2, 3};
          for (int threads : threadCounts) {
            const Frame fast = renderWith(scene, cam, format, RasterKind::Tiled, threads);
            ++compared;
            const std::string what = fmt::format("{} {}x{} {} threads {}", sc.name, w, h, format.name(), threads);
            if (!expectIdentical(reference, fast, what, replayCommand(sc.name, pose, w, h, format, threads))) return;
          }
        }
      }
  }
  EXPECT_GE(compared, 3000);
}

// Every instruction set Highway compiled and this CPU runs (AVX-512, AVX2, SSE4, ..., the
// emulated 128-bit one) gives the same bits, with every output and with depth only.
TEST(Tiled, IdenticalOnEveryInstructionSet) {
  std::vector<std::string> tested;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    tested.push_back(tiled::kernelTarget());
    for (const char* name : {"builtin:random?n=1000", "builtin:cubes", "builtin:zfight"}) {
      const Scene scene = loadScene(name);
      for (const CameraSpec& pose : poses(scene, 3, 11)) {
        const Camera cam = resolveCamera(pose, 150, 111, scene.bounds());
        for (const DepthFormat& format : allFormats()) {
          const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
          const Frame fast = renderWith(scene, cam, format, RasterKind::Tiled, 1);
          if (!expectIdentical(reference, fast, fmt::format("{} {} on {}", name, format.name(), tested.back()),
                               replayCommand(name, pose, 150, 111, format, 1)))
            break;
          // Depth only has its own resolve, which writes +inf where nothing was drawn.
          const Frame referenceDepth = renderWith(scene, cam, format, RasterKind::HalfSpace, 1, FrameOutputs::DepthOnly);
          const Frame fastDepth = renderWith(scene, cam, format, RasterKind::Tiled, 1, FrameOutputs::DepthOnly);
          ASSERT_EQ(firstDifference(fastDepth.depth, referenceDepth.depth), -1)
              << name << " " << format.name() << " depth only on " << tested.back();
        }
      }
    }
  }
  hwy::SetSupportedTargetsForTest(0);  // back to the best target
  RecordProperty("targets", fmt::format("{}", fmt::join(tested, ", ")));
  EXPECT_GE(tested.size(), 2u) << fmt::format("{}", fmt::join(tested, ", "));
}

// Odd image sizes (one pixel, thin strips, exact multiples of the tile and one more) and large
// triangles crossing many tiles.
TEST(Tiled, IdenticalOnOddImageSizes) {
  const Scene scene = test::randomSoup(300, 9, 1.5);
  const std::pair<int, int> sizes[] = {{1, 1}, {7, 300}, {300, 3}, {64, 64}, {65, 129}, {128, 64}, {257, 190}};
  for (auto [w, h] : sizes)
    for (const CameraSpec& pose : poses(scene, 4, 5)) {
      const Camera cam = resolveCamera(pose, w, h, scene.bounds());
      for (const char* f : {"f32:reversed", "u24:z", "u32:linear"}) {
        const DepthFormat format = DepthFormat::parse(f);
        expectIdentical(renderWith(scene, cam, format, RasterKind::HalfSpace, 1),
                        renderWith(scene, cam, format, RasterKind::Tiled, 2),
                        fmt::format("soup {}x{} {}", w, h, f), replayCommand("test:soup", pose, w, h, format, 2));
      }
    }
}

// countEntries' per-tile chunk lists name, in chunk order, exactly the chunks with something in
// the tile — a triangle, a deferred back face or a deferred cluster — and its counts are the
// lists' lengths; before countEntries (and after prepareBins) every chunk is walked.
TEST(Tiled, PerTileChunkListsNameEveryChunkWithItemsThere) {
  const Scene scene = loadScene("builtin:sphere?n=60000");
  const Camera cam = resolveCamera(frameBounds(scene.bounds()), 320, 240, scene.bounds());
  const DepthSetup depth{DepthFormat{}, cam.near, cam.far, cam.orthographic};
  FrontEndOutput fe;
  runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth, .deferBackFaces = true});
  ASSERT_GT(fe.chunkCount, 4u);
  tiled::Bins bins;
  tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
  for (size_t c = 0; c < fe.chunkCount; ++c) tiled::binChunk(bins, c, fe.chunks[c], &depth);
  const size_t tiles = size_t(bins.tileCount());
  auto walked = [&](int tile) {
    std::vector<size_t> chunks;
    bins.forChunksOf(tile, [&](size_t c) { chunks.push_back(c); });
    return chunks;
  };
  EXPECT_EQ(walked(0).size(), fe.chunkCount);  // (no lists yet: every chunk)
  bins.countEntries();
  size_t sets[3] = {0, 0, 0}, listedPairs = 0;
  for (size_t t = 0; t < tiles; ++t) {
    std::vector<size_t> expected;
    uint32_t count[3] = {0, 0, 0};
    for (size_t c = 0; c < fe.chunkCount; ++c) {
      bool any = false;
      for (int s = 0; s < 3; ++s) {
        const tiled::ChunkBins& cb = (s == 0 ? bins.chunks : s == 1 ? bins.late : bins.clusters)[c];
        const uint32_t n = cb.start[t + 1] - cb.start[t];
        count[s] += n;
        sets[s] += n;
        any |= n > 0;
      }
      if (any) expected.push_back(c);
    }
    EXPECT_EQ(walked(int(t)), expected) << "tile " << t;
    EXPECT_LT(expected.size(), fe.chunkCount) << "tile " << t;  // (the point: not every chunk)
    for (int s = 0; s < 3; ++s) EXPECT_EQ(bins.tileEntries[size_t(s) * tiles + t], count[s]) << "tile " << t;
    listedPairs += expected.size();
  }
  EXPECT_GT(sets[0], 0u);  // triangles, deferred faces and deferred clusters all binned somewhere
  EXPECT_GT(sets[1], 0u);
  EXPECT_GT(sets[2], 0u);
  EXPECT_GT(listedPairs, 0u);
  tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);  // a new frame: the lists are gone
  EXPECT_EQ(walked(0).size(), fe.chunkCount);
}

// The front end's chunk size depends on the scene's triangle count alone (binning culls within a
// chunk: the statistics must not depend on the thread count): whole clusters, kMinChunkTriangles
// to kChunkTriangles triangles, and about 4 chunks for scenes of 1K to 16K triangles.
TEST(Tiled, ChunkSizeFollowsTheSceneOnly) {
  for (const size_t n : {size_t(0), size_t(1), size_t(1000), size_t(10000), size_t(16384), size_t(20000), size_t(43202),
                         size_t(65536), size_t(1003520)}) {
    const size_t k = chunkTrianglesFor(n);
    EXPECT_EQ(k % kClusterTriangles, 0u) << n;
    EXPECT_GE(k, kMinChunkTriangles) << n;
    EXPECT_LE(k, kChunkTriangles) << n;
    if (n >= 4 * kMinChunkTriangles && n <= 4 * kChunkTriangles) {  // about 4 chunks
      const size_t chunks = (n + k - 1) / k;
      EXPECT_GE(chunks, 4u) << n;
      EXPECT_LE(chunks, 5u) << n;  // (n / 4 rounded down to whole clusters can leave a few over)
    }
  }
  const Scene scene = loadScene("builtin:random?n=10000");
  const Camera cam = resolveCamera(frameBounds(scene.bounds()), 320, 240, scene.bounds());
  for (const int threads : {1, 2}) {
    RenderOptions opt;
    opt.threads = threads;
    FrontEndOutput fe;
    runFrontEnd(scene, cam, opt, fe, {});
    EXPECT_EQ(fe.chunkTriangles, 2528u);  // 10000 / 4, rounded up to whole clusters
    ASSERT_EQ(fe.chunkCount, 4u);
    for (size_t c = 0; c < fe.chunkCount; ++c) {
      EXPECT_EQ(fe.chunks[c].firstTriangle, c * 2528);
      for (const SetupTriangle& t : fe.chunks[c].triangles) {
        EXPECT_GE(t.triangle, c * 2528);
        EXPECT_LT(t.triangle, (c + 1) * 2528);
      }
    }
  }
}

// Binning chunk by chunk, in any order, gives per-tile lists that, read in chunk order, list
// every triangle touching the tile once, in submission order; the nearest bounds do not depend
// on the order either.
TEST(Tiled, BinsAreInSubmissionOrderWhateverTheChunkOrder) {
  const Scene scene = loadScene("builtin:random?n=10000&size=0.4");
  const Camera cam = resolveCamera(frameBounds(scene.bounds()), 300, 200, scene.bounds());
  const DepthSetup depth{DepthFormat{}, cam.near, cam.far, cam.orthographic};
  FrontEndOutput fe;
  runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
  ASSERT_GT(fe.chunkCount, 2u);
  ASSERT_GT(fe.triangleCount(), 8000u);
  auto binned = [&](bool reverse) {
    tiled::Bins bins;
    tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
    for (size_t i = 0; i < fe.chunkCount; ++i) {
      const size_t c = reverse ? fe.chunkCount - 1 - i : i;
      tiled::binChunk(bins, c, fe.chunks[c]);
    }
    // Per tile: (submission position, nearest) of each entry, in list order.
    std::vector<std::vector<std::pair<size_t, double>>> lists(size_t(bins.tileCount()));
    size_t base = 0;
    for (size_t c = 0; c < fe.chunkCount; ++c) {
      const tiled::ChunkBins& cb = bins.chunks[c];
      for (int t = 0; t < bins.tileCount(); ++t)
        for (uint32_t k = cb.start[size_t(t)]; k < cb.start[size_t(t) + 1]; ++k)
          lists[size_t(t)].emplace_back(base + tiled::localIndex(cb.items[k]), cb.itemNearest[k]);
      base += fe.chunks[c].triangles.size();
    }
    return lists;
  };
  const auto forward = binned(false), backward = binned(true);
  EXPECT_EQ(forward, backward);
  const std::vector<SetupTriangle> all = fe.flatten();
  size_t entries = 0;
  std::set<std::pair<size_t, size_t>> listed;  // (triangle, tile)
  for (size_t t = 0; t < forward.size(); ++t) {
    const int tx = int(t) % ((cam.width + tiled::kTileSize - 1) / tiled::kTileSize);
    const int ty = int(t) / ((cam.width + tiled::kTileSize - 1) / tiled::kTileSize);
    for (size_t k = 0; k < forward[t].size(); ++k) {
      const size_t i = forward[t][k].first;
      if (k > 0) EXPECT_LT(forward[t][k - 1].first, i) << "tile " << t;  // strictly increasing
      // The triangle's box overlaps the tile.
      EXPECT_LE(all[i].minX / tiled::kTileSize, tx);
      EXPECT_GE(all[i].maxX / tiled::kTileSize, tx);
      EXPECT_LE(all[i].minY / tiled::kTileSize, ty);
      EXPECT_GE(all[i].maxY / tiled::kTileSize, ty);
      listed.insert({i, t});
    }
    entries += forward[t].size();
  }
  // Every tile where a triangle covers a pixel lists it (no entry lost by the sort).
  const int tilesX = (cam.width + tiled::kTileSize - 1) / tiled::kTileSize;
  for (size_t i = 0; i < all.size(); ++i)
    rasterizeHalfSpace(all[i], [&](int x, int y, double) {
      const size_t t = size_t((y / tiled::kTileSize) * tilesX + x / tiled::kTileSize);
      EXPECT_TRUE(listed.count({i, t})) << "triangle " << i << " covers (" << x << ", " << y << ") but is not in tile " << t;
    });
  EXPECT_GT(entries - all.size(), 100u);  // some triangles were binned to several tiles
  // And no more than the tiles of its box that no edge excludes (each edge tested at all four
  // corner pixel centres of the box's part in the tile), pair for pair.
  std::set<std::pair<size_t, size_t>> expected;
  for (size_t i = 0; i < all.size(); ++i) {
    const SetupTriangle& t = all[i];
    const Edge e[3] = {makeEdge(t, 0), makeEdge(t, 1), makeEdge(t, 2)};
    for (int ty = t.minY / tiled::kTileSize; ty <= t.maxY / tiled::kTileSize; ++ty)
      for (int tx = t.minX / tiled::kTileSize; tx <= t.maxX / tiled::kTileSize; ++tx) {
        const int x0 = std::max<int>(tx * tiled::kTileSize, t.minX), x1 = std::min<int>(tx * tiled::kTileSize + tiled::kTileSize - 1, t.maxX);
        const int y0 = std::max<int>(ty * tiled::kTileSize, t.minY), y1 = std::min<int>(ty * tiled::kTileSize + tiled::kTileSize - 1, t.maxY);
        bool excluded = false;
        for (const Edge& edge : e) {
          bool anyInside = false;
          for (int c = 0; c < 4; ++c)
            anyInside |= edge.at(centerFixed(c & 1 ? x1 : x0), centerFixed(c & 2 ? y1 : y0)) >= edge.bias;
          excluded |= !anyInside;
        }
        if (!excluded) expected.insert({i, size_t(ty * tilesX + tx)});
      }
  }
  EXPECT_EQ(listed, expected);
}

// Depth only: no ids, no colour in the frame; depth is the winner's eye depth, bit for bit the
// full frame's and the reference's, for every format and thread count.
TEST(Tiled, DepthOnlyKeepsOnlyDepth) {
  for (const char* name : {"builtin:cubes", "builtin:random?n=1500", "builtin:zfight", "builtin:layers?n=5"}) {
    const Scene scene = loadScene(name);
    for (const CameraSpec& pose : poses(scene, 2, 3)) {
      const Camera cam = resolveCamera(pose, 160, 100, scene.bounds());
      for (const DepthFormat& format : allFormats()) {
        const Frame full = renderWith(scene, cam, format, RasterKind::Tiled, 1);
        const Frame only = renderWith(scene, cam, format, RasterKind::Tiled, 2, FrameOutputs::DepthOnly);
        const Frame refOnly = renderWith(scene, cam, format, RasterKind::HalfSpace, 1, FrameOutputs::DepthOnly);
        const std::string what = fmt::format("{} {}", name, format.name());
        ASSERT_EQ(firstDifference(only.depth, full.depth), -1) << what;
        ASSERT_EQ(firstDifference(refOnly.depth, full.depth), -1) << what;
        EXPECT_EQ(only.stats.depth_writes, full.stats.depth_writes) << what;
        EXPECT_EQ(only.stats.covered_pixels, full.stats.covered_pixels) << what;
        EXPECT_EQ(only.stats.color_writes, 0u) << what;
        EXPECT_TRUE(only.faceId.empty() && only.triangleId.empty() && only.color.empty()) << what;
      }
    }
  }
}

// Any set of outputs with ids: the buffers asked for equal the full frame's, bit for bit, for the
// tiled rasterizer (1 and 2 threads) and the reference; the others are empty and cost nothing.
TEST(Tiled, EverySetOfOutputsEqualsTheFullFrame) {
  const Scene scene = loadScene("builtin:city");
  const Camera cam = resolveCamera(*scene.camera, 240, 135, scene.bounds());
  for (RasterKind raster : {RasterKind::Tiled, RasterKind::HalfSpace}) {
    const Frame full = renderWith(scene, cam, DepthFormat{}, raster, 2);
    ASSERT_EQ(full.color.size(), full.depth.size());
    for (uint8_t bits = 1; bits <= uint8_t(FrameOutputs::All); ++bits)
      for (int threads : {1, 2}) {
        const FrameOutputs outputs = FrameOutputs(bits);
        const std::string what = frameOutputsName(outputs) + " threads " + std::to_string(threads);
        const Frame part = renderWith(scene, cam, DepthFormat{}, raster, threads, outputs);
        EXPECT_EQ(firstDifference(full.depth, part.depth), -1) << what;
        if (has(outputs, FrameOutputs::FaceIds)) EXPECT_EQ(full.faceId, part.faceId) << what;
        else EXPECT_TRUE(part.faceId.empty()) << what;
        if (has(outputs, FrameOutputs::TriangleIds)) EXPECT_EQ(full.triangleId, part.triangleId) << what;
        else EXPECT_TRUE(part.triangleId.empty()) << what;
        if (has(outputs, FrameOutputs::Color)) {
          EXPECT_EQ(firstDifference(full.color, part.color), -1) << what;
          EXPECT_EQ(part.stats.color_writes, full.stats.color_writes) << what;
        } else {
          EXPECT_TRUE(part.color.empty()) << what;
          EXPECT_EQ(part.stats.color_writes, 0u) << what;
        }
        EXPECT_EQ(part.stats.covered_pixels, full.stats.covered_pixels) << what;
        EXPECT_EQ(part.stats.depth_writes, full.stats.depth_writes) << what;
        if (outputs != FrameOutputs::All) EXPECT_LT(part.stats.memory_bytes, full.stats.memory_bytes) << what;
      }
  }
}

TEST(Tiled, OutputListsParseAndName) {
  EXPECT_EQ(parseFrameOutputs("depth"), FrameOutputs::DepthOnly);
  EXPECT_EQ(parseFrameOutputs("depth,face,triangle,color"), FrameOutputs::All);
  EXPECT_EQ(parseFrameOutputs("color,face"), FrameOutputs::FaceIds | FrameOutputs::Color);
  EXPECT_EQ(parseFrameOutputs("triangle,face,depth"), FrameOutputs::IdsAndDepth);
  EXPECT_EQ(frameOutputsName(FrameOutputs::All), "depth,face,triangle,color");
  EXPECT_EQ(frameOutputsName(FrameOutputs::DepthOnly), "depth");
  for (uint8_t bits = 0; bits <= uint8_t(FrameOutputs::All); ++bits)
    EXPECT_EQ(parseFrameOutputs(frameOutputsName(FrameOutputs(bits))), FrameOutputs(bits));
  for (const char* bad : {"", "colour", "depth,", "face,,color", "Face", "depth color"})
    EXPECT_THROW(parseFrameOutputs(bad), InputError) << bad;
  EXPECT_TRUE(has(FrameOutputs::All, FrameOutputs::IdsAndDepth));
  EXPECT_FALSE(has(FrameOutputs::FaceIds | FrameOutputs::Color, FrameOutputs::IdsAndDepth));
  EXPECT_FALSE(has(FrameOutputs::All, FrameOutputs::DepthOnly));
}

// Every path of the kernel in one frame: screen-parallel layers (whole tiles and whole blocks
// replaced, then broken up), a sphere of small triangles (scalar path, blocks materialized under
// it) and a random soup (SIMD blocks) interleaved in depth — identical to the reference on every
// format, odd sizes, 1 and 2 threads, in any of the layers' orders.
class TiledMixed : public test::TempDirTest {};
TEST_F(TiledMixed, LayersSphereAndSoupTogetherAreIdentical) {
  for (const char* order : {"back-to-front", "front-to-back", "random"}) {
    const std::string json = path(std::string("mixed-") + order + ".json");
    std::ofstream(json) << R"({"meshes": [
      {"builtin": "layers?n=6&order=)" << order << R"(", "scale": [0.12, 0.4, 1], "translate": [-0.4, 0, 0]},
      {"builtin": "sphere?n=20000", "scale": 0.5, "translate": [0.25, -0.1, -2.2]},
      {"builtin": "layers?n=4&order=random&seed=4", "scale": [0.1, 0.3, 0.5], "translate": [0.5, 0.3, -0.8]},
      {"builtin": "random?n=300&seed=5", "scale": 2.0, "translate": [-0.3, 0.2, -6]}],
      "camera": {"eye": [0, 0, 0], "target": [0, 0, -1], "up": [0, 1, 0], "fovy_deg": 60, "near": 1, "far": 11}})";
    const Scene scene = loadScene(json);
    RenderOptions o;
    const Frame look = render(scene, resolveCamera(*scene.camera, 256, 192, scene.bounds()), o);
    ASSERT_GT(look.stats.covered_pixels, 20000u);  // a mix: layers, sphere and soup all show,
    std::set<int32_t> faces(look.faceId.begin(), look.faceId.end());
    ASSERT_GT(faces.size(), 2000u);                 // thousands of the sphere's faces among them
    for (auto [w, h] : {std::pair{256, 192}, std::pair{203, 141}}) {
      const Camera cam = resolveCamera(*scene.camera, w, h, scene.bounds());
      for (const char* f : {"f32:reversed", "u16:z", "u24:inv", "u32:linear", "f32:z"}) {
        const DepthFormat format = DepthFormat::parse(f);
        const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
        for (int threads : {1, 2})
          if (!expectIdentical(reference, renderWith(scene, cam, format, RasterKind::Tiled, threads),
                               fmt::format("mixed {} {}x{} {} threads {}", order, w, h, f, threads), ""))
            return;
      }
    }
  }
}

// Whole-tile planes ("lossless compression"): a triangle covering a whole tile in front of
// everything stored there replaces the tile in O(1). Each tile visits its triangles nearest
// first, so whatever the submission order the nearest layer does that on every tile it covers
// whole, and the layers behind it are rejected. Counted by the kernel; the frames are identical
// to the reference (tests above).
TEST(Tiled, TrianglesInFrontOfAWholeTileReplaceIt) {
  for (const char* order : {"back-to-front", "front-to-back"}) {
    const BinnedScene binned(std::string("builtin:layers?n=10&order=") + order, 256, 192);
    const tiled::Bins& bins = binned.bins;
    const DepthSetup& depth = binned.depth;
    auto scratch = std::make_unique<tiled::TileScratch>();
    tiled::TileOrder lists;
    tiled::RasterCounters counters;
    int planeTiles = 0;
    for (int tile = 0; tile < bins.tileCount(); ++tile) {
      tiled::rasterizeTile(bins, tile, depth, true, *scratch, lists, counters);
      planeTiles += scratch->state == tiled::TileState::Plane;
    }
    EXPECT_GT(planeTiles, 0) << order;
    EXPECT_EQ(counters.tilesWhole, uint64_t(planeTiles)) << order;  // the nearest layer only
    EXPECT_GE(counters.culledTiles, uint64_t(9 * planeTiles)) << order;
    // Tiles the layers' diagonal crosses: the nearest layer's blocks off the diagonal are
    // replaced whole.
    EXPECT_GT(counters.blocksWhole, 8u) << order;
  }
}

// Binning with the frame's depth setup leaves out the pairs of triangles behind a triangle that
// covers the tile whole (layers: every layer but the nearest, off the diagonal), counts them, and
// keeps the rest as they were; the image does not change (the identity tests above bin this way).
TEST(Tiled, TrianglesBehindATriangleCoveringTheTileAreNotBinned) {
  const Scene scene = loadScene("builtin:layers?n=16");
  const Camera cam = resolveCamera(*scene.camera, 1000, 600, scene.bounds());
  for (const char* f : {"f32:reversed", "u16:z", "u24:inv", "u32:linear"}) {
    const DepthSetup depth{DepthFormat::parse(f), cam.near, cam.far, cam.orthographic};
    FrontEndOutput fe;
    runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    ASSERT_EQ(fe.chunkCount, 1u);
    tiled::Bins all, culled;
    tiled::prepareBins(all, cam.width, cam.height, fe.chunkCount);
    tiled::prepareBins(culled, cam.width, cam.height, fe.chunkCount);
    for (size_t c = 0; c < fe.chunkCount; ++c) {
      tiled::binChunk(all, c, fe.chunks[c]);
      tiled::binChunk(culled, c, fe.chunks[c], &depth);
    }
    size_t allEntries = 0, culledEntries = 0;
    for (int t = 0; t < all.tileCount(); ++t) {
      allEntries += all.entries(t);
      culledEntries += culled.entries(t);
      // What is kept is a sublist, in the same order, holding the nearest layer.
      std::vector<uint32_t> a(all.chunks[0].items.begin() + all.chunks[0].start[size_t(t)],
                              all.chunks[0].items.begin() + all.chunks[0].start[size_t(t) + 1]);
      std::vector<uint32_t> k(culled.chunks[0].items.begin() + culled.chunks[0].start[size_t(t)],
                              culled.chunks[0].items.begin() + culled.chunks[0].start[size_t(t) + 1]);
      EXPECT_TRUE(std::includes(a.begin(), a.end(), k.begin(), k.end())) << f << " tile " << t;
      EXPECT_FALSE(k.empty()) << f << " tile " << t;
    }
    EXPECT_EQ(all.culled(), 0u);
    EXPECT_EQ(culled.culled(), allEntries - culledEntries) << f;
    EXPECT_LT(culledEntries * 2, allEntries) << f;  // (the tiles the diagonal crosses keep every layer)
  }
}

// The order-free depth test: a fragment equal to the stored value wins when its triangle was
// submitted first. Two identical triangles (equal depth everywhere): the second is given a
// nearer (still valid) bound, so its tile visits it first; the first must still win every pixel,
// as in submission order.
// A tile held pixel by pixel is resolved from the cells prepareResolve fills; resolving it
// without that step is a programming error, reported, not a wrong image.
TEST(Tiled, ResolvingIdsNeedsPrepareResolve) {
  const BinnedScene binned("builtin:random?n=200", 128, 96);
  const tiled::Bins& bins = binned.bins;
  const DepthSetup& depth = binned.depth;
  auto scratch = std::make_unique<tiled::TileScratch>();
  tiled::TileOrder lists;
  tiled::RasterCounters counters;
  const TriangleShader shade(binned.scene, binned.cam, Shading::Flat);
  Frame frame;
  frame.allocate(binned.cam.width, binned.cam.height);
  int pixelTiles = 0;
  for (int tile = 0; tile < bins.tileCount(); ++tile) {
    tiled::rasterizeTile(bins, tile, depth, true, *scratch, lists, counters);
    if (scratch->state != tiled::TileState::Pixels) continue;
    ++pixelTiles;
    EXPECT_THROW(tiled::resolveTile(bins, tile, depth, FrameOutputs::All, &shade, Rgba8{}, *scratch, frame),
                 std::logic_error);
    tiled::prepareResolve(bins, tile, FrameOutputs::All, &shade, Rgba8{}, *scratch);
    EXPECT_GT(tiled::resolveTile(bins, tile, depth, FrameOutputs::All, &shade, Rgba8{}, *scratch, frame), 0u);
  }
  EXPECT_GT(pixelTiles, 0);
}

// A triangle facing a camera at the origin that looks down -z: centred on (cx, cy), d away,
// r its half-width.
void addFacingTriangle(Scene& scene, double cx, double cy, double r, double d) {
  const uint32_t first = uint32_t(scene.positions.size());
  scene.positions.push_back({cx - r, cy - r, -d});
  scene.positions.push_back({cx + r, cy - r, -d});
  scene.positions.push_back({cx, cy + r, -d});
  const std::vector<uint32_t> face = {first, first + 1, first + 2};
  scene.addFace(std::span<const uint32_t>(face), Rgba8{200, 0, 0, 255});
}

// A 60x60 image (one tile) from the origin down -z.
Camera oneTileCamera(const Scene& scene, double near, double far, double fovyDeg = 0) {
  CameraSpec spec;
  spec.eye = {0, 0, 0};
  spec.target = {0, 0, -1};
  if (fovyDeg > 0) spec.fovyDeg = fovyDeg;
  spec.near = near;
  spec.far = far;
  return resolveCamera(spec, 60, 60, scene.bounds());
}

// Set-up takes the triangles of a mesh whose vertices are all inside the clip volume
// (FrontEndOutput::meshUnclipped) to its batches without reading their outcodes: the records,
// their order and the nearest bounds are those of setupTriangle on each triangle alone, beside a
// mesh that needs clipping, with a whole scene and with set-up of some meshes only.
TEST(Tiled, UnclippedMeshesAreSetUpAsTriangleByTriangle) {
  Scene scene;
  auto addMesh = [&](const char* name, double r, double depth, int count) {
    scene.beginMesh(name);
    for (int i = 0; i < count; ++i)
      addFacingTriangle(scene, 0.8 * std::sin(0.7 * i), 0.6 * std::cos(1.3 * i), r, depth + 0.01 * i);
  };
  addMesh("inside", 0.05, 3, 150);
  addMesh("beyond the guard band", 1e4, 4, 40);  // (each triangle clipped)
  addMesh("inside too", 0.2, 2, 70);
  scene.finalize();
  ASSERT_EQ(scene.meshes.size(), 3u);
  const Camera cam = oneTileCamera(scene, 0.5, 100, 60);
  const DepthSetup depth{DepthFormat::parse("f32:reversed"), cam.near, cam.far, cam.orthographic};
  const RenderOptions opt;
  FrontEndOutput vertices, fe;
  runVertexPass(scene, cam, opt, vertices);
  // Every triangle of a mesh given, alone, in submission order.
  auto alone = [&](std::initializer_list<size_t> meshes, std::vector<SetupTriangle>& out,
                   std::vector<double>& nearest) {
    for (size_t m : meshes) {
      const MeshRange& mesh = scene.meshes[m];
      for (uint32_t i = mesh.firstTriangle; i < mesh.firstTriangle + mesh.triangleCount; ++i) {
        SetupTriangle st;
        FrontEndCounters counters;
        bool kept = false;
        setUpAlone(scene, vertices, i, cam, Cull::None, counters, st, kept);
        ASSERT_FALSE(HasFatalFailure());
        if (!kept) continue;
        out.push_back(st);
        nearest.push_back(nearestStored(st, depth));
      }
    }
  };
  // The set-up triangles of meshes 0 and 2 from `fe`, checked against those alone.
  auto check = [&](std::initializer_list<size_t> meshes, const char* what) {
    std::vector<SetupTriangle> expected, got;
    std::vector<double> expectedNearest, gotNearest;
    alone(meshes, expected, expectedNearest);
    ASSERT_GT(expected.size(), 50u) << what;
    for (size_t c = 0; c < fe.chunkCount; ++c)
      for (size_t i = 0; i < fe.chunks[c].triangles.size(); ++i) {
        const SetupTriangle& t = fe.chunks[c].triangles[i];
        if (t.triangle >= scene.meshes[1].firstTriangle && t.triangle < scene.meshes[2].firstTriangle) continue;
        got.push_back(t);
        gotNearest.push_back(fe.chunks[c].nearest[i]);
      }
    ASSERT_EQ(got.size(), expected.size()) << what;
    for (size_t i = 0; i < got.size(); ++i) {
      const std::string at = fmt::format("{}, triangle {}", what, i);
      EXPECT_EQ(std::memcmp(&got[i], &expected[i], offsetof(SetupTriangle, frontFacing)), 0) << at;  // (then padding)
      EXPECT_EQ(got[i].frontFacing, expected[i].frontFacing) << at;
      EXPECT_EQ(got[i].coverage, expected[i].coverage) << at;
      EXPECT_EQ(gotNearest[i], expectedNearest[i]) << at;
    }
  };
  runSetUp(scene, cam, opt, vertices, fe, {}, {.nearestFor = &depth});
  EXPECT_EQ(fe.meshUnclipped, (std::vector<uint8_t>{1, 0, 1}));
  EXPECT_GT(fe.clipped, 0u);  // the middle mesh went through clipping
  check({0, 2}, "whole scene");
  const std::vector<TriangleRange> only = {{scene.meshes[2].firstTriangle,
                                            scene.meshes[2].firstTriangle + scene.meshes[2].triangleCount}};
  runSetUp(scene, cam, opt, vertices, fe, {}, {.nearestFor = &depth, .only = &only});
  EXPECT_EQ(fe.meshUnclipped, (std::vector<uint8_t>{0, 0, 1}));  // (only the meshes set up are tested)
  EXPECT_EQ(fe.clipped, 0u);
  check({2}, "mesh 2 only");
}

// orderTile's buckets are of equal width in eye depth, whatever the mapping: with a perspective
// camera the z, reversed and inv mappings crowd the distance into a few stored values (here 50
// and 100 units away fall into one bucket of equal stored width), and the tile's nearer
// triangles must still come first.
TEST(Tiled, OrderTileVisitsByEyeDepthInEveryMapping) {
  Scene scene;
  scene.source = "test";
  // Three squares' first triangles facing the camera, farthest submitted first: 100, 50, 1 away.
  for (double d : {100.0, 50.0, 1.0}) addFacingTriangle(scene, 0, 0, 0.4 * d, d);
  scene.finalize();
  const Camera cam = oneTileCamera(scene, 0.1, 1000);
  for (const char* f : {"f32:z", "u24:z", "f32:reversed", "u32:inv", "f32:linear", "u16:reversed"}) {
    const DepthSetup depth{DepthFormat::parse(f), cam.near, cam.far, cam.orthographic};
    FrontEndOutput fe;
    runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    ASSERT_EQ(fe.triangleCount(), 3u) << f;
    tiled::Bins bins;
    tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
    tiled::binChunk(bins, 0, fe.chunks[0]);
    ASSERT_EQ(bins.tileCount(), 1);
    tiled::TileOrder lists;
    const std::vector<tiled::TileEntry>& order = tiled::orderTile(bins, 0, depth, lists);
    ASSERT_EQ(order.size(), 3u) << f;
    for (uint32_t i = 0; i < 3; ++i)  // nearest (submitted last) first
      EXPECT_EQ(order[i].key, tiled::triangleKey(0, tiled::localKey(2 - i, false, 2 - i))) << f << " place " << i;
  }
}

// Nearest first by buckets fine enough for the depth complexity of the built-in layers: 64
// screen-filling quads at evenly spaced depths, submitted farthest first. Each tile visits the
// nearest quad's triangles before the others (kOrderBuckets: two layers to a bucket with 32
// buckets, the farther drawn first), so every pixel is written once, in every depth format.
TEST(Tiled, StackedLayersAreEachWrittenOnce) {
  const Scene scene = loadScene("builtin:layers?n=64");
  const Camera cam = resolveCamera(*scene.camera, 640, 480, scene.bounds());
  for (const char* f : {"f32:reversed", "f32:z", "u24:z", "u32:inv", "f32:linear"})
    for (const FrameOutputs outputs : {FrameOutputs::All, FrameOutputs::DepthOnly}) {
      const Frame frame = renderWith(scene, cam, DepthFormat::parse(f), RasterKind::Tiled, 2, outputs);
      EXPECT_EQ(frame.stats.covered_pixels, uint64_t(cam.width) * uint64_t(cam.height)) << f;
      EXPECT_EQ(frame.stats.depth_writes, frame.stats.covered_pixels) << f << " " << frameOutputsName(outputs);
    }
}

// A tile of many small triangles (at least kUnsortedEntries, their boxes holding at most
// kUnsortedArea pixels) is left in submission order; the same number of large ones is sorted.
TEST(Tiled, OrderTileLeavesManySmallTrianglesInSubmissionOrder) {
  for (const bool small : {true, false}) {
    Scene scene;
    scene.source = "test";
    // 100 triangles facing the camera, farthest submitted first (1000 down to 10 away); small:
    // about 4 pixels across, scattered over the tile; large: each covering the tile.
    constexpr int kCount = 100;
    for (int i = 0; i < kCount; ++i) {
      const double d = 1000.0 - 9.9 * i;
      const double cx = small ? ((i % 10) - 4.5) * 0.02 * d : 0, cy = small ? ((i / 10) - 4.5) * 0.02 * d : 0;
      addFacingTriangle(scene, cx, cy, small ? 0.03 * d : 2 * d, d);
    }
    scene.finalize();
    const Camera cam = oneTileCamera(scene, 1, 2000, 45);
    const DepthSetup depth{DepthFormat::parse("f32:reversed"), cam.near, cam.far, cam.orthographic};
    FrontEndOutput fe;
    runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    ASSERT_EQ(fe.triangleCount(), size_t(kCount)) << small;
    tiled::Bins bins;
    tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
    tiled::binChunk(bins, 0, fe.chunks[0]);
    ASSERT_EQ(bins.tileCount(), 1);
    uint64_t area = 0;
    for (size_t i = 0; i < fe.chunks[0].triangles.size(); ++i) {
      const SetupTriangle& t = fe.chunks[0].triangles[i];
      area += uint64_t(t.maxX - t.minX + 1) * uint64_t(t.maxY - t.minY + 1);
    }
    EXPECT_EQ(bins.chunks[0].area[0], area) << small;  // (the boxes lie in the one tile)
    EXPECT_EQ(area <= tiled::kUnsortedArea, small) << area;
    tiled::TileOrder lists;
    const std::vector<tiled::TileEntry>& order = tiled::orderTile(bins, 0, depth, lists);
    ASSERT_EQ(order.size(), size_t(kCount)) << small;
    // Small: in submission order. Large: roughly nearest first (by buckets), so one of the
    // nearest, submitted last, before the farthest, submitted first.
    bool submissionOrder = true;
    for (size_t i = 1; i < order.size(); ++i) submissionOrder &= order[i - 1].key < order[i].key;
    EXPECT_EQ(submissionOrder, small);
    if (!small) EXPECT_GT(order.front().key, order.back().key);
    // Either way, the frame is the reference's.
    const Frame reference = renderWith(scene, cam, depth.format, RasterKind::HalfSpace, 1);
    expectIdentical(reference, renderWith(scene, cam, depth.format, RasterKind::Tiled, 2), small ? "small" : "large",
                    "");
  }
}

// Seen from inside a closed mesh every visible face is a back face, shaded in the resolve (its
// record carries no colour): colour, ids and depth are the reference's.
TEST(Tiled, BackFacesSeenFromInsideResolveAsTheReference) {
  const Scene scene = loadScene("builtin:sphere?n=20000");
  const Camera cam = resolveCamera(insideCamera(scene), 256, 160, scene.bounds());
  for (const char* f : {"f32:reversed", "u16:z"}) {
    const DepthFormat format = DepthFormat::parse(f);
    const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
    EXPECT_GT(reference.stats.covered_pixels, 256u * 160u / 2) << f;
    for (int threads : {1, 2})
      expectIdentical(reference, renderWith(scene, cam, format, RasterKind::Tiled, threads),
                      fmt::format("inside the sphere, {} threads {}", f, threads), "");
  }
}

TEST(Tiled, EqualDepthGoesToTheTriangleSubmittedFirstWhateverTheVisitOrder) {
  Scene scene;
  scene.source = "test";
  scene.positions = {{-1, -1, 0}, {1, -1, 0.5}, {0, 1, 0.25}};
  const std::vector<uint32_t> face = {0, 1, 2};
  scene.addFace(std::span<const uint32_t>(face), Rgba8{200, 0, 0, 255});
  scene.addFace(std::span<const uint32_t>(face), Rgba8{0, 200, 0, 255});
  scene.finalize();
  CameraSpec spec;
  spec.eye = {0.3, 0.2, 3};
  spec.target = {0, 0, 0};
  const Camera cam = resolveCamera(spec, 64, 64, scene.bounds());
  for (const char* f : {"f32:reversed", "u16:z", "u32:linear"}) {
    const DepthSetup depth{DepthFormat::parse(f), cam.near, cam.far, cam.orthographic};
    const bool greater = depth.format.mapping == DepthMapping::Reversed || depth.format.mapping == DepthMapping::Inv;
    FrontEndOutput fe;
    runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth});
    ASSERT_EQ(fe.triangleCount(), 2u);
    std::vector<double>& nearest = fe.chunks[0].nearest;
    ASSERT_GT(nearest[0], 0) << f;
    nearest[1] = greater ? 2 * nearest[0] : nearest[0] / 2;  // nearer: visited first
    tiled::Bins bins;
    tiled::prepareBins(bins, cam.width, cam.height, fe.chunkCount);
    tiled::binChunk(bins, 0, fe.chunks[0]);
    auto scratch = std::make_unique<tiled::TileScratch>();
    tiled::RasterCounters counters;
    ASSERT_EQ(bins.tileCount(), 1);
    tiled::TileOrder lists;
    const std::vector<tiled::TileEntry>& order = tiled::orderTile(bins, 0, depth, lists);
    ASSERT_EQ(order.size(), 2u);
    EXPECT_EQ(order[0].key, tiled::triangleKey(0, tiled::localKey(1, false, 1))) << f;  // the second triangle first
    tiled::rasterizeTile(bins, 0, depth, true, *scratch, lists, counters);
    size_t covered = 0;
    for (int y = 0; y < cam.height; ++y)
      for (int x = 0; x < cam.width; ++x) {
        const uint64_t key = scratch->triangle[size_t(y) * tiled::kTileSize + size_t(x)];
        if (!key) continue;
        ++covered;
        ASSERT_EQ(key, tiled::triangleKey(0, tiled::localKey(0, false, 0))) << f << " pixel " << x << "," << y;
      }
    EXPECT_GT(covered, 500u) << f;
    EXPECT_EQ(counters.depthWrites, 2 * covered) << f;  // the second, then the first on every pixel
    // And through render(), as the reference draws it: face 0 everywhere.
    RenderOptions o;
    o.depthFormat = depth.format;
    const Frame frame = render(scene, cam, o);
    EXPECT_EQ(std::count(frame.faceId.begin(), frame.faceId.end(), 1), 0) << f;
  }
}

// Deferred back faces (tiled.hpp, binChunk): a back face whose box lies in one tile is kept out
// of the bins until the tile's other triangles are drawn, then drawn only if it may show. On a
// coplanar pair of opposite winding (the same plane: equal depths on every pixel), the one
// submitted first must win every pixel, whichever of the two is the deferred back face.
TEST(Tiled, DeferredBackFaceTiesGoToTheTriangleSubmittedFirst) {
  for (bool backFirst : {false, true}) {
    Scene scene;
    scene.source = "test";
    scene.positions = {{-1, -1, 0}, {1, -1, 0.5}, {0, 1, 0.25}};
    const std::vector<uint32_t> front = {0, 1, 2}, back = {0, 2, 1};
    scene.addFace(std::span<const uint32_t>(backFirst ? back : front), Rgba8{200, 0, 0, 255});
    scene.addFace(std::span<const uint32_t>(backFirst ? front : back), Rgba8{0, 200, 0, 255});
    scene.finalize();
    CameraSpec spec;
    spec.eye = {0.3, 0.2, 3};
    spec.target = {0, 0, 0};
    const Camera cam = resolveCamera(spec, 60, 60, scene.bounds());  // one tile
    for (const char* f : {"f32:reversed", "u16:z", "u32:linear", "u24:inv"}) {
      const DepthFormat format = DepthFormat::parse(f);
      const DepthSetup depth{format, cam.near, cam.far, cam.orthographic};
      FrontEndOutput fe;
      runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth, .deferBackFaces = true});
      ASSERT_EQ(fe.chunks[0].triangles.size(), 1u) << f;
      ASSERT_EQ(fe.chunks[0].deferred.size(), 1u) << f;  // the back face
      EXPECT_EQ(fe.chunks[0].deferred[0].face, backFirst ? 0u : 1u) << f;
      const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
      const Frame fast = renderWith(scene, cam, format, RasterKind::Tiled, 1);
      expectIdentical(reference, fast, std::string(f) + (backFirst ? " back face first" : " front face first"), "");
      EXPECT_GT(std::count(fast.faceId.begin(), fast.faceId.end(), 0), 500) << f;
      EXPECT_EQ(std::count(fast.faceId.begin(), fast.faceId.end(), 1), 0) << f;
    }
  }
}

// Deferred clusters (deferCluster): every triangle of one is inside the clip volume, its pixel
// box inside the cluster's, and its own nearest bound (nearestStored, which bounds its fragments)
// no nearer than the cluster's — for random poses, close-ups that see the sphere's far side
// steeply, two image sizes and every depth format. And the sphere defers clusters at all.
TEST(Tiled, DeferredClusterBoundsEveryTriangle) {
  const Scene scene = loadScene("builtin:sphere?n=20000");
  std::vector<CameraSpec> cameras = poses(scene, 12, 17);
  for (const CameraSpec& p : alongRay(scene, {1.02, 1.2, 2.0, 40.0})) cameras.push_back(p);  // (1.02: near side clipped)
  size_t clusters = 0, triangles = 0;
  for (const CameraSpec& pose : cameras)
    for (auto [w, h] : {std::pair{256, 160}, std::pair{1920, 1080}}) {
      const Camera cam = resolveCamera(pose, w, h, scene.bounds());
      for (const DepthFormat& format : allFormats()) {
        const DepthSetup depth{format, cam.near, cam.far, cam.orthographic};
        FrontEndOutput fe;
        runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth, .deferBackFaces = true});
        const bool greater = format.greaterWins();
        for (size_t k = 0; k < fe.chunkCount; ++k)
          for (const DeferredCluster& dc : fe.chunks[k].clusters) {
            ++clusters;
            for (size_t i = 0; i < kClusterTriangles; ++i) {
              const uint32_t index = uint32_t(dc.cluster * kClusterTriangles + i);
              SetupTriangle st;
              FrontEndCounters counters;
              bool kept = false;
              setUpAlone(scene, fe, index, cam, Cull::None, counters, st, kept);
              ASSERT_FALSE(HasFatalFailure()) << "cluster " << dc.cluster;
              if (!kept) continue;
              ++triangles;
              EXPECT_TRUE(st.minX >= dc.minX && st.maxX <= dc.maxX && st.minY >= dc.minY && st.maxY <= dc.maxY)
                  << "triangle " << index;
              const double own = nearestStored(st, depth);
              EXPECT_TRUE(greater ? own <= dc.nearest : own >= dc.nearest)
                  << fmt::format("triangle {} {}: own nearest {} cluster's {}", index, format.name(), own, dc.nearest);
            }
          }
      }
    }
  EXPECT_GT(clusters, 1000u);
  EXPECT_GT(triangles, 30000u);
}

// Culled clusters (cullCluster, with --cull back): every triangle of one is inside the clip
// volume and culled by its own set-up as a back face — not degenerate, not empty — so culling
// the cluster whole counts what the set-up would. Same poses as above; far away, the sphere's
// triangles are too small for the guarantee and no cluster may be culled there unless it holds.
TEST(Tiled, CulledClustersAreBackFacesEveryTriangle) {
  const Scene scene = loadScene("builtin:sphere?n=20000");
  std::vector<CameraSpec> cameras = poses(scene, 12, 17);
  for (const CameraSpec& p : alongRay(scene, {1.02, 1.2, 2.0, 40.0, 400.0, 40000.0}))  // (40000: 1/1000-pixel triangles)
    cameras.push_back(p);
  size_t culled = 0;
  for (const CameraSpec& pose : cameras)
    for (auto [w, h] : {std::pair{256, 160}, std::pair{1920, 1080}}) {
      const Camera cam = resolveCamera(pose, w, h, scene.bounds());
      FrontEndOutput fe;
      RenderOptions o;
      o.cull = Cull::Back;
      runFrontEnd(scene, cam, o, fe);  // (for the projected vertices)
      const ClusterView view = clusterView(cam);
      const dmat4 M = cam.pixelFromCamera * cam.cameraFromWorld;
      for (size_t k = 0; k < scene.clusters.size(); ++k) {
        if (!cullCluster(scene.clusters[k], view, cam, M)) continue;
        ++culled;
        for (size_t i = 0; i < kClusterTriangles; ++i) {
          const uint32_t index = uint32_t(k * kClusterTriangles + i);
          SetupTriangle st;
          FrontEndCounters counters;
          bool kept = true;
          setUpAlone(scene, fe, index, cam, Cull::Back, counters, st, kept);
          ASSERT_FALSE(HasFatalFailure()) << "cluster " << k;
          EXPECT_FALSE(kept) << "triangle " << index;
          EXPECT_EQ(counters.culledBackface, 1u) << "triangle " << index;
        }
      }
    }
  EXPECT_GT(culled, 1000u);
}

// With --cull back the culled clusters change no bit and no count: frames and statistics equal
// with them turned off (the switch defer-clusters off), 1 and 3 threads, a camera inside the sphere too.
TEST(Tiled, CulledClustersChangeNoBitNorCount) {
  const Scene scene = loadScene("builtin:sphere?n=20000");
  std::vector<CameraSpec> cameras = poses(scene, 3, 23);
  cameras.push_back(insideCamera(scene));
  for (const CameraSpec& pose : cameras) {
    const Camera cam = resolveCamera(pose, 256, 160, scene.bounds());
    for (int threads : {1, 3}) {
      RenderOptions o;
      o.cull = Cull::Back;
      o.threads = threads;
      const Frame on = render(scene, cam, o);
      o.tiled.deferClusters = false;
      const Frame off = render(scene, cam, o);
      const std::string what = fmt::format("threads {}", threads);
      EXPECT_EQ(on.faceId, off.faceId) << what;
      EXPECT_EQ(on.triangleId, off.triangleId) << what;
      EXPECT_EQ(firstDifference(on.depth, off.depth), -1) << what;
      EXPECT_EQ(firstDifference(on.color, off.color), -1) << what;
      EXPECT_EQ(on.stats.culled_backface, off.stats.culled_backface) << what;
      EXPECT_EQ(on.stats.triangles_degenerate, off.stats.triangles_degenerate) << what;
      EXPECT_EQ(on.stats.culled_frustum, off.stats.culled_frustum) << what;
      EXPECT_EQ(on.stats.culled_occlusion, off.stats.culled_occlusion) << what;
      EXPECT_EQ(on.stats.depth_tests, off.stats.depth_tests) << what;
      EXPECT_EQ(on.stats.depth_writes, off.stats.depth_writes) << what;
      EXPECT_GT(on.stats.culled_backface, 5000u) << what;
    }
  }
}

// Deferred back faces and clusters change nothing but the work: with clusters turned off
// (the switch defer-clusters off) or all deferral (defer-back-faces off) every frame is the same
// bits. Random triangles show many back faces (drawn late, after being set up again); a closed
// mesh hides nearly all of them, which are then never binned to a tile list, ordered or visited
// (counted as culled pairs) — except from inside, where its far side is deferred and shows.
TEST(Tiled, DeferredBackFacesChangeNoBit) {
  struct Case {
    const char* scene;
    bool backFacesShow;
  };
  for (const Case& c : {Case{"builtin:random?n=3000&size=0.05", true}, Case{"builtin:sphere?n=20000", false}}) {
    const Scene scene = loadScene(c.scene);
    std::vector<CameraSpec> cameras = poses(scene, 2, 5);
    if (!c.backFacesShow) cameras.push_back(insideCamera(scene));  // the far side: deferred, and shows
    for (const CameraSpec& pose : cameras) {
      const bool inside = &pose == &cameras.back() && !c.backFacesShow;
      const Camera cam = resolveCamera(pose, 256, 160, scene.bounds());
      for (const char* f : {"f32:reversed", "u16:z"}) {
        const DepthFormat format = DepthFormat::parse(f);
        const DepthSetup depth{format, cam.near, cam.far, cam.orthographic};
        FrontEndOutput fe;
        runFrontEnd(scene, cam, RenderOptions{}, fe, {}, {.nearestFor = &depth, .deferBackFaces = true});
        std::set<int32_t> deferred;  // scene triangles
        size_t clusters = 0;
        for (size_t k = 0; k < fe.chunkCount; ++k) {
          for (const DeferredFace& d : fe.chunks[k].deferred) deferred.insert(int32_t(d.triangle));
          for (const DeferredCluster& d : fe.chunks[k].clusters)
            for (size_t i = 0; i < kClusterTriangles; ++i) deferred.insert(int32_t(d.cluster * kClusterTriangles + i));
          clusters += fe.chunks[k].clusters.size();
        }
        ASSERT_GT(deferred.size(), 100u) << c.scene;
        if (!c.backFacesShow && !cam.orthographic) EXPECT_GT(clusters, 10u) << c.scene;
        for (FrameOutputs outputs : {FrameOutputs::All, FrameOutputs::DepthOnly})
          for (int threads : {1, 3}) {
            const Frame on = renderWith(scene, cam, format, RasterKind::Tiled, threads, outputs);
            const Frame facesOnly = renderWith(scene, cam, format, RasterKind::Tiled, threads, outputs,
                                               {.deferClusters = false});
            const Frame off = renderWith(scene, cam, format, RasterKind::Tiled, threads, outputs,
                                         {.deferBackFaces = false});
            const std::string what = fmt::format("{} {} threads {}", c.scene, f, threads);
            EXPECT_EQ(facesOnly.faceId, off.faceId) << what;
            EXPECT_EQ(facesOnly.triangleId, off.triangleId) << what;
            EXPECT_EQ(firstDifference(facesOnly.depth, off.depth), -1) << what;
            EXPECT_EQ(firstDifference(facesOnly.color, off.color), -1) << what;
            EXPECT_EQ(on.faceId, off.faceId) << what;
            EXPECT_EQ(on.triangleId, off.triangleId) << what;
            EXPECT_EQ(firstDifference(on.depth, off.depth), -1) << what;
            EXPECT_EQ(firstDifference(on.color, off.color), -1) << what;
            EXPECT_EQ(on.stats.covered_pixels, off.stats.covered_pixels) << what;
            // The deferral's statistics: what the front end above deferred, none with it off.
            EXPECT_EQ(on.stats.detailCount("triangles_deferred"), deferred.size()) << what;
            EXPECT_EQ(on.stats.detailCount("clusters_deferred"), clusters) << what;
            EXPECT_LE(on.stats.detailCount("triangles_set_up_late").value_or(0), deferred.size()) << what;
            if (inside) EXPECT_GT(on.stats.detailCount("triangles_set_up_late").value_or(0), 200u) << what;
            EXPECT_EQ(off.stats.detailCount("triangles_deferred"), 0u) << what;
            EXPECT_EQ(off.stats.detailCount("triangles_set_up_late"), 0u) << what;
            if (outputs == FrameOutputs::DepthOnly) continue;
            const auto shown = std::count_if(on.triangleId.begin(), on.triangleId.end(),
                                             [&](int32_t t) { return deferred.count(t) > 0; });
            if (c.backFacesShow || inside) EXPECT_GT(shown, 200) << what;
            else EXPECT_GT(on.stats.culled_occlusion, off.stats.culled_occlusion + deferred.size() / 2) << what;
          }
      }
    }
  }
}

// render() into a Frame that holds an earlier, different image: every pixel is rewritten (the
// frame is sized, not cleared), for every output kind.
TEST(Tiled, ReusedFrameIsFullyOverwritten) {
  const Scene full = loadScene("builtin:layers?n=3"), sparse = loadScene("builtin:cubes");
  const Camera fullCam = resolveCamera(*full.camera, 150, 100, full.bounds());
  const Camera sparseCam = resolveCamera(frameBounds(sparse.bounds()), 150, 100, sparse.bounds());
  for (FrameOutputs outputs : {FrameOutputs::All, FrameOutputs::IdsAndDepth, FrameOutputs::FaceIds | FrameOutputs::Color,
                               FrameOutputs::DepthOnly}) {
    RenderOptions o;
    o.outputs = outputs;
    o.background = Rgba8{10, 20, 30, 255};
    Frame reused;
    render(full, fullCam, o, reused);
    render(sparse, sparseCam, o, reused);
    const Frame fresh = render(sparse, sparseCam, o);
    EXPECT_EQ(reused.faceId, fresh.faceId);
    EXPECT_EQ(reused.triangleId, fresh.triangleId);
    EXPECT_EQ(firstDifference(reused.depth, fresh.depth), -1);
    EXPECT_EQ(firstDifference(reused.color, fresh.color), -1);
    EXPECT_GT(std::count(fresh.depth.begin(), fresh.depth.end(), std::numeric_limits<float>::infinity()), 1000);
  }
}

// The background of segments with nothing binned is streamed by the workers' pumps while they
// rasterize the rest (zbuffer.cpp, tiled::BackgroundPump): a small object far off in a wide
// frame whose rows do not start on cache lines (1000 and 1016 pixels wide: the pieces' partial
// lines), rendered into a frame left full of other values, equals the reference for every set of
// buffers and 1 to 3 threads, and the frame with the pumps turned off (the switch background-pump off).
TEST(Tiled, PumpedBackgroundIsTheReferences) {
  const Scene scene = loadScene("builtin:cubes");
  const Bounds3 b = scene.bounds();
  CameraSpec pose = frameBounds(b);
  pose.eye = b.center() + (pose.eye - b.center()) * 6.0;  // the cubes in a few tiles of the middle
  for (int width : {1000, 1016}) {
    const Camera cam = resolveCamera(pose, width, 700, b);
    RenderOptions ref;
    setRaster(ref, RasterKind::HalfSpace);
    ref.background = Rgba8{10, 20, 30, 255};
    const Frame reference = render(scene, cam, ref);
    ASSERT_GT(reference.stats.covered_pixels, 1000u);
    ASSERT_LT(reference.stats.covered_pixels, uint64_t(width) * 700 / 8);  // most segments idle
    for (FrameOutputs outputs : {FrameOutputs::All, FrameOutputs::FaceIds | FrameOutputs::Color, FrameOutputs::DepthOnly})
      for (int threads : {1, 2, 3}) {
        RenderOptions o = ref;
        setRaster(o, RasterKind::Tiled);
        o.outputs = outputs;
        o.threads = threads;
        Frame pumped, unpumped;
        for (Frame* f : {&pumped, &unpumped}) {  // frames full of other values
          f->allocate(cam.width, cam.height, outputs);
          std::fill(f->depth.begin(), f->depth.end(), 1.5f);
          std::fill(f->faceId.begin(), f->faceId.end(), 7);
          std::fill(f->triangleId.begin(), f->triangleId.end(), 7);
          std::fill(f->color.begin(), f->color.end(), Rgba8{1, 2, 3, 4});
          o.tiled.backgroundPump = f != &unpumped;
          render(scene, cam, o, *f);
        }
        const std::string what = fmt::format("width {}, outputs {}, threads {}", width, frameOutputsName(outputs), threads);
        EXPECT_EQ(pumped.faceId, unpumped.faceId) << what;
        EXPECT_EQ(pumped.triangleId, unpumped.triangleId) << what;
        EXPECT_EQ(firstDifference(pumped.depth, unpumped.depth), -1) << what;
        EXPECT_EQ(firstDifference(pumped.color, unpumped.color), -1) << what;
        if (has(outputs, FrameOutputs::FaceIds)) EXPECT_EQ(pumped.faceId, reference.faceId) << what;
        if (has(outputs, FrameOutputs::Color)) EXPECT_EQ(firstDifference(pumped.color, reference.color), -1) << what;
        if (outputs != FrameOutputs::DepthOnly) EXPECT_EQ(firstDifference(pumped.depth, reference.depth), -1) << what;
        EXPECT_EQ(pumped.stats.covered_pixels, reference.stats.covered_pixels) << what;
      }
  }
}

// Occlusion culling: each tile visits its triangles nearest first, so whatever the submission
// order the layers behind the nearest are rejected tile by tile, with the reference's image;
// the reference, in submission order, tests every fragment of layers drawn back to front.
TEST(Tiled, RejectsTrianglesBehindATilesFarthestDepth) {
  for (const char* order : {"front-to-back", "back-to-front"}) {
    const std::string name = std::string("builtin:layers?n=10&order=") + order;
    const Scene scene = loadScene(name);
    const Camera cam = resolveCamera(*scene.camera, 256, 192, scene.bounds());
    for (const char* f : {"f32:reversed", "u16:z", "u32:inv"}) {
      const DepthFormat format = DepthFormat::parse(f);
      const Frame reference = renderWith(scene, cam, format, RasterKind::HalfSpace, 1);
      const Frame fast = renderWith(scene, cam, format, RasterKind::Tiled, 1);
      expectIdentical(reference, fast, name + " " + f, "");
      // The nearest layer is drawn first: the others are rejected by the tile, block or row
      // bounds without computing their depth.
      EXPECT_GT(fast.stats.culled_occlusion, 0u) << order << " " << f;
      EXPECT_LT(fast.stats.depth_tests * 5, reference.stats.depth_tests) << order << " " << f;
      EXPECT_EQ(fast.stats.depth_writes, fast.stats.covered_pixels) << order << " " << f;  // no overdraw
      if (std::string(order) == "back-to-front")
        EXPECT_EQ(reference.stats.depth_writes, 10 * reference.stats.covered_pixels) << f;  // all overdraw
    }
  }
}

}  // namespace
}  // namespace hsr

// Binning and the tiles' cover bounds narrow each row of tiles to an edge by solving E >= bias
// for the column (edge.hpp, narrowTilesToEdge): the same tiles as testing, tile by tile, the
// corner where E is largest (binning) or smallest (tiles wholly inside), on random edges, boxes
// and starting intervals (steep, flat, horizontal and vertical edges, both biases, exact
// boundaries included by the small slopes).
TEST(Tiled, TilesNarrowedToAnEdgeAreThoseWhoseLargestOrSmallestCornerIsInside) {
  std::mt19937_64 random(7);
  constexpr int kTile = 64;
  size_t partial[2] = {0, 0};
  for (int it = 0; it < 600000; ++it) {
    const bool whole = it % 2;
    const int span = random() % 4 == 0 ? 100000 : 3000;
    const int minX = int(random() % uint64_t(span)), maxX = minX + int(random() % uint64_t(span));
    const int y0 = int(random() % uint64_t(span)), y1 = y0 + int(random() % kTile);
    auto coordinate = [&] { return int64_t(random() % uint64_t(span * 256)) - span * 80; };
    auto slope = [&] { return int64_t(random() % 2000001) - 1000000; };
    hsr::Edge e{slope(), slope(), coordinate(), coordinate(), 0};
    if (random() % 8 == 0) e.dy = 0;
    if (random() % 8 == 0) e.dx = 0;
    if (random() % 4 == 0) {
      e.dx %= 300;
      e.dy %= 300;
    }
    e.bias = int64_t(random() % 2);
    int first = minX / kTile, last = maxX / kTile;
    if (random() % 3 == 0) {
      first += int(random() % 3);
      last -= int(random() % 3);
      first = std::min(first, last + 1);
    }
    std::vector<int> expected;
    for (int tx = first; tx <= last; ++tx) {
      const int left = std::max(tx * kTile, minX), right = std::min(tx * kTile + kTile - 1, maxX);
      const int x = (e.dy < 0) != whole ? right : left;
      const int y = (e.dx > 0) != whole ? y1 : y0;
      if (e.at(hsr::centerFixed(x), hsr::centerFixed(y)) >= e.bias) expected.push_back(tx);
    }
    const int before[2] = {first, last};
    hsr::narrowTilesToEdge(e, whole, kTile, minX, maxX, y0, y1, first, last);
    ASSERT_LE(first, last + 1);
    std::vector<int> got;
    for (int tx = first; tx <= last; ++tx) got.push_back(tx);
    ASSERT_EQ(got, expected) << "edge dx " << e.dx << " dy " << e.dy << " a (" << e.ax << ", " << e.ay << ") bias "
                             << e.bias << (whole ? ", whole" : "") << ", box x " << minX << ".." << maxX << " y "
                             << y0 << ".." << y1;
    partial[whole] += !expected.empty() && (expected.front() != before[0] || expected.back() != before[1]);
  }
  EXPECT_GT(partial[0], 10000u);
  EXPECT_GT(partial[1], 10000u);  // the cases exercised include intervals cut on either side
}

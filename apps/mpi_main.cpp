// hsr-mpi: `hsr render` of one scene over the ranks of an MPI job. Every rank reads the flags and
// loads only its share of a scene JSON's mesh entries (any other scene: all of it, then keeps a
// spatial partition's share); the ranks agree on the whole scene's bounds, which place the camera,
// and on where each share's face ids start. Rank r renders its share over the full frame; the
// frames are composited by
// MPI (mpi/composite.hpp) and rank 0 writes the outputs as `hsr render` does. A failure on any rank
// ends every rank with one line on stderr and the same exit status (docs/distributed.md).
#include <hsr/hsr.hpp>
#include <hsr/subscene.hpp>

#include <CLI/CLI.hpp>
#include <fmt/core.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <iostream>
#include <limits>
#include <new>

#include <sys/resource.h>

#include "commands.hpp"
#include "mpi/composite.hpp"
#include "mpi/partition.hpp"
#include "render_cmd.hpp"

namespace hsr::mpi {
namespace {

// One stage's outcome on this rank: an exit status and, if it failed, the one line to print.
struct Outcome {
  int status = 0;
  std::string message;
};

template <class Stage>
Outcome attempt(Stage&& stage) {
  try {
    stage();
    return {};
  } catch (const InputError& e) {
    return {2, cli::cliMessage(e)};
  } catch (const std::bad_alloc&) {
    return {1, "error: out of memory"};
  } catch (const std::exception& e) {
    return {1, std::string("error: ") + e.what()};
  }
}

// Every rank's outcome of a stage, agreed on by all: the worst status (0: all succeeded). The
// lowest failing rank prints its message, so one line is printed however many ranks failed.
int agree(const Outcome& mine, MPI_Comm comm) {
  int rank = 0, ranks = 1, worst = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  MPI_Allreduce(&mine.status, &worst, 1, MPI_INT, MPI_MAX, comm);
  if (worst == 0) return 0;
  const int candidate = mine.status ? rank : ranks;
  int first = ranks;
  MPI_Allreduce(&candidate, &first, 1, MPI_INT, MPI_MIN, comm);
  if (rank == first) {
    std::string line = mine.message;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::cout.flush();
    std::cerr << "hsr-mpi: " << (rank > 0 ? fmt::format("rank {}: ", rank) : "") << line << std::endl;
  }
  return worst;
}

// This process's peak resident memory so far, in MB.
double peakResidentMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

double cpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

struct MpiFlags {
  std::string composite = "sparse";
  bool verbose = false;
};

// What only hsr-mpi refuses: images that do not composite by depth to one process's bits.
void checkCompositable(const cli::RenderFlags& f, const cli::Job& job, const Scene& held) {
  if (job.options.algorithm != "zbuffer")
    throw InputError("--algorithm " + job.options.algorithm +
                     ": hsr-mpi composites the z-buffer's images only (--algorithm zbuffer)");
  auto raster = job.options.params.find("raster");
  if (raster != job.options.params.end() && raster->second == "scanline")
    throw InputError("--param raster=scanline: its depth steps along spans, not the stored depth the ranks "
                     "composite by (use tiled, halfspace or binned)");
  if (!f.overdrawImage.empty())
    throw InputError("--overdraw-image: the ranks' overdraw does not add up to one process's (drop it)");
  const auto transparent = std::count_if(held.faceColors.begin(), held.faceColors.end(),
                                         [](const Rgba8& c) { return c.a != 255; });
  if (transparent)
    throw InputError(fmt::format("{}: {} transparent faces: hsr-mpi composites opaque surfaces only",
                                 job.sceneName, transparent));
}

// Per rank, gathered to rank 0 for --verbose and the statistics.
struct RankRecord {
  double firstEntry, entries, loadedTriangles, peakMb, triangles, renderMs, renderCpuMs, storedMs, waitMs, compositeMs, bytesSent, rectWidth, rectHeight;
};

// The counters of the ranks' frames that add up to the whole frame's.
std::vector<uint64_t> counters(const Stats& s) {
  return {s.triangles_clipped, s.triangles_degenerate, s.culled_backface, s.culled_frustum, s.culled_occlusion,
          s.depth_tests,       s.depth_writes,         s.color_writes,    s.memory_bytes};
}
void setCounters(Stats& s, const std::vector<uint64_t>& c) {
  s.triangles_clipped = c[0], s.triangles_degenerate = c[1], s.culled_backface = c[2], s.culled_frustum = c[3];
  s.culled_occlusion = c[4], s.depth_tests = c[5], s.depth_writes = c[6], s.color_writes = c[7];
  s.memory_bytes = c[8];
}

// What needs the whole scene on rank 0 (the ranks hold shares): the check against the reference,
// shadows, the attributes resolved from the ids, and the visibility counts (each mesh alone).
bool needsWholeScene(const cli::RenderFlags& f) {
  return f.verify || f.shadows || !f.instanceIds.empty() || !f.barycentric.empty() || !f.visibilityJson.empty();
}

// This rank's part of the scene as loaded, before the ranks agree on the whole's bounds and ids.
struct Loaded {
  ScenePart part;                // a share of a scene JSON's entries, or the whole scene
  cli::ViewFlags::CameraFlags camera;
};

// The whole scene's bounds and counts, and where this rank's share starts in its face and
// triangle order (each rank holds a run of entries, in rank order).
struct Totals {
  Bounds3 bounds;
  uint64_t faces = 0, triangles = 0, firstFace = 0, firstTriangle = 0;
};
Totals totalsOf(const Scene& share, MPI_Comm comm) {
  Totals t;
  const Bounds3 mine = share.bounds();
  MPI_Allreduce(&mine.lo[0], &t.bounds.lo[0], 3, MPI_DOUBLE, MPI_MIN, comm);
  MPI_Allreduce(&mine.hi[0], &t.bounds.hi[0], 3, MPI_DOUBLE, MPI_MAX, comm);
  const uint64_t counts[2] = {share.faceCount(), share.triangles.size()};
  uint64_t sums[2] = {0, 0}, before[2] = {0, 0};
  MPI_Allreduce(counts, sums, 2, MPI_UINT64_T, MPI_SUM, comm);
  MPI_Exscan(counts, before, 2, MPI_UINT64_T, MPI_SUM, comm);  // undefined on rank 0: stays 0
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  t.faces = sums[0], t.triangles = sums[1];
  if (rank > 0) t.firstFace = before[0], t.firstTriangle = before[1];
  return t;
}

// A loaded share as the part this rank renders: its faces and triangles are the whole scene's
// from `totals`' first ones on.
SceneRange shareRange(Scene share, const Totals& totals) {
  SceneRange r;
  r.globalFace.resize(share.faceCount());
  r.globalTriangle.resize(share.triangles.size());
  for (size_t i = 0; i < r.globalFace.size(); ++i) r.globalFace[i] = uint32_t(totals.firstFace + i);
  for (size_t i = 0; i < r.globalTriangle.size(); ++i) r.globalTriangle[i] = uint32_t(totals.firstTriangle + i);
  r.scene = std::move(share);
  return r;
}

int renderRanks(const cli::RenderFlags& f, const MpiFlags& m, MPI_Comm comm) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);

  // Flags, and this rank's share of the scene (only rank 0 writes, so only it checks the output
  // files). A scene JSON of several meshes is shared out by entries; anything else loads whole.
  cli::Job job;
  Loaded loaded;
  RankRecord record{};
  int status = agree(attempt([&] {
                       cli::checkRenderFlags(f, rank == 0);
                       job = cli::prepareRenderOptions(f);
                       loaded.camera = f.view.cameraFlags();
                       loaded.part = loadScenePart(job.sceneName, rank, ranks);
                       checkCompositable(f, job, loaded.part.scene);
                       if (loaded.part.whole) {
                         job.scene = std::move(loaded.part.scene);
                       } else if (rank == 0 && needsWholeScene(f)) {
                         job.scene = loadScene(job.sceneName);
                       } else {
                         job.scene.camera = loaded.part.scene.camera;
                         job.scene.light = loaded.part.scene.light;
                       }
                       record.firstEntry = double(loaded.part.firstEntry);
                       record.entries = double(loaded.part.entryCount);
                       record.loadedTriangles = double(loaded.part.whole ? job.scene.triangles.size()
                                                                         : loaded.part.scene.triangles.size());
                     }),
                     comm);
  if (status) return status;
  const auto start = std::chrono::steady_clock::now();  // the summary's wall time, as hsr render's

  // The whole scene's bounds place the camera; a share's ids start where the earlier ranks' end.
  const bool whole = loaded.part.whole;
  const Totals totals = whole ? Totals{job.scene.bounds(), job.scene.faceCount(), job.scene.triangles.size(), 0, 0}
                              : totalsOf(loaded.part.scene, comm);

  // This rank's share, rendered over the full frame with its stored depth.
  SceneRange part;
  Frame mine;
  std::vector<Sample> samples;
  Sample background{kBackground, std::numeric_limits<float>::infinity(), -1, -1, job.options.background};
  status = agree(attempt([&] {
                   if (totals.faces == 0) throw InputError(job.sceneName + ": no polygon faces to render");
                   f.view.placeCamera(job, loaded.camera, totals.bounds);
                   if (whole) {
                     const auto groups = partitionFaces(job.scene, ranks);
                     part = extractFaces(job.scene, groups[size_t(rank)]);
                     if (rank != 0) job.scene = Scene{};  // rank 0 keeps it for --verify, --shadows, attributes
                   } else {
                     part = shareRange(std::move(loaded.part.scene), totals);
                   }
                   RenderOptions options = job.options;
                   options.verify = false;
                   if (options.outputs != FrameOutputs::DepthOnly) options.outputs = options.outputs | FrameOutputs::FaceIds;
                   const double cpu0 = cpuMs();
                   const auto t0 = std::chrono::steady_clock::now();
                   hsr::render(part.scene, job.camera, options, mine);
                   record.renderMs = cli::millisecondsSince(t0);
                   record.renderCpuMs = cpuMs() - cpu0;
                   const auto t1 = std::chrono::steady_clock::now();
                   OcclusionBuffer stored;
                   stored.render(part.scene, job.camera, {options.depthFormat, options.cull, options.threads, options.tiled});
                   samples = samplesOf(mine, stored, part, options);
                   record.storedMs = cli::millisecondsSince(t1);
                 }),
                 comm);
  if (status) return status;

  // The ranks wait for the slowest render here, so that the composite's time is its own.
  const auto waitStart = std::chrono::steady_clock::now();
  MPI_Barrier(comm);
  record.waitMs = cli::millisecondsSince(waitStart);
  std::vector<Pixel> image;
  const CompositeStats cs = composite(samples, job.camera.width, job.camera.height, background,
                                      m.composite == "dense" ? Mode::Dense : Mode::Sparse, comm, image);
  samples = {};
  record.triangles = double(part.scene.triangles.size());
  record.peakMb = peakResidentMb();
  record.compositeMs = cs.ms;
  record.bytesSent = double(cs.bytesSent);
  record.rectWidth = std::max(0, cs.rect[2] - cs.rect[0] + 1);
  record.rectHeight = std::max(0, cs.rect[3] - cs.rect[1] + 1);
  std::vector<uint64_t> mineCounts = counters(mine.stats), sums(mineCounts.size());
  MPI_Reduce(mineCounts.data(), sums.data(), int(sums.size()), MPI_UINT64_T, MPI_SUM, 0, comm);
  std::vector<RankRecord> records(size_t(rank == 0 ? ranks : 0));
  constexpr int kFields = sizeof(RankRecord) / sizeof(double);
  MPI_Gather(&record, kFields, MPI_DOUBLE, records.data(), kFields, MPI_DOUBLE, 0, comm);

  // Rank 0: the composite as a frame, then what `hsr render` does with a frame.
  Outcome written;
  if (rank == 0) {
    written = attempt([&] {
      Frame frame;
      frame.allocate(job.camera.width, job.camera.height, job.options.outputs);
      uint64_t covered = 0;
      for (size_t i = 0; i < image.size(); ++i) {
        const Pixel& p = image[i];
        frame.depth[i] = p.depth;
        if (!frame.faceId.empty()) frame.faceId[i] = p.face;
        if (!frame.triangleId.empty()) frame.triangleId[i] = p.triangle;
        if (!frame.color.empty()) frame.color[i] = p.color;
        covered += p.depth != std::numeric_limits<float>::infinity();
      }
      image = {};
      frame.stats = mine.stats;
      Stats& st = frame.stats;
      setCounters(st, sums);
      st.faces = totals.faces;
      st.triangles = totals.triangles;
      st.covered_pixels = covered;
      double renderMax = 0, storedMax = 0, compositeMax = 0, bytesMax = 0, bytesTotal = 0;
      for (const RankRecord& r : records) {
        renderMax = std::max(renderMax, r.renderMs), storedMax = std::max(storedMax, r.storedMs);
        compositeMax = std::max(compositeMax, r.compositeMs), bytesMax = std::max(bytesMax, r.bytesSent);
        bytesTotal += r.bytesSent;
      }
      st.time_ms = {{"render_max", renderMax}, {"stored_depth_max", storedMax}, {"composite_max", compositeMax}};
      st.setDetail("mpi_ranks", uint64_t(ranks));
      st.setDetail("mpi_composite", m.composite);
      st.setDetail("mpi_load", whole ? "whole" : "share");
      st.setDetail("mpi_bytes_sent", uint64_t(bytesTotal));
      st.setDetail("mpi_bytes_sent_max", uint64_t(bytesMax));
      if (f.verify) verifyFrame(job.scene, job.camera, job.options, frame);  // rank 0 holds the whole scene
      cli::finishRender(f, job, frame, start);
      if (f.quiet || f.json || f.stats == "-") return;
      fmt::print("  mpi: {} ranks, {} composite, scene loaded {}, sent {:.1f} MB in all, {:.1f} MB at most per rank\n", ranks,
                 m.composite, whole ? "whole by every rank" : "in shares of its entries", bytesTotal / 1e6, bytesMax / 1e6);
      if (!m.verbose) return;
      for (int r = 0; r < ranks; ++r) {
        const RankRecord& x = records[size_t(r)];
        const std::string loadedWhat =
            whole ? fmt::format("the whole scene ({:.0f} triangles)", x.loadedTriangles)
                  : fmt::format("entries {:.0f}..{:.0f} ({:.0f} triangles)", x.firstEntry, x.firstEntry + x.entries,
                                x.loadedTriangles);
        fmt::print("  rank {}: loaded {}, peak memory {:.1f} MB; triangles {:.0f}, covers {:.0f}x{:.0f}, render {:.2f} "
                   "ms ({:.2f} ms CPU), stored depth {:.2f} ms, waited {:.2f} ms, composite {:.2f} ms, sent {:.0f} "
                   "bytes\n",
                   r, loadedWhat, x.peakMb, x.triangles, x.rectWidth, x.rectHeight, x.renderMs, x.renderCpuMs,
                   x.storedMs, x.waitMs, x.compositeMs, x.bytesSent);
      }
    });
  }
  return agree(written, comm);
}

int run(int argc, char** argv, MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  CLI::App app("hsr-mpi " HSR_VERSION " - one scene rendered by the ranks of an MPI job, composited by depth",
               "hsr-mpi");
  app.set_version_flag("--version", "hsr-mpi " HSR_VERSION);
  app.require_subcommand(1);
  app.footer("Run under mpirun: mpirun -n 4 hsr-mpi render SCENE ... (docs/distributed.md).\n"
             "Exit status: 0 success, 2 bad usage or bad input (one line on stderr), 1 any other failure.");
  CLI::App* cmd = app.add_subcommand("render", "Render a scene, each rank its share of the meshes, composited");
  cli::RenderFlags f;
  MpiFlags m;
  cli::declareRenderFlags(*cmd, &f);
  std::string maxMemory;
  CLI::Option* maxMemoryFlag = cmd->add_option("--max-memory", maxMemory, "As hsr render's, per rank")->type_name("SIZE");
  const char* group = "Compositing (hsr-mpi)";
  cmd->add_option("--composite", m.composite,
                  "sparse: each rank sends each strip's owner only the part of its covered rectangle in the strip "
                  "(MPI_Alltoallv); dense: whole frames reduced by MPI_Reduce_scatter_block")
      ->check(CLI::IsMember({"sparse", "dense"}))
      ->capture_default_str()
      ->group(group);
  cmd->add_flag("--verbose", m.verbose, "Also a line per rank: its triangles, covered rectangle, times and bytes sent")
      ->group(group);
  cmd->footer("Examples:\n"
              "  mpirun -n 4 hsr-mpi render builtin:city --size 1920x1080 --ids ids.png --depth depth.npy\n"
              "  mpirun -n 8 hsr-mpi render scene.json --camera cam.json -o color.png --verify --verbose");

  bool helped = false;  // --help or --version: rank 0 printed them
  Outcome parsed = attempt([&] {
    try {
      app.parse(argc, argv);
    } catch (const CLI::Success& e) {
      if (rank == 0) app.exit(e);
      helped = true;
      return;
    } catch (const CLI::ParseError& e) {
      throw InputError(std::string(e.what()) + " (see 'hsr-mpi render --help')");
    }
    if (maxMemoryFlag->count()) hsr::setMemoryLimit(hsr::parseMemorySize(maxMemory, "--max-memory"));
  });
  if (helped) return 0;
  return parsed.status ? agree(parsed, comm) : renderRanks(f, m, comm);
}

}  // namespace
}  // namespace hsr::mpi

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int status = 1;
  try {
    status = hsr::mpi::run(argc, argv, MPI_COMM_WORLD);
  } catch (const std::exception& e) {  // after the ranks agreed: a failure of this rank alone
    std::cerr << "hsr-mpi: error: " << e.what() << std::endl;
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Finalize();
  return status;
}

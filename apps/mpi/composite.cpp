// Compositing for hsr-mpi (composite.hpp): keys made from the stored depth, the nearest sample per
// pixel by a user-defined MPI_Op or by direct send, and the gather of the strips to rank 0.
#include "composite.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hsr::mpi {
namespace {

// The nearer of two samples; equal keys are the same face's sample (each face lies on one rank),
// or both the background: either way the same payload, so the operator is commutative.
void nearestOp(void* in, void* inout, int* count, MPI_Datatype*) {
  const Sample* a = static_cast<const Sample*>(in);
  Sample* b = static_cast<Sample*>(inout);
  for (int i = 0; i < *count; ++i)
    if (a[i].key < b[i].key) b[i] = a[i];
}

// The MPI type of a Sample (24 bytes, moved whole) and the operator, for one composite.
struct SampleType {
  MPI_Datatype type;
  MPI_Op op;
  SampleType() {
    MPI_Type_contiguous(int(sizeof(Sample)), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    MPI_Op_create(&nearestOp, 1, &op);
  }
  ~SampleType() {
    MPI_Op_free(&op);
    MPI_Type_free(&type);
  }
};

// Rows [first, end) of strip s of `parts` over `height` rows.
int stripRow(int s, int parts, int height) { return int(int64_t(height) * s / parts); }

// The rectangle of the non-background samples: x0, y0, x1, y1 (x1 < x0 when there are none).
void coveredRect(const std::vector<Sample>& samples, int width, int height, int rect[4]) {
  rect[0] = width, rect[1] = height, rect[2] = -1, rect[3] = -1;
  for (int y = 0; y < height; ++y) {
    const Sample* row = samples.data() + size_t(y) * size_t(width);
    int x0 = 0;
    while (x0 < width && row[x0].key == kBackground) ++x0;
    if (x0 == width) continue;
    int x1 = width - 1;
    while (row[x1].key == kBackground) --x1;
    rect[0] = std::min(rect[0], x0), rect[2] = std::max(rect[2], x1);
    rect[1] = std::min(rect[1], y), rect[3] = y;
  }
  if (rect[2] < rect[0]) rect[0] = 0, rect[1] = 0, rect[2] = -1, rect[3] = -1;
}

// Rows [y0, y1] of `rect` that lie in rows [s0, s1): y0 > y1 when none.
void rowsIn(const int rect[4], int s0, int s1, int& y0, int& y1) {
  y0 = std::max(rect[1], s0);
  y1 = std::min(rect[3], s1 - 1);
  if (rect[2] < rect[0]) y0 = 1, y1 = 0;
}

}  // namespace

uint32_t nearestFirst(double stored, const DepthFormat& format) {
  uint32_t bits = format.storage == DepthStorage::F32 ? std::bit_cast<uint32_t>(float(stored) + 0.0f)
                                                      : uint32_t(stored);
  return format.greaterWins() ? ~bits : bits;
}

std::vector<Sample> samplesOf(const Frame& frame, const OcclusionBuffer& stored, const SceneRange& part,
                              const RenderOptions& options) {
  const DepthFormat& format = options.depthFormat;
  const double clear = format.quantize(format.clearValue());
  const bool ids = !frame.faceId.empty(), triangles = !frame.triangleId.empty(), colors = !frame.color.empty();
  const bool recolor = colors && options.shading == Shading::FaceId;
  std::vector<Sample> out(size_t(frame.width) * size_t(frame.height));
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x) {
      const size_t i = frame.index(x, y);
      Sample& s = out[i];
      s.depth = frame.depth[i];
      s.face = ids ? frame.faceId[i] : -1;
      s.triangle = triangles ? frame.triangleId[i] : -1;
      s.color = colors ? frame.color[i] : Rgba8{};
      // With face ids, a pixel without one is the background; only drawn pixels need the stored value.
      const double value = ids && s.face < 0 ? clear : stored.storedAt(x, y);
      if (value == clear) {
        s.key = kBackground;
        continue;
      }
      if (s.face >= 0) s.face = int32_t(part.globalFace[size_t(s.face)]);
      if (s.triangle >= 0) s.triangle = int32_t(part.globalTriangle[size_t(s.triangle)]);
      if (recolor) s.color = faceIdColor(uint32_t(s.face));
      s.key = uint64_t(nearestFirst(value, format)) << 32 | uint32_t(std::max(s.face, 0));
    }
  return out;
}

CompositeStats composite(const std::vector<Sample>& samples, int width, int height, const Sample& background,
                         Mode mode, MPI_Comm comm, std::vector<Pixel>& image) {
  const SampleType kType;
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const auto start = std::chrono::steady_clock::now();
  CompositeStats stats;
  coveredRect(samples, width, height, stats.rect);
  const size_t pixelCount = size_t(width) * size_t(height);
  std::vector<Sample> strip;  // this rank's part of the image
  const size_t n = size_t(ranks);
  std::vector<int> counts(n), displs(n);

  if (mode == Mode::Dense) {
    // Blocks of equal size (the last padded with background): rank r owns pixels [r B, (r+1) B).
    const size_t block = (pixelCount + size_t(ranks) - 1) / size_t(ranks);
    if (block > size_t(std::numeric_limits<int>::max())) throw std::length_error("image too large for one MPI block");
    std::vector<Sample> padded;
    const Sample* send = samples.data();
    if (block * size_t(ranks) != pixelCount) {
      padded = samples;
      padded.resize(block * size_t(ranks), background);
      send = padded.data();
    }
    strip.resize(block);
    MPI_Reduce_scatter_block(send, strip.data(), int(block), kType.type, kType.op, comm);
    // A reduce-scatter moves at least (K - 1)/K of the frame out of each rank (ring or pairwise).
    stats.bytesSent = uint64_t(ranks - 1) * block * sizeof(Sample);
    for (int r = 0; r < ranks; ++r) counts[size_t(r)] = int(block), displs[size_t(r)] = int(block) * r;
  } else {
    // Direct send: rank r owns rows [stripRow(r), stripRow(r + 1)); every rank sends it the part
    // of its covered rectangle in those rows, row by row.
    std::vector<int> rects(4 * n);
    MPI_Allgather(stats.rect, 4, MPI_INT, rects.data(), 4, MPI_INT, comm);
    std::vector<int> sendCounts(n), sendDispls(n), recvCounts(n), recvDispls(n);
    const int rectWidth = stats.rect[2] - stats.rect[0] + 1;
    std::vector<Sample> send;
    for (int s = 0; s < ranks; ++s) {
      int y0, y1;
      rowsIn(stats.rect, stripRow(s, ranks, height), stripRow(s + 1, ranks, height), y0, y1);
      sendDispls[size_t(s)] = int(send.size());
      for (int y = y0; y <= y1; ++y) {
        const Sample* row = samples.data() + size_t(y) * size_t(width) + size_t(stats.rect[0]);
        send.insert(send.end(), row, row + rectWidth);
      }
      sendCounts[size_t(s)] = int(send.size()) - sendDispls[size_t(s)];
      if (s != rank) stats.bytesSent += uint64_t(sendCounts[size_t(s)]) * sizeof(Sample);
    }
    const int s0 = stripRow(rank, ranks, height), s1 = stripRow(rank + 1, ranks, height);
    size_t received = 0;
    for (int r = 0; r < ranks; ++r) {
      int y0, y1;
      const int* rect = &rects[size_t(4 * r)];
      rowsIn(rect, s0, s1, y0, y1);
      recvDispls[size_t(r)] = int(received);
      recvCounts[size_t(r)] = y1 >= y0 ? (y1 - y0 + 1) * (rect[2] - rect[0] + 1) : 0;
      received += size_t(recvCounts[size_t(r)]);
    }
    std::vector<Sample> recv(received);
    MPI_Alltoallv(send.data(), sendCounts.data(), sendDispls.data(), kType.type, recv.data(), recvCounts.data(),
                  recvDispls.data(), kType.type, comm);
    // The nearest of what every rank sent, in rank order (any order gives the same: see nearestOp).
    strip.assign(size_t(s1 - s0) * size_t(width), background);
    for (int r = 0; r < ranks; ++r) {
      int y0, y1;
      const int* rect = &rects[size_t(4 * r)];
      rowsIn(rect, s0, s1, y0, y1);
      const Sample* in = recv.data() + recvDispls[size_t(r)];
      for (int y = y0; y <= y1; ++y) {
        Sample* out = strip.data() + size_t(y - s0) * size_t(width) + size_t(rect[0]);
        int n = rect[2] - rect[0] + 1;
        nearestOp(const_cast<Sample*>(in), out, &n, nullptr);
        in += n;
      }
    }
    for (int r = 0; r < ranks; ++r) {
      counts[size_t(r)] = (stripRow(r + 1, ranks, height) - stripRow(r, ranks, height)) * width;
      displs[size_t(r)] = stripRow(r, ranks, height) * width;
    }
  }

  // The strips to rank 0, without their keys.
  std::vector<Pixel> pixels(strip.size());
  std::transform(strip.begin(), strip.end(), pixels.begin(),
                 [](const Sample& s) { return Pixel{s.depth, s.face, s.triangle, s.color}; });
  strip = {};
  MPI_Datatype pixelType;
  MPI_Type_contiguous(int(sizeof(Pixel)), MPI_BYTE, &pixelType);
  MPI_Type_commit(&pixelType);
  if (rank == 0) image.resize(size_t(displs.back()) + size_t(counts.back()));
  MPI_Gatherv(pixels.data(), int(pixels.size()), pixelType, rank == 0 ? image.data() : nullptr, counts.data(),
              displs.data(), pixelType, 0, comm);
  MPI_Type_free(&pixelType);
  if (rank == 0) image.resize(pixelCount);
  if (rank != 0) stats.bytesSent += pixels.size() * sizeof(Pixel);
  stats.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace hsr::mpi

// Sort-last compositing of the ranks' frames over MPI: each pixel's nearest surface, decided by a
// 64-bit key that orders as the single-process z-buffer does (stored depth, then submission
// order). Called by every rank of hsr-mpi (main.cpp) with its frame; rank 0 gets the image.
#pragma once
#include <hsr/hsr.hpp>
#include <hsr/subscene.hpp>

#include <mpi.h>

#include <cstdint>
#include <vector>

namespace hsr::mpi {

/// One pixel of a rank's frame as it travels: the key and the winner's payload.
struct Sample {
  uint64_t key;      // (nearest-first stored depth << 32) | global face id; kBackground: nothing
  float depth;       // eye depth, +inf for the background
  int32_t face;      // global face id, -1 for the background
  int32_t triangle;  // global triangle id, -1 for the background
  Rgba8 color;
};
static_assert(sizeof(Sample) == 24, "a Sample travels as 24 bytes");

/// A pixel of the composited image as gathered to rank 0: the winner's payload without its key.
struct Pixel {
  float depth;
  int32_t face;
  int32_t triangle;
  Rgba8 color;
};
static_assert(sizeof(Pixel) == 16, "a Pixel travels as 16 bytes");
inline constexpr uint64_t kBackground = ~uint64_t(0);

/// The 32 bits of a stored depth value (the format's code or float, as OcclusionBuffer::storedAt
/// gives it) that order nearest first as unsigned integers.
uint32_t nearestFirst(double stored, const DepthFormat& format);

/// A rank's frame as samples, row 0 first: keys from `stored` (the same view's stored depth), ids
/// made global through `part`, and with Shading::FaceId the colours of the global ids.
std::vector<Sample> samplesOf(const Frame& frame, const OcclusionBuffer& stored, const SceneRange& part,
                              const RenderOptions& options);

enum class Mode { Sparse, Dense };

/// What one rank did and sent while compositing.
struct CompositeStats {
  uint64_t bytesSent = 0;        // to other ranks, counted as what this rank hands MPI (dense: as modelled)
  int rect[4] = {0, 0, -1, -1};  // x0, y0, x1, y1 of the pixels this rank covers (empty: x1 < x0)
  double ms = 0;                 // wall time of the exchange, the reduction and the gather
};

/// Composites every rank's `samples` (width x height, the same size on every rank) into rank 0's
/// `image` (resized there; left empty elsewhere). `background` is the sample of an uncovered pixel.
/// Sparse: each rank sends to each strip's owner the part of its covered rectangle in that strip
/// (MPI_Alltoallv), the owner keeps the nearest; Dense: MPI_Reduce_scatter_block of whole frames
/// with a user-defined MPI_Op. Then the strips are gathered to rank 0.
CompositeStats composite(const std::vector<Sample>& samples, int width, int height, const Sample& background,
                         Mode mode, MPI_Comm comm, std::vector<Pixel>& image);

}  // namespace hsr::mpi

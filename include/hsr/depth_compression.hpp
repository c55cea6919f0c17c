// Lossless depth-buffer compression, as GPUs store depth tiles to save memory bandwidth (the
// Ukrainian paper's list of z-buffer improvements): the buffer in 8x8 blocks, each kept as the
// smallest of
//   clear   every value the clear value (1 byte);
//   plane   a plane in the values' bits, base + x dx + y dy, with each value's residual from it in
//           the fewest bits the block needs (13 bytes + 64 residuals; 0 bits when the plane is exact);
//   raw     the 64 values (1 + 4 x 64 bytes).
// Bit-exact both ways (decompressDepth(compressDepth(v)) == v). Used by `hsr compare`'s study
// (docs/memory.md: compression ratios per scene and depth format).
#pragma once
#include <hsr/depth_format.hpp>
#include <hsr/occlusion.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace hsr {

/// A compressed depth buffer: its size, the blocks' bytes in row order of blocks, and how many
/// blocks each way was chosen.
struct CompressedDepth {
  int width = 0, height = 0;
  uint32_t clear = 0;           // the clear value's word
  std::vector<uint8_t> bytes;   // every block, each starting with its header byte
  uint64_t clearBlocks = 0, planeBlocks = 0, residualBlocks = 0, rawBlocks = 0;
  uint64_t rawBytes() const { return uint64_t(width) * uint64_t(height) * 4; }
  double ratio() const { return bytes.empty() ? 0.0 : double(rawBytes()) / double(bytes.size()); }
};

/// Block edge in pixels; blocks at the right and bottom edges hold the pixels that exist.
inline constexpr int kDepthBlock = 8;

/// `words` (width x height, row by row: each pixel's stored value as a 32-bit word) compressed;
/// `clear` is the word of an untouched pixel. Throws std::invalid_argument on a size mismatch.
CompressedDepth compressDepth(std::span<const uint32_t> words, int width, int height, uint32_t clear);
/// The words again, bit for bit. Throws std::invalid_argument for bytes that are not a compressed
/// buffer of that size (truncated, or a block header out of range).
std::vector<uint32_t> decompressDepth(const CompressedDepth& compressed);

/// The stored values of a rendered buffer as 32-bit words: an integer format's code, a float's
/// bits; and the clear value's word of `format`.
std::vector<uint32_t> storedDepthWords(const OcclusionBuffer& buffer, const DepthFormat& format);
uint32_t clearDepthWord(const DepthFormat& format);

}  // namespace hsr

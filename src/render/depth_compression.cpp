// Lossless depth-buffer compression (include/hsr/depth_compression.hpp): 8x8 blocks kept clear,
// as a plane with packed residuals, or raw, whichever is smallest.
#include <hsr/depth_compression.hpp>

#include <algorithm>
#include <bit>
#include <limits>
#include <stdexcept>
#include <string>

namespace hsr {
namespace {

constexpr uint8_t kClear = 0, kRaw = 0xFF;  // headers; 1 + b: a plane with b-bit residuals (b <= 32)
constexpr int kMaxResidualBits = 32;

// The pixels of one block: [x0, x0 + w) x [y0, y0 + h).
struct Block {
  int x0, y0, w, h;
  int count() const { return w * h; }
};

// A plane in the words' bits: base at the block's first pixel, steps along x and y.
struct WordPlane {
  uint32_t base = 0;
  int32_t dx = 0, dy = 0;
  int64_t at(int x, int y) const { return int64_t(base) + int64_t(x) * dx + int64_t(y) * dy; }
};

uint64_t zigzag(int64_t r) { return (uint64_t(r) << 1) ^ uint64_t(r >> 63); }
int64_t unzigzag(uint64_t z) { return int64_t(z >> 1) ^ -int64_t(z & 1); }

void putWord(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// Reads the compressed bytes in order, refusing to run past their end.
class Reader {
 public:
  explicit Reader(const std::vector<uint8_t>& bytes) : bytes_(bytes) {}
  uint8_t byte() {
    need(1);
    return bytes_[at_++];
  }
  uint32_t word() {
    need(4);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t(bytes_[at_++]) << (8 * i);
    return v;
  }
  // `count` values of `bits` bits each, packed least significant bit first.
  void bitsInto(int bits, int count, std::vector<uint64_t>& out) {
    const size_t n = (size_t(bits) * size_t(count) + 7) / 8;
    need(n);
    out.assign(size_t(count), 0);
    for (int i = 0; i < count; ++i)
      for (int b = 0; b < bits; ++b) {
        const size_t bit = size_t(i) * size_t(bits) + size_t(b);
        out[size_t(i)] |= uint64_t(bytes_[at_ + bit / 8] >> (bit % 8) & 1) << b;
      }
    at_ += n;
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  void need(size_t n) const {
    if (bytes_.size() - at_ < n) throw std::invalid_argument("decompressDepth: the bytes end inside a block");
  }
  const std::vector<uint8_t>& bytes_;
  size_t at_ = 0;
};

void putBits(std::vector<uint8_t>& out, const std::vector<uint64_t>& values, int bits) {
  const size_t first = out.size();
  out.resize(first + (size_t(bits) * values.size() + 7) / 8, 0);
  for (size_t i = 0; i < values.size(); ++i)
    for (int b = 0; b < bits; ++b) {
      const size_t bit = i * size_t(bits) + size_t(b);
      out[first + bit / 8] |= uint8_t((values[i] >> b & 1) << (bit % 8));
    }
}

// The block's plane from its first pixel and its neighbours along x and y (0 where the block has
// no such neighbour); nullopt-like false when a step does not fit 32 bits.
bool planeOf(std::span<const uint32_t> words, int width, const Block& b, WordPlane& plane) {
  const auto word = [&](int x, int y) { return int64_t(words[size_t(b.y0 + y) * size_t(width) + size_t(b.x0 + x)]); };
  const int64_t dx = b.w > 1 ? word(1, 0) - word(0, 0) : 0, dy = b.h > 1 ? word(0, 1) - word(0, 0) : 0;
  constexpr int64_t lo = std::numeric_limits<int32_t>::min(), hi = std::numeric_limits<int32_t>::max();
  if (dx < lo || dx > hi || dy < lo || dy > hi) return false;
  plane = {uint32_t(word(0, 0)), int32_t(dx), int32_t(dy)};
  return true;
}

// Appends block b, choosing the smallest way, and counts it.
void compressBlock(std::span<const uint32_t> words, int width, uint32_t clear, const Block& b, CompressedDepth& out) {
  const auto word = [&](int x, int y) { return words[size_t(b.y0 + y) * size_t(width) + size_t(b.x0 + x)]; };
  bool allClear = true;
  for (int y = 0; y < b.h; ++y)
    for (int x = 0; x < b.w; ++x) allClear &= word(x, y) == clear;
  if (allClear) {
    out.bytes.push_back(kClear);
    ++out.clearBlocks;
    return;
  }
  WordPlane plane;
  std::vector<uint64_t> residuals;
  int bits = kMaxResidualBits + 1;
  if (planeOf(words, width, b, plane)) {
    uint64_t widest = 0;
    for (int y = 0; y < b.h; ++y)
      for (int x = 0; x < b.w; ++x) {
        residuals.push_back(zigzag(int64_t(word(x, y)) - plane.at(x, y)));
        widest |= residuals.back();
      }
    bits = std::bit_width(widest);
  }
  const size_t planeBytes = 13 + (size_t(bits) * size_t(b.count()) + 7) / 8, rawBytes = 1 + 4 * size_t(b.count());
  if (bits <= kMaxResidualBits && planeBytes < rawBytes) {
    out.bytes.push_back(uint8_t(1 + bits));
    putWord(out.bytes, plane.base);
    putWord(out.bytes, uint32_t(plane.dx));
    putWord(out.bytes, uint32_t(plane.dy));
    putBits(out.bytes, residuals, bits);
    ++(bits == 0 ? out.planeBlocks : out.residualBlocks);
    return;
  }
  out.bytes.push_back(kRaw);
  for (int y = 0; y < b.h; ++y)
    for (int x = 0; x < b.w; ++x) putWord(out.bytes, word(x, y));
  ++out.rawBlocks;
}

// Calls f(block) for every block of a width x height buffer, in row order of blocks.
template <class F>
void forEachBlock(int width, int height, F&& f) {
  for (int y0 = 0; y0 < height; y0 += kDepthBlock)
    for (int x0 = 0; x0 < width; x0 += kDepthBlock)
      f(Block{x0, y0, std::min(kDepthBlock, width - x0), std::min(kDepthBlock, height - y0)});
}

}  // namespace

CompressedDepth compressDepth(std::span<const uint32_t> words, int width, int height, uint32_t clear) {
  if (width < 0 || height < 0 || words.size() != size_t(width) * size_t(height))
    throw std::invalid_argument("compressDepth: " + std::to_string(words.size()) + " words for a " +
                                std::to_string(width) + "x" + std::to_string(height) + " buffer");
  CompressedDepth out;
  out.width = width;
  out.height = height;
  out.clear = clear;
  forEachBlock(width, height, [&](const Block& b) { compressBlock(words, width, clear, b, out); });
  return out;
}

std::vector<uint32_t> decompressDepth(const CompressedDepth& c) {
  std::vector<uint32_t> words(size_t(c.width) * size_t(c.height));
  Reader in(c.bytes);
  std::vector<uint64_t> residuals;
  forEachBlock(c.width, c.height, [&](const Block& b) {
    const auto word = [&](int x, int y) -> uint32_t& { return words[size_t(b.y0 + y) * size_t(c.width) + size_t(b.x0 + x)]; };
    const uint8_t header = in.byte();
    if (header == kClear) {
      for (int y = 0; y < b.h; ++y)
        for (int x = 0; x < b.w; ++x) word(x, y) = c.clear;
    } else if (header == kRaw) {
      for (int y = 0; y < b.h; ++y)
        for (int x = 0; x < b.w; ++x) word(x, y) = in.word();
    } else if (header <= 1 + kMaxResidualBits) {
      WordPlane plane;
      plane.base = in.word();
      plane.dx = int32_t(in.word());
      plane.dy = int32_t(in.word());
      in.bitsInto(header - 1, b.count(), residuals);
      for (int y = 0; y < b.h; ++y)
        for (int x = 0; x < b.w; ++x)
          word(x, y) = uint32_t(plane.at(x, y) + unzigzag(residuals[size_t(y * b.w + x)]));
    } else {
      throw std::invalid_argument("decompressDepth: block header " + std::to_string(header) + " out of range");
    }
  });
  if (!in.done()) throw std::invalid_argument("decompressDepth: bytes left over after the last block");
  return words;
}

namespace {

// A stored value (as OcclusionBuffer::storedAt gives it) as its word.
uint32_t wordOf(double stored, const DepthFormat& format) {
  if (format.storage == DepthStorage::F32) return std::bit_cast<uint32_t>(float(stored));
  return uint32_t(stored);
}

}  // namespace

uint32_t clearDepthWord(const DepthFormat& format) { return wordOf(format.quantize(format.clearValue()), format); }

std::vector<uint32_t> storedDepthWords(const OcclusionBuffer& buffer, const DepthFormat& format) {
  std::vector<uint32_t> words;
  words.reserve(size_t(buffer.width()) * size_t(buffer.height()));
  for (int y = 0; y < buffer.height(); ++y)
    for (int x = 0; x < buffer.width(); ++x) words.push_back(wordOf(buffer.storedAt(x, y), format));
  return words;
}

}  // namespace hsr

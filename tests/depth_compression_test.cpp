// Lossless depth compression (hsr/depth_compression.hpp): bit-exact round trips of real buffers in
// every depth format, each block kind where it should be, and bad bytes refused.
#include <gtest/gtest.h>

#include <hsr/hsr.hpp>

#include <stdexcept>
#include <string>

namespace hsr {
namespace {

std::vector<uint32_t> bufferWords(const Scene& scene, const DepthFormat& format, int w, int h) {
  OcclusionBuffer buffer;
  OcclusionOptions options;
  options.depthFormat = format;
  options.threads = 1;
  buffer.render(scene, resolveCamera(frameBounds(scene.bounds()), w, h, scene.bounds()), options);
  return storedDepthWords(buffer, format);
}

TEST(DepthCompression, RealBuffersRoundTripBitForBitInEveryFormat) {
  for (const char* name : {"builtin:cubes", "builtin:city", "builtin:sphere?n=2000", "builtin:random?n=300",
                           "builtin:layers", "builtin:zfight", "builtin:interpenetrate"}) {
    const Scene scene = loadScene(name);
    for (const char* f : {"u16:z", "u24:z", "u32:z", "f32:z", "f32:reversed", "u24:linear", "u16:inv"})
      for (auto [w, h] : {std::pair{97, 61}, std::pair{320, 240}}) {
        const DepthFormat format = DepthFormat::parse(f);
        const std::vector<uint32_t> words = bufferWords(scene, format, w, h);
        const CompressedDepth c = compressDepth(words, w, h, clearDepthWord(format));
        ASSERT_EQ(decompressDepth(c), words) << name << " " << f << " " << w << "x" << h;
        const uint64_t blocks = uint64_t((w + 7) / 8) * uint64_t((h + 7) / 8);
        EXPECT_EQ(c.clearBlocks + c.planeBlocks + c.residualBlocks + c.rawBlocks, blocks);
        EXPECT_LE(c.bytes.size(), blocks * (1 + 4 * 64)) << "never larger than raw blocks with their headers";
      }
  }
}

TEST(DepthCompression, ClearPlanesAndNoiseTakeTheirOwnKinds) {
  const int w = 64, h = 32;
  const uint32_t clear = 0xFFFFFFu;
  // Untouched: a byte a block.
  const CompressedDepth cleared = compressDepth(std::vector<uint32_t>(w * h, clear), w, h, clear);
  EXPECT_EQ(cleared.bytes.size(), 32u);
  EXPECT_EQ(cleared.clearBlocks, 32u);
  // A plane of integer codes: exact planes, 13 bytes a block.
  std::vector<uint32_t> plane(w * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) plane[size_t(y * w + x)] = uint32_t(1000000 + 37 * x - 11 * y);
  const CompressedDepth planes = compressDepth(plane, w, h, clear);
  EXPECT_EQ(planes.planeBlocks, 32u);
  EXPECT_EQ(planes.bytes.size(), 32u * 13u);
  EXPECT_EQ(decompressDepth(planes), plane);
  // A plane with rounding (+-1): small residuals, far fewer bytes than raw.
  for (size_t i = 0; i < plane.size(); ++i) plane[i] += uint32_t(i * 2654435761u >> 31);
  const CompressedDepth rounded = compressDepth(plane, w, h, clear);
  EXPECT_EQ(rounded.residualBlocks + rounded.planeBlocks, 32u);
  EXPECT_LE(rounded.bytes.size(), 32u * (13u + 40u));
  EXPECT_EQ(decompressDepth(rounded), plane);
  // Noise: raw.
  for (size_t i = 0; i < plane.size(); ++i) plane[i] = uint32_t(i * 2654435761u);
  const CompressedDepth noise = compressDepth(plane, w, h, clear);
  EXPECT_EQ(noise.rawBlocks, 32u);
  EXPECT_EQ(decompressDepth(noise), plane);
}

TEST(DepthCompression, BadInputIsRefused) {
  EXPECT_THROW(compressDepth(std::vector<uint32_t>(10), 4, 4, 0), std::invalid_argument);
  std::vector<uint32_t> words(16 * 8);
  for (size_t i = 0; i < words.size(); ++i) words[i] = uint32_t(i * 2654435761u);
  CompressedDepth c = compressDepth(words, 16, 8, 0);
  CompressedDepth truncated = c;
  truncated.bytes.pop_back();
  EXPECT_THROW(decompressDepth(truncated), std::invalid_argument);
  CompressedDepth longer = c;
  longer.bytes.push_back(0);
  EXPECT_THROW(decompressDepth(longer), std::invalid_argument);
  CompressedDepth badHeader = c;
  badHeader.bytes[0] = 40;
  EXPECT_THROW(decompressDepth(badHeader), std::invalid_argument);
}

}  // namespace
}  // namespace hsr

// Tests of the writers (io.hpp): every output format is written, read back independently (NPY
// and PFM headers parsed here, PNG via stb_image, EXR via the OpenEXR API) and compared bit for
// bit; the atomic write never leaves a temporary or half a file behind.
#include <hsr/io.hpp>

#include "io/encode.hpp"

#include <gtest/gtest.h>

#include "temp_dir.hpp"
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

std::vector<uint8_t> readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A w x h frame whose pixel (x, y) has a distinct depth and face id; the last column is empty.
hsr::Frame makeFrame(int w, int h) {
  hsr::Frame f;
  f.width = w;
  f.height = h;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool empty = x == w - 1;
      f.faceId.push_back(empty ? -1 : y * w + x);
      f.triangleId.push_back(empty ? -1 : 2 * (y * w + x));
      f.depth.push_back(empty ? kInf : 1.0f + 0.25f * float(y * w + x));
      f.color.push_back(empty ? hsr::Rgba8{} : hsr::Rgba8{uint8_t(10 * x), uint8_t(20 * y), 7, 255});
    }
  return f;
}

// Four little-endian bytes as a float / int32 (the test host is little-endian x86 or ARM).
template <class T>
T fromLittleEndian(const uint8_t* p) {
  static_assert(sizeof(T) == 4);
  T value;
  std::memcpy(&value, p, 4);
  return value;
}

struct Npy {
  std::string header;
  size_t dataOffset = 0;
};
Npy parseNpyHeader(const std::vector<uint8_t>& file) {
  EXPECT_GE(file.size(), 10u);
  EXPECT_EQ(0, std::memcmp(file.data(), "\x93NUMPY\x01\x00", 8));
  size_t len = file[8] | (size_t(file[9]) << 8);
  Npy npy{std::string(file.begin() + 10, file.begin() + 10 + ptrdiff_t(len)), 10 + len};
  EXPECT_EQ(npy.dataOffset % 64, 0u);
  EXPECT_EQ(npy.header.back(), '\n');
  return npy;
}

struct Png {
  int width = 0, height = 0, channels = 0;
  std::vector<uint8_t> pixels;
};
Png readPng(const fs::path& path) {
  std::vector<uint8_t> file = readFile(path);
  Png png;
  uint8_t* data = stbi_load_from_memory(file.data(), int(file.size()), &png.width, &png.height, &png.channels, 0);
  EXPECT_NE(data, nullptr) << path;
  if (data) {
    png.pixels.assign(data, data + size_t(png.width) * size_t(png.height) * size_t(png.channels));
    stbi_image_free(data);
  }
  return png;
}

class IoWriters : public hsr::test::TempDirTest {
 protected:
  // Every file in the directory: a writer must leave exactly its target behind.
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
};

}  // namespace

TEST_F(IoWriters, DepthNpyIsFloat32RowMajorWithInfBackground) {
  hsr::Frame f = makeFrame(5, 3);
  hsr::writeDepth(f, path("d.npy"));
  std::vector<uint8_t> file = readFile(path("d.npy"));
  Npy npy = parseNpyHeader(file);
  EXPECT_NE(npy.header.find("'descr': '<f4'"), std::string::npos) << npy.header;
  EXPECT_NE(npy.header.find("'fortran_order': False"), std::string::npos);
  EXPECT_NE(npy.header.find("'shape': (3, 5)"), std::string::npos);
  ASSERT_EQ(file.size(), npy.dataOffset + 15 * 4);
  for (size_t i = 0; i < 15; ++i) EXPECT_EQ(fromLittleEndian<float>(&file[npy.dataOffset + 4 * i]), f.depth[i]) << i;
  EXPECT_TRUE(std::isinf(fromLittleEndian<float>(&file[npy.dataOffset + 4 * 4])));
}

TEST_F(IoWriters, FaceIdNpyIsInt32WithMinusOneBackground) {
  hsr::Frame f = makeFrame(4, 2);
  hsr::writeFaceIds(f, path("ids.NPY"));  // extensions are case-insensitive
  std::vector<uint8_t> file = readFile(path("ids.NPY"));
  Npy npy = parseNpyHeader(file);
  EXPECT_NE(npy.header.find("'descr': '<i4'"), std::string::npos) << npy.header;
  EXPECT_NE(npy.header.find("'shape': (2, 4)"), std::string::npos);
  ASSERT_EQ(file.size(), npy.dataOffset + 8 * 4);
  for (size_t i = 0; i < 8; ++i) EXPECT_EQ(fromLittleEndian<int32_t>(&file[npy.dataOffset + 4 * i]), f.faceId[i]);
  EXPECT_EQ(fromLittleEndian<int32_t>(&file[npy.dataOffset + 4 * 3]), -1);
}

TEST_F(IoWriters, PfmStoresRowsBottomToTopLittleEndian) {
  hsr::Frame f = makeFrame(3, 4);
  hsr::writeDepth(f, path("d.pfm"));
  std::vector<uint8_t> file = readFile(path("d.pfm"));
  const std::string header = "Pf\n3 4\n-1.0\n";
  ASSERT_GE(file.size(), header.size());
  EXPECT_EQ(std::string(file.begin(), file.begin() + ptrdiff_t(header.size())), header);
  ASSERT_EQ(file.size(), header.size() + 12 * 4);
  const uint8_t* data = file.data() + header.size();
  for (int fileRow = 0; fileRow < 4; ++fileRow)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(fromLittleEndian<float>(data + 4 * (fileRow * 3 + x)), f.depth[size_t((3 - fileRow) * 3 + x)]);
}

TEST_F(IoWriters, RawF32IsTopRowFirst) {
  hsr::Frame f = makeFrame(3, 2);
  hsr::writeDepth(f, path("d.f32"));
  std::vector<uint8_t> file = readFile(path("d.f32"));
  ASSERT_EQ(file.size(), 6u * 4);
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(fromLittleEndian<float>(&file[4 * i]), f.depth[i]);
}

TEST_F(IoWriters, ExrHasOneFloatChannelZ) {
  hsr::Frame f = makeFrame(7, 5);
  hsr::writeDepth(f, path("d.exr"));
  std::vector<uint8_t> file = readFile(path("d.exr"));
  ASSERT_GE(file.size(), 4u);
  EXPECT_EQ(0, std::memcmp(file.data(), "\x76\x2f\x31\x01", 4));  // OpenEXR magic number
  hsr::io::FloatImage image = hsr::io::decodeExrDepth(file, "d.exr");
  ASSERT_EQ(image.width, 7);
  ASSERT_EQ(image.height, 5);
  for (size_t i = 0; i < f.depth.size(); ++i) EXPECT_EQ(image.pixels[i], f.depth[i]) << i;
}

TEST_F(IoWriters, ColorPngIsRgbWhenOpaqueRgbaOtherwise) {
  hsr::Frame f = makeFrame(6, 4);
  hsr::writeColorPng(f, path("c.png"));
  Png png = readPng(path("c.png"));
  ASSERT_EQ(png.width, 6);
  ASSERT_EQ(png.height, 4);
  ASSERT_EQ(png.channels, 3);
  const hsr::Rgba8 c = f.color[f.index(2, 3)];
  size_t at = (3 * 6 + 2) * 3;
  EXPECT_EQ(png.pixels[at], c.r);
  EXPECT_EQ(png.pixels[at + 1], c.g);
  EXPECT_EQ(png.pixels[at + 2], c.b);

  f.color[5].a = 128;
  hsr::writeColorPng(f, path("c.png"));
  png = readPng(path("c.png"));
  ASSERT_EQ(png.channels, 4);
  EXPECT_EQ(png.pixels[5 * 4 + 3], 128);
  EXPECT_EQ(png.pixels[4 * 4 + 3], 255);
}

TEST_F(IoWriters, FaceIdPngEncodesIdPlusOneIn24Bits) {
  hsr::Frame f = makeFrame(4, 1);
  f.faceId = {-1, 0, 70000, (1 << 24) - 2};
  hsr::writeFaceIds(f, path("ids.png"));
  Png png = readPng(path("ids.png"));
  ASSERT_EQ(png.channels, 3);
  ASSERT_EQ(png.pixels.size(), 12u);
  std::vector<uint8_t> expected = {0, 0, 0, 0, 0, 1, 1, 17, 113, 255, 255, 255};  // 70001 = 0x011171
  EXPECT_EQ(png.pixels, expected);
}

TEST_F(IoWriters, FaceIdTooLargeForPngThrowsAndWritesNothing) {
  hsr::Frame f = makeFrame(2, 1);
  f.faceId = {0, (1 << 24) - 1};
  EXPECT_THROW(hsr::writeFaceIds(f, path("ids.png")), std::runtime_error);
  EXPECT_TRUE(listing().empty());
  hsr::writeFaceIds(f, path("ids.npy"));  // .npy has room for any id
  EXPECT_EQ(listing(), std::vector<std::string>{"ids.npy"});
}

TEST_F(IoWriters, DepthPictureMapsVisibleRangeNearWhiteFarGrey) {
  hsr::Frame f = makeFrame(4, 1);
  f.depth = {1.0f, 2.0f, 3.0f, kInf};
  hsr::writeDepthImage(f, path("z.png"));
  Png png = readPng(path("z.png"));
  ASSERT_EQ(png.channels, 1);
  EXPECT_EQ(png.pixels, (std::vector<uint8_t>{255, 144, 32, 0}));  // 255 - 223 * (d - 1) / 2

  f.depth = {5.0f, kInf, 5.0f, 5.0f};  // a single visible depth: all white
  hsr::writeDepthImage(f, path("z.png"));
  EXPECT_EQ(readPng(path("z.png")).pixels, (std::vector<uint8_t>{255, 0, 255, 255}));
}

TEST_F(IoWriters, UnknownExtensionNamesPathAndAllowedOnes) {
  hsr::Frame f = makeFrame(2, 2);
  try {
    hsr::writeDepth(f, path("d.tiff"));
    FAIL() << "no error";
  } catch (const hsr::InputError& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find(path("d.tiff")), std::string::npos) << msg;
    for (const char* ext : {".npy", ".pfm", ".exr", ".f32"}) EXPECT_NE(msg.find(ext), std::string::npos) << msg;
  }
  EXPECT_THROW(hsr::writeFaceIds(f, path("ids")), hsr::InputError);
  EXPECT_THROW(hsr::writeColorPng(f, path("c.jpg")), hsr::InputError);
  EXPECT_THROW(hsr::checkOutputPath(hsr::OutputKind::DepthImage, path("z.npy")), hsr::InputError);
  EXPECT_NO_THROW(hsr::checkOutputPath(hsr::OutputKind::Depth, path("dir.v2/d.EXR")));
  EXPECT_THROW(hsr::checkOutputPath(hsr::OutputKind::Depth, path("dir.npy/d")), hsr::InputError);
  EXPECT_TRUE(listing().empty());
}

TEST_F(IoWriters, IncompleteFrameIsRejected) {
  hsr::Frame f = makeFrame(3, 3);
  f.depth.pop_back();
  EXPECT_THROW(hsr::writeDepth(f, path("d.npy")), std::runtime_error);
  EXPECT_THROW(hsr::writeColorPng(hsr::Frame{}, path("c.png")), std::runtime_error);
  EXPECT_TRUE(listing().empty());
}

TEST_F(IoWriters, AtomicWriteReplacesAndLeavesNoTemporary) {
  hsr::writeTextFile("first", path("a.json"));
  hsr::writeTextFile("{\"second\": 2}\n", path("a.json"));
  std::vector<uint8_t> bytes = readFile(path("a.json"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "{\"second\": 2}\n");
  EXPECT_EQ(listing(), std::vector<std::string>{"a.json"});
}

// writeFileAtomic never replaces what is not a regular file, and an OutputBatch writes all of
// its files or none.
TEST_F(IoWriters, SpecialFilesAreNeverReplacedAndBatchesAreAllOrNothing) {
  ASSERT_EQ(::mkfifo(path("fifo.json").c_str(), 0600), 0);
  EXPECT_THROW(hsr::writeTextFile("x", path("fifo.json")), std::runtime_error);
  EXPECT_THROW(hsr::writeTextFile("x", "/dev/null"), std::runtime_error);
  EXPECT_THROW(hsr::checkOutputTarget(path("fifo.json")), hsr::InputError);
  EXPECT_THROW(hsr::checkOutputTarget(""), hsr::InputError);
  EXPECT_NO_THROW(hsr::checkOutputTarget(path("new.json")));
  EXPECT_TRUE(fs::is_fifo(path("fifo.json")));
  fs::remove(path("fifo.json"));

  hsr::writeTextFile("old", path("a.json"));
  try {
    hsr::OutputBatch batch;
    hsr::writeTextFile("new", path("a.json"));
    hsr::writeTextFile("b", path("b.json"));
    EXPECT_FALSE(fs::exists(path("b.json")));  // staged, not yet in place
    hsr::writeColorPng(makeFrame(2, 2), path("no/such/dir/c.png"));
    batch.commit();
    FAIL() << "no error";
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(listing(), std::vector<std::string>{"a.json"});  // no b.json, no temporaries
  std::vector<uint8_t> bytes = readFile(path("a.json"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "old");
  {
    hsr::OutputBatch batch;
    hsr::writeTextFile("new", path("a.json"));
    hsr::writeTextFile("b", path("b.json"));
    batch.commit();
  }
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.json", "b.json"}));
  bytes = readFile(path("a.json"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "new");
}

TEST_F(IoWriters, FailedWriteThrowsNamingPathAndKeepsOldFile) {
  // Into a directory that does not exist: an error naming the path, nothing created.
  std::string missing = path("no/such/dir/c.png");
  try {
    hsr::writeColorPng(makeFrame(2, 2), missing);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(missing + ": ", 0), 0u) << e.what();
  }
  EXPECT_TRUE(listing().empty());

  // Failing at the final rename (the target is a non-empty directory): the temporary is removed.
  fs::create_directories(path("target.npy/inside"));
  EXPECT_THROW(hsr::writeDepth(makeFrame(2, 2), path("target.npy")), std::runtime_error);
  EXPECT_EQ(listing(), std::vector<std::string>{"target.npy"});
  EXPECT_TRUE(fs::is_directory(path("target.npy/inside")));

  // Failing while encoding: the previous file is untouched.
  hsr::writeTextFile("old", path("ids.png"));
  hsr::Frame f = makeFrame(2, 1);
  f.faceId = {0, 1 << 24};
  EXPECT_THROW(hsr::writeFaceIds(f, path("ids.png")), std::runtime_error);
  std::vector<uint8_t> bytes = readFile(path("ids.png"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "old");
}

// Tests of loadScene() and the format loaders (OBJ+MTL, PLY, STL, OFF, glTF via assimp, scene
// JSON): small files written to a temporary folder, loaded and checked for positions, face
// order, colours and triangles; malformed variants must fail with "file[:line]: problem".
#include <gtest/gtest.h>

#include "temp_dir.hpp"
#include <hsr/io.hpp>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace hsr {
namespace {

namespace fs = std::filesystem;

constexpr Rgba8 kGrey{200, 200, 200, 255};

/// A temporary folder per test, removed afterwards.
class LoaderTest : public test::TempDirTest {
 protected:

  std::string write(const std::string& name, std::string_view bytes) {
    fs::path p = dir_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
  }

  /// Expects loadScene(path) to throw InputError with a message starting with the file name and
  /// containing each of `parts`.
  void expectError(const std::string& path, std::initializer_list<std::string> parts) {
    try {
      loadScene(path);
      ADD_FAILURE() << path << ": no error, expected one mentioning " << *parts.begin();
    } catch (const InputError& e) {
      std::string msg = e.what();
      EXPECT_EQ(msg.rfind(path, 0), 0u) << "message does not start with the file name: " << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "message is not one line: " << msg;
      for (const std::string& part : parts) EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' not in: " << msg;
    }
  }
  /// Writes `text` to `name` and expects the error.
  void expectError(const std::string& name, std::string_view text, std::initializer_list<std::string> parts) {
    SCOPED_TRACE(std::string(text.substr(0, 200)));
    expectError(write(name, text), parts);
  }
};

/// Little helper to build binary files.
struct Bytes {
  std::string s;
  bool bigEndian = false;
  template <class T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof v);
    if (bigEndian) std::reverse(b, b + sizeof v);
    s.append(b, sizeof v);
    return *this;
  }
  Bytes& text(std::string_view t) {
    s += t;
    return *this;
  }
};

std::vector<uint32_t> faceIndices(const Scene& s, size_t f) {
  auto span = s.face(f);
  return {span.begin(), span.end()};
}

// --- OBJ --------------------------------------------------------------------------------------

class LoaderObj : public LoaderTest {};

TEST_F(LoaderObj, IndexFormsFaceOrderAndMeshes) {
  std::string path = write("model.obj",
                           "# a comment\n"
                           "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                           "vt 0 0\nvn 0 0 1\ns off\n"
                           "o first\n"
                           "f 1 2 3 4\n"
                           "f 1/1 2/1 5/1\n"
                           "g second\r\n"
                           "f -5//1 -4//1 -1//1\r\n"
                           "f 1/1/1 3/1/1 4/1/1  # trailing comment\n"
                           "l 1 2\n");
  Scene s = loadScene(path);
  EXPECT_EQ(s.source, path);
  ASSERT_EQ(s.faceCount(), 4u);
  EXPECT_EQ(faceIndices(s, 0), (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(faceIndices(s, 1), (std::vector<uint32_t>{0, 1, 4}));
  EXPECT_EQ(faceIndices(s, 2), (std::vector<uint32_t>{0, 1, 4}));
  EXPECT_EQ(faceIndices(s, 3), (std::vector<uint32_t>{0, 2, 3}));
  ASSERT_EQ(s.triangles.size(), 5u);
  const uint32_t faces[] = {0, 0, 1, 2, 3};
  for (size_t t = 0; t < 5; ++t) EXPECT_EQ(s.triangles[t].face, faces[t]);
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.meshes[0].name, "first");
  EXPECT_EQ(s.meshes[0].faceCount, 2u);
  EXPECT_EQ(s.meshes[1].name, "second");
  EXPECT_EQ(s.meshes[1].firstFace, 2u);
  for (const Rgba8& c : s.faceColors) EXPECT_EQ(c, kGrey);
  EXPECT_EQ(s.positions[4], dvec3(0, 0, 1));
}

TEST_F(LoaderObj, MaterialsGiveColourAndOpacity) {
  write("mats/m.mtl",
        "# materials\n"
        "newmtl red\nKd 1 0 0\nd 0.5\n"
        "newmtl blue\n  Kd 0 0 1\n  Tr 0.25\n"
        "newmtl grey\nKd 0.5\n");
  std::string path = write("mats/model.obj",
                           "mtllib m.mtl\n"
                           "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                           "usemtl red\nf 1 2 3\n"
                           "usemtl blue\nf 1 2 3\n"
                           "usemtl grey\nf 1 2 3\n"
                           "usemtl nowhere\nf 1 2 3\n");
  Scene s = loadScene(path);
  ASSERT_EQ(s.faceCount(), 4u);
  EXPECT_EQ(s.faceColors[0], (Rgba8{255, 0, 0, 128}));
  EXPECT_EQ(s.faceColors[1], (Rgba8{0, 0, 255, 191}));
  EXPECT_EQ(s.faceColors[2], (Rgba8{128, 128, 128, 255}));
  EXPECT_EQ(s.faceColors[3], kGrey);
  ASSERT_EQ(s.problems.notes.size(), 1u);
  EXPECT_NE(s.problems.notes[0].find("'nowhere'"), std::string::npos);
}

TEST_F(LoaderObj, MissingMaterialLibraryIsANote) {
  std::string path = write("model.obj", "mtllib missing.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  Scene s = loadScene(path);
  EXPECT_EQ(s.faceColors[0], kGrey);
  ASSERT_EQ(s.problems.notes.size(), 1u);
  EXPECT_NE(s.problems.notes[0].find("missing.mtl"), std::string::npos);
  EXPECT_NE(s.problems.notes[0].find(":1:"), std::string::npos);
}

TEST_F(LoaderObj, VertexColoursAverageOverTheFace) {
  std::string path = write("model.obj",
                           "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 1 1 0\n"
                           "f 1 2 3\nf 2 4 3\n");
  Scene s = loadScene(path);
  EXPECT_EQ(s.faceColors[0], (Rgba8{85, 85, 85, 255}));
  EXPECT_EQ(s.faceColors[1], kGrey);  // vertex 4 has no colour
}

TEST_F(LoaderObj, LineContinuationJoinsLines) {
  std::string path = write("model.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\n 3 4\nf 1 2 x\n");
  expectError(path, {":7:", "'x'"});  // the continuation does not shift later line numbers
  write("model.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\r\n 3 4\n");
  Scene s = loadScene(path);
  ASSERT_EQ(s.faceCount(), 1u);
  EXPECT_EQ(s.face(0).size(), 4u);
}

TEST_F(LoaderObj, MillionUnitOffsetKeepsFullPrecision) {
  const char* xs[] = {"1000000.001", "-2000000.0000003", "1e6", "3000000.125000001"};
  std::string text;
  for (const char* x : xs) text += std::string("v ") + x + " " + x + " 0.5\n";
  text += "f 1 2 3\nf 2 3 4\n";
  Scene s = loadScene(write("far.obj", text));
  for (size_t i = 0; i < 4; ++i) {
    double expected = std::strtod(xs[i], nullptr);
    EXPECT_EQ(s.positions[i].x, expected) << xs[i];
    EXPECT_EQ(s.positions[i].y, expected) << xs[i];
  }
  EXPECT_NE(s.positions[0].x, double(float(s.positions[0].x)));  // more than float precision
}

TEST_F(LoaderObj, ForwardReferencesAreAllowed) {
  Scene s = loadScene(write("fwd.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_EQ(s.triangles.size(), 1u);
}

TEST_F(LoaderObj, MalformedFilesGiveFileAndLine) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expectError("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", {"nan.obj:2:", "'nan'"});
  expectError("inf.obj", "v 0 0 inf\n", {"inf.obj:1:", "'inf'"});
  expectError("huge.obj", "v 0 0 1e999\n", {"huge.obj:1:"});
  expectError("range.obj", tri + "f 1 2 4\n", {"range.obj:4:", "vertex index 4 out of range"});
  expectError("zero.obj", tri + "f 0 1 2\n", {"zero.obj:4:", "index 0"});
  expectError("rel.obj", tri + "f -4 1 2\n", {"rel.obj:4:", "before the first vertex"});
  expectError("two.obj", tri + "f 1 2\n", {"two.obj:4:", "at least 3"});
  expectError("token.obj", tri + "\nf 1 2 3x\n", {"token.obj:5:", "'3x'"});
  expectError("short.obj", "v 1 2\n", {"short.obj:1:", "z coordinate"});
  expectError("five.obj", "v 1 2 3 4 5\n", {"five.obj:1:"});
  expectError("noface.obj", tri, {"no polygon faces"});
  expectError("empty.obj", "", {"file is empty"});
  expectError((dir_ / "absent.obj").string(), {"file not found"});
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage += char((i * 2654435761u) >> 13);
  expectError("garbage.obj", garbage, {"garbage.obj"});
}

TEST_F(LoaderObj, MalformedMaterialLibraryGivesItsLine) {
  write("m.mtl", "newmtl a\nKd 1 0 nan\n");
  std::string mtl = (dir_ / "m.mtl").string();
  try {
    loadScene(write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(mtl + ":2:", 0), 0u) << e.what();
  }
}

TEST_F(LoaderObj, LargeFileLoadsQuickly) {
  // A 300 x 300 grid of quads split in triangles: 180k triangles, ~6 MB of text.
  const int n = 300;
  std::string text;
  text.reserve(8 << 20);
  char line[96];
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) {
      std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", x * 0.01 + 1e5, y * 0.01, (x * y % 7) * 1e-3);
      text += line;
    }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      int a = y * (n + 1) + x + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
      std::snprintf(line, sizeof line, "f %d/%d/%d %d/%d/%d %d/%d/%d\nf %d %d %d\n", a, a, a, b, b, b, c, c, c, a, c, d);
      text += line;
    }
  std::string path = write("big.obj", text);
  auto start = std::chrono::steady_clock::now();
  Scene s = loadScene(path);
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(s.triangles.size(), size_t(2 * n * n));
  EXPECT_LT(ms, 2000.0);  // ~60 ms in a release build
}

// --- PLY --------------------------------------------------------------------------------------

class LoaderPly : public LoaderTest {};

TEST_F(LoaderPly, AsciiWithVertexColoursAndOtherElements) {
  std::string path = write("a.ply",
                           "ply\nformat ascii 1.0\ncomment made by hand\n"
                           "element vertex 5\nproperty float x\nproperty float y\nproperty double z\n"
                           "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                           "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
                           "element face 2\nproperty list uchar int vertex_indices\n"
                           "end_header\n"
                           "0 0 0 255 0 0\n1 0 0 255 0 0\n1 1 0 0 0 255\n0 1 0 0 0 255\n0 0 1.5 0 255 0\n"
                           "0 1\n"
                           "4 0 1 2 3\n3 0 1 4\n");
  Scene s = loadScene(path);
  ASSERT_EQ(s.faceCount(), 2u);
  EXPECT_EQ(faceIndices(s, 0), (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(faceIndices(s, 1), (std::vector<uint32_t>{0, 1, 4}));
  EXPECT_EQ(s.positions[4], dvec3(0, 0, 1.5));
  EXPECT_EQ(s.faceColors[0], (Rgba8{128, 0, 128, 255}));
  EXPECT_EQ(s.faceColors[1], (Rgba8{170, 85, 0, 255}));
  EXPECT_EQ(s.triangles.size(), 3u);
}

/// A binary PLY: 3 double vertices (with an ignored normal and uchar colours), a skipped
/// element holding a list, and one face with float colours.
std::string binaryPly(bool bigEndian, const dvec3 (&v)[3]) {
  Bytes b;
  b.bigEndian = bigEndian;
  b.text(std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") + " 1.0\n")
      .text("element vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty float nx\n")
      .text("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n")
      .text("element material 1\nproperty list uchar uchar name\nproperty float shininess\n")
      .text("element face 1\nproperty list int uint vertex_indices\n")
      .text("property float red\nproperty float green\nproperty float blue\nend_header\n");
  for (const dvec3& p : v) b.put(p.x).put(p.y).put(p.z).put(1.0f).put(uint8_t(1)).put(uint8_t(2)).put(uint8_t(3)).put(uint8_t(4));
  b.put(uint8_t(3)).put(uint8_t('a')).put(uint8_t('b')).put(uint8_t('c')).put(0.5f);
  b.put(int32_t(3)).put(uint32_t(2)).put(uint32_t(0)).put(uint32_t(1)).put(1.0f).put(0.5f).put(0.0f);
  return b.s;
}

TEST_F(LoaderPly, BinaryBothEndiannessesInDouble) {
  const dvec3 v[3] = {{1000000.001, -2.5, 3}, {1000001.001, -2.5, 3}, {1000000.001, -1.5, 3.25}};
  for (bool big : {false, true}) {
    Scene s = loadScene(write(big ? "be.ply" : "le.ply", binaryPly(big, v)));
    ASSERT_EQ(s.faceCount(), 1u);
    EXPECT_EQ(faceIndices(s, 0), (std::vector<uint32_t>{2, 0, 1}));
    for (int i = 0; i < 3; ++i) EXPECT_EQ(s.positions[size_t(i)], v[i]);
    EXPECT_EQ(s.faceColors[0], (Rgba8{255, 128, 0, 255}));  // the face's own colour wins
  }
}

TEST_F(LoaderPly, MalformedFilesAreClearErrors) {
  const dvec3 v[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  std::string good = binaryPly(false, v);
  expectError("truncated.ply", good.substr(0, good.size() - 3), {"truncated", "byte offset"});
  expectError("half.ply", good.substr(0, good.size() - 40), {"'vertex'", "more than"});

  dvec3 bad[3] = {{0, 0, 0}, {std::nan(""), 0, 0}, {0, 1, 0}};
  expectError("nan.ply", binaryPly(false, bad), {"vertex 1 has a non-finite coordinate", "byte offset"});

  // A lying header: a trillion vertices in a small file.
  std::string lying = good;
  lying.replace(lying.find("vertex 3"), 8, "vertex 1000000000000");
  expectError("lying.ply", lying, {"1000000000000", "more than"});
  // A lying list length: 4 billion indices.
  Bytes b;
  b.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n")
      .text("property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n");
  for (int i = 0; i < 9; ++i) b.put(float(i % 2));
  b.put(uint32_t(0xFFFFFFFFu)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2));
  expectError("biglist.ply", b.s, {"truncated", "byte offset"});

  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expectError("nan_ascii.ply", header + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", {"nan_ascii.ply:11:", "'nan'"});
  expectError("range.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", {"range.ply:13:", "out of range"});
  expectError("negative.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", {"negative.ply:13:", "out of range"});
  expectError("two.ply", header + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", {"two.ply:13:", "at least 3"});
  expectError("short_ascii.ply", header + "0 0 0\n1 0 0\n", {"short_ascii.ply"});
  expectError("lying_ascii.ply", "ply\nformat ascii 1.0\nelement vertex 99999999\nproperty float x\n"
              "property float y\nproperty float z\nend_header\n0 0 0\n", {"more than"});
  expectError("noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", {"end_header"});
  expectError("type.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty quad x\nend_header\n", {"type.ply:4:", "'quad'"});
  expectError("magic.ply", "plx\n", {"magic.ply:1:", "not a PLY file"});
  expectError("novertex.ply", "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
              {"no 'vertex' element"});
}

// --- STL --------------------------------------------------------------------------------------

class LoaderStl : public LoaderTest {};

TEST_F(LoaderStl, AsciiFacetsAndSolids) {
  std::string path = write("a.stl",
                           "solid part one\n"
                           "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n"
                           "      vertex 0 1 0\n    endloop\n  endfacet\n"
                           "  facet normal nan nan nan\n    outer loop\n      vertex 1 0 0\n      vertex 1 1 0\n"
                           "      vertex 0 1 0.5e-1\n    endloop\n  endfacet\n"
                           "endsolid part one\n"
                           "solid two\nfacet normal 0 0 0\nouter loop\nvertex 5 5 5\nvertex 6 5 5\nvertex 5 6 5\n"
                           "endloop\nendfacet\nendsolid\n");
  Scene s = loadScene(path);
  ASSERT_EQ(s.faceCount(), 3u);
  EXPECT_EQ(s.positions[5], dvec3(0, 1, 0.05));
  EXPECT_EQ(faceIndices(s, 2), (std::vector<uint32_t>{6, 7, 8}));
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.meshes[0].name, "part one");
  EXPECT_EQ(s.meshes[1].firstFace, 2u);
}

std::string binaryStl(std::string header80, const std::vector<std::array<float, 9>>& tris,
                      const std::vector<uint16_t>& attributes) {
  Bytes b;
  header80.resize(80, ' ');
  b.text(header80).put(uint32_t(tris.size()));
  for (size_t t = 0; t < tris.size(); ++t) {
    b.put(0.0f).put(0.0f).put(1.0f);
    for (float f : tris[t]) b.put(f);
    b.put(attributes[t]);
  }
  return b.s;
}

TEST_F(LoaderStl, BinaryEvenWhenTheHeaderSaysSolid) {
  std::string bytes = binaryStl("solid exported by a CAD tool", {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}},
                                {uint16_t(0x8000u | (31u << 10)), 0});
  Scene s = loadScene(write("b.stl", bytes));
  ASSERT_EQ(s.faceCount(), 2u);
  EXPECT_EQ(s.positions[4], dvec3(1, 1, 0));
  EXPECT_EQ(s.faceColors[0], (Rgba8{255, 0, 0, 255}));  // VisCAM colour: red
  EXPECT_EQ(s.faceColors[1], kGrey);
}

TEST_F(LoaderStl, MalformedFilesAreClearErrors) {
  std::string good = binaryStl("binary", {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}}, {0, 0});
  expectError("truncated.stl", good.substr(0, good.size() - 10), {"truncated", "2 triangles"});
  std::string lying = good;
  lying[83] = char(0x7f);  // a count of about two billion
  expectError("lying.stl", lying, {"truncated"});
  float nan = std::numeric_limits<float>::quiet_NaN();
  expectError("nan.stl", binaryStl("x", {{0, 0, 0, 1, nan, 0, 0, 1, 0}}, {0}), {"non-finite", "byte offset 108"});
  expectError("short.stl", "hello", {"not an STL file"});
  const std::string head = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
  expectError("nan_ascii.stl", head + "vertex 1 nan 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n",
              {"nan_ascii.stl:5:", "'nan'"});
  expectError("cut.stl", head + "vertex 1 0 0\n", {"cut.stl:5:", "end of file"});
  expectError("two.stl", head + "vertex 1 0 0\nendloop\nendfacet\nendsolid\n", {"two.stl:6:", "at least 3"});
  expectError("word.stl", head + "vertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter lop\n",
              {"word.stl:10:", "'lop'"});
}

// --- OFF --------------------------------------------------------------------------------------

class LoaderOff : public LoaderTest {};

TEST_F(LoaderOff, FacesWithColoursAndComments) {
  Scene s = loadScene(write("a.off",
                            "OFF\n# a comment\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0  # trailing comment\n0 0 1\n\n"
                            "4 0 1 2 3 255 0 0\n3 0 1 4 0.0 1.0 0.0 0.5\n"));
  ASSERT_EQ(s.faceCount(), 2u);
  EXPECT_EQ(faceIndices(s, 1), (std::vector<uint32_t>{0, 1, 4}));
  EXPECT_EQ(s.faceColors[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_EQ(s.faceColors[1], (Rgba8{0, 255, 0, 128}));
  EXPECT_EQ(s.triangles.size(), 3u);
}

TEST_F(LoaderOff, CoffVertexColoursAndCountsOnTheHeaderLine) {
  Scene s = loadScene(write("c.off", "COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 0 255 255\n0 1 0 0 0 0 255\n3 0 1 2\n"));
  ASSERT_EQ(s.faceCount(), 1u);
  EXPECT_EQ(s.faceColors[0], (Rgba8{85, 0, 85, 255}));
}

TEST_F(LoaderOff, MalformedFilesGiveFileAndLine) {
  expectError("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", {"range.off:6:", "out of range"});
  expectError("lying.off", "OFF\n5 1 0\n0 0 0\n1 0 0\n0 1 0\n", {"lying.off:5:", "vertex 3 of 5"});
  expectError("huge.off", "OFF\n5000000000 1 0\n0 0 0\n", {"huge.off:2:", "2^32"});
  expectError("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", {"nan.off:4:", "'nan'"});
  expectError("two.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", {"two.off:6:", "at least 3"});
  expectError("header.off", "PLY\n", {"header.off:1:", "not an OFF file"});
  expectError("fourd.off", "4OFF\n", {"fourd.off:1:", "unsupported"});
  expectError("binary.off", "OFF BINARY\n", {"binary.off:1:", "binary"});
  expectError("extra.off", "OFF\n3 1 0\n0 0 0 7\n", {"extra.off:3:"});
}

// --- glTF through assimp ------------------------------------------------------------------------

std::string base64(std::string_view bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t n = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) n |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) n |= uint32_t(uint8_t(bytes[i + 2]));
    out += k[n >> 18 & 63];
    out += k[n >> 12 & 63];
    out += i + 1 < bytes.size() ? k[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? k[n & 63] : '=';
  }
  return out;
}

class LoaderGltf : public LoaderTest {};

TEST_F(LoaderGltf, NodeTransformsAreFlattened) {
  Bytes buffer;
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) buffer.put(f);
  for (uint16_t i : {0, 1, 2}) buffer.put(i);
  std::string gltf = R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
    "nodes": [
      {"name": "a", "mesh": 0, "translation": [10, 0, 0]},
      {"name": "b", "translation": [0, 5, 0], "children": [2]},
      {"name": "c", "mesh": 0, "scale": [2, 2, 2]}],
    "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}}],
    "buffers": [{"byteLength": 42, "uri": "data:application/octet-stream;base64,)" +
                     base64(buffer.s) + R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })";
  Scene s = loadScene(write("two.gltf", gltf));
  ASSERT_EQ(s.faceCount(), 2u);
  ASSERT_EQ(s.triangles.size(), 2u);
  ASSERT_EQ(s.meshes.size(), 2u);
  const dvec3 expected[6] = {{10, 0, 0}, {11, 0, 0}, {10, 1, 0}, {0, 5, 0}, {2, 5, 0}, {0, 7, 0}};
  for (int i = 0; i < 6; ++i) {
    uint32_t v = s.face(size_t(i / 3))[size_t(i % 3)];
    EXPECT_EQ(s.positions[v], expected[i]) << i;
  }
  EXPECT_EQ(s.faceColors[0], (Rgba8{255, 0, 0, 255}));
}

// glTF opacity: baseColorFactor's alpha with alphaMode BLEND; OPAQUE (also the default) ignores
// it; MASK is opaque from alphaCutoff up.
TEST_F(LoaderGltf, AlphaModeDecidesTheOpacity) {
  Bytes buffer;
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) buffer.put(f);
  for (uint16_t i : {0, 1, 2}) buffer.put(i);
  std::string gltf = R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3]}],
    "nodes": [{"mesh": 0}, {"mesh": 1}, {"mesh": 2}, {"mesh": 3}],
    "meshes": [
      {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
      {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 1}]},
      {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 2}]},
      {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 3}]}],
    "materials": [
      {"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 0.5]}, "alphaMode": "BLEND"},
      {"pbrMetallicRoughness": {"baseColorFactor": [0, 1, 0, 0.5]}},
      {"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 1, 0.4]}, "alphaMode": "MASK", "alphaCutoff": 0.3},
      {"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 1, 0.2]}, "alphaMode": "MASK"}],
    "buffers": [{"byteLength": 42, "uri": "data:application/octet-stream;base64,)" +
                     base64(buffer.s) + R"("}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
  })";
  Scene s = loadScene(write("alpha.gltf", gltf));
  ASSERT_EQ(s.faceCount(), 4u);
  EXPECT_EQ(s.faceColors[0].a, 128);
  EXPECT_EQ(s.faceColors[1].a, 255);
  EXPECT_EQ(s.faceColors[2].a, 255);
  EXPECT_EQ(s.faceColors[3].a, 0);
}

TEST_F(LoaderGltf, AssimpErrorsNameTheFile) {
  expectError("broken.gltf", "{ \"asset\": ", {"broken.gltf: assimp:"});
  expectError("unknown.xyz123", "what is this", {"unknown.xyz123: assimp:"});
}

// --- Scene JSON ------------------------------------------------------------------------------

class LoaderJson : public LoaderTest {};

TEST_F(LoaderJson, MeshesAreTransformedRecolouredAndNamed) {
  write("parts/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  std::string path = write("scene.json", R"({
    "meshes": [
      {"file": "parts/tri.obj", "name": "moved", "translate": [1, 2, 3], "scale": 2, "color": [0, 0, 1]},
      {"file": "parts/tri.obj", "rotate_deg": [0, 0, 90], "opacity": 0.5},
      {"file": "parts/tri.obj", "transform": [[1, 0, 0, 7], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
       "color": [255, 128, 0, 255]},
      {"builtin": "cubes"}
    ],
    "camera": {"eye": [0, 0, 10], "target": [0, 0, 0], "fovy_deg": 40}
  })");
  Scene s = loadScene(path);
  Scene cubes = loadScene("builtin:cubes");
  ASSERT_EQ(s.faceCount(), 3 + cubes.faceCount());
  EXPECT_EQ(s.triangles.size(), 3 + cubes.triangles.size());
  EXPECT_EQ(s.positions[1], dvec3(3, 2, 3));  // scaled, then translated
  EXPECT_NEAR(s.positions[4].x, 0, 1e-15);     // (1, 0, 0) rotated 90 degrees about z
  EXPECT_NEAR(s.positions[4].y, 1, 1e-15);
  EXPECT_EQ(s.positions[7], dvec3(8, 0, 0));
  EXPECT_EQ(s.faceColors[0], (Rgba8{0, 0, 255, 255}));
  EXPECT_EQ(s.faceColors[1], (Rgba8{200, 200, 200, 128}));
  EXPECT_EQ(s.faceColors[2], (Rgba8{255, 128, 0, 255}));
  EXPECT_EQ(s.faceColors[3], cubes.faceColors[0]);
  EXPECT_EQ(s.meshes.front().name, "moved");
  EXPECT_EQ(s.meshes[1].name, "tri");
  ASSERT_TRUE(s.camera.has_value());
  EXPECT_EQ(s.camera->eye, dvec3(0, 0, 10));
  EXPECT_EQ(s.camera->fovyDeg, 40);
}

TEST_F(LoaderJson, ErrorsNameTheFileAndLine) {
  expectError("syntax.json", "{\n  \"meshes\": [\n    {\"file\": \"a.obj\",}\n  ]\n}\n", {"syntax.json:3:"});
  expectError("key.json", R"({"meshes": [{"file": "a.obj", "colour": [1, 0, 0]}]})", {"meshes[0]", "'colour'"});
  expectError("both.json", R"({"meshes": [{"file": "a.obj", "builtin": "cubes"}]})", {"exactly one"});
  expectError("mixed.json", R"({"meshes": [{"builtin": "cubes", "scale": 2, "transform": []}]})", {"meshes[0].transform"});
  expectError("affine.json",
              R"({"meshes": [{"builtin": "cubes", "transform": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]}]})",
              {"affine"});
  expectError("empty_meshes.json", R"({"meshes": []})", {"non-empty"});
  expectError("camera.json", R"({"meshes": [{"builtin": "cubes"}], "camera": {"eye": [0, 0]}})", {"camera"});
  std::string missing = (dir_ / "nothere.obj").string();
  try {
    loadScene(write("missing.json", R"({"meshes": [{"file": "nothere.obj"}]})"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), missing + ": file not found");
  }
}

TEST_F(LoaderJson, SelfInclusionIsRefused) {
  expectError("self.json", R"({"meshes": [{"file": "self.json"}]})", {"includes itself"});
  write("a.json", R"({"meshes": [{"file": "b.json"}]})");
  write("b.json", R"({"meshes": [{"file": "./a.json"}]})");
  try {
    loadScene((dir_ / "a.json").string());
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("includes itself"), std::string::npos) << e.what();
  }
}

// --- Hostile input (issue 53) -------------------------------------------------------------------

class LoaderHostile : public LoaderTest {};

// A UTF-8 byte-order mark before the first line is skipped in every text format (it used to
// swallow an OBJ's first vertex).
TEST_F(LoaderHostile, ByteOrderMarkIsSkippedInEveryTextFormat) {
  const std::string bom = "\xEF\xBB\xBF";
  const std::pair<std::string, std::string> files[] = {
      {"bom.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"bom.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"bom.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"bom.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                  "endfacet\nendsolid s\n"},
      {"bom.json", R"({"meshes": [{"file": "bom.obj"}]})"}};
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    Scene s = loadScene(write(name, bom + text));
    EXPECT_EQ(s.positions.size(), 3u);
    EXPECT_EQ(s.triangles.size(), 1u);
  }
  // An MTL library with a mark keeps its first statement.
  write("m.mtl", bom + "newmtl red\nKd 1 0 0\n");
  Scene s = loadScene(write("mtl.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n"));
  EXPECT_EQ(s.faceColors[0], (Rgba8{255, 0, 0, 255}));
  EXPECT_TRUE(s.problems.notes.empty()) << s.problems.notes[0];
}

// A PLY header line of no PLY keyword (PLY/Wuson.ply of assimp's test models has "Created by
// ...") is skipped and counted in a note naming its line, as assimp reads such files.
TEST_F(LoaderHostile, UnknownPlyHeaderLinesAreSkippedWithANote) {
  Scene s = loadScene(write("wuson.ply",
                            "ply\nformat ascii 1.0\ncomment made by hand\nCreated by a 3D program\nelement vertex 3\n"
                            "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                            "property list uchar int vertex_indices\nfoo bar\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(s.triangles.size(), 1u);
  ASSERT_EQ(s.problems.notes.size(), 1u);
  EXPECT_NE(s.problems.notes[0].find("wuson.ply:4: 2 header line(s) of no PLY keyword skipped (the first 'Created')"),
            std::string::npos)
      << s.problems.notes[0];
}

// A coordinate beyond 1e30 is named with the file's line and the format's own vertex number.
TEST_F(LoaderHostile, HugeCoordinatesNameTheLineAndTheFormatsVertexNumber) {
  expectError("huge.obj", "v 0 0 0\nv 1e31 0 0\nv 0 1 0\nf 1 2 3\n",
              {"huge.obj:2: vertex 2 has a coordinate beyond 1e30 in magnitude"});
  expectError("huge.off", "OFF\n3 1 0\n0 0 0\n1 -2e30 0\n0 1 0\n3 0 1 2\n",
              {"huge.off:4: vertex 1 has a coordinate beyond 1e30 in magnitude"});
  expectError("huge.ply",
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1e31 0\n3 0 1 2\n",
              {"huge.ply:12: vertex 2 has a coordinate beyond 1e30 in magnitude"});
  expectError("huge.stl",
              "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 5e30\nendloop\n"
              "endfacet\nendsolid s\n",
              {"huge.stl:6: vertex has a coordinate beyond 1e30 in magnitude"});
}

// A binary PLY's bad index is printed as the integer it is, not as "-5.000000".
TEST_F(LoaderHostile, BinaryPlyIndexErrorsPrintIntegers) {
  Bytes b;
  b.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n")
      .text("property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n");
  for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b.put(c);
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(-5)).put(int32_t(2));
  expectError("index.ply", b.s, {"face 0: vertex index -5 out of range (3 vertices)"});
}

// A GLB whose header declares a first chunk longer than the file is refused before assimp, which
// would allocate the declared length (a fuzz finding: 1.7 GB for a 3 KB file).
TEST_F(LoaderHostile, GlbChunkLengthBeyondTheFileIsRefusedBeforeAssimp) {
  Bytes b;
  b.text("glTF").put(uint32_t(2)).put(uint32_t(1900)).put(uint32_t(1711277184)).text("JSON");
  b.text(R"({"asset":{"version":"2.0"}})");
  expectError("huge-chunk.glb", b.s, {"huge-chunk.glb: GLB header: the first chunk declares 1711277184 bytes"});
}

// Debian's assimp dereferences null on a GLB line loop whose indices lie beyond its vertices
// (a fuzz finding): the import is tried in a child process first, so the file is refused.
TEST_F(LoaderHostile, AFileThatCrashesAssimpIsRefused) {
  std::ifstream in(std::string(HSR_SOURCE_DIR) + "/fuzz/regressions/assimp/glb-line-loop-indices-beyond-vertices",
                   std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  expectError("line-loop.glb", bytes, {"line-loop.glb: assimp crashed reading the file"});
}

// --- Dispatch -----------------------------------------------------------------------------------

class LoaderDispatch : public LoaderTest {};

TEST_F(LoaderDispatch, ExtensionsAreCaseInsensitive) {
  Scene s = loadScene(write("UPPER.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(s.triangles.size(), 1u);
}

TEST_F(LoaderDispatch, BuiltinsAndBadPaths) {
  Scene s = loadScene("builtin:cubes");
  EXPECT_GT(s.triangles.size(), 0u);
  EXPECT_THROW(loadScene("builtin:no-such-scene"), InputError);
  expectError(dir_.string(), {"is a directory"});
  expectError("empty.ply", "", {"file is empty"});
  expectError("empty.gltf", "", {"file is empty"});
}

}  // namespace
}  // namespace hsr

// loadScenePart: a scene JSON's shares, in order, are the whole scene's faces in order (same
// vertices, same colours), each share a run of whole entries; anything else loads whole.
TEST(LoadScenePart, SharesInOrderAreTheWholeScene) {
  const std::string blocks = std::string(HSR_SOURCE_DIR) + "/tests/mpi/data/blocks.json";
  const hsr::Scene whole = hsr::loadScene(blocks);
  for (int parts : {1, 2, 3, 5, 8, 11}) {
    size_t face = 0, nextEntry = 0;
    for (int p = 0; p < parts; ++p) {
      const hsr::ScenePart share = hsr::loadScenePart(blocks, p, parts);
      EXPECT_EQ(share.whole, parts == 1);
      if (!share.whole) {
        EXPECT_EQ(share.firstEntry, nextEntry) << parts << " parts, share " << p;
        EXPECT_EQ(share.entriesInFile, 8u);
        nextEntry += share.entryCount;
      }
      for (size_t f = 0; f < share.scene.faceCount(); ++f, ++face) {
        ASSERT_LT(face, whole.faceCount());
        const auto a = share.scene.face(f), b = whole.face(face);
        ASSERT_EQ(a.size(), b.size());
        for (size_t k = 0; k < a.size(); ++k)
          ASSERT_EQ(share.scene.positions[a[k]], whole.positions[b[k]]) << parts << " parts, face " << face;
        ASSERT_EQ(share.scene.faceColors[f], whole.faceColors[face]);
      }
    }
    EXPECT_EQ(face, whole.faceCount()) << parts << " parts";
    if (parts > 1) EXPECT_EQ(nextEntry, 8u);
  }
  const hsr::ScenePart builtin = hsr::loadScenePart("builtin:cubes", 1, 3);
  EXPECT_TRUE(builtin.whole);
  EXPECT_EQ(builtin.scene.faceCount(), hsr::loadScene("builtin:cubes").faceCount());
  EXPECT_THROW(hsr::loadScenePart("builtin:cubes", 3, 3), std::invalid_argument);
}

// A share reports only its own entries' errors: the other shares load.
TEST(LoadScenePart, AnEntrysErrorIsItsShares) {
  const std::string missing = std::string(HSR_SOURCE_DIR) + "/tests/mpi/data/missing-mesh.json";
  // A missing file weighs nothing, the built-in entry 1: shares of 3 are nothing, cubes, the missing file.
  EXPECT_EQ(hsr::loadScenePart(missing, 0, 3).scene.faceCount(), 0u);
  EXPECT_EQ(hsr::loadScenePart(missing, 1, 3).scene.faceCount(), hsr::loadScene("builtin:cubes").faceCount());
  try {
    hsr::loadScenePart(missing, 2, 3);
    ADD_FAILURE() << "the missing mesh loaded";
  } catch (const hsr::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-mesh.obj"), std::string::npos) << e.what();
  }
}

// STL loader, ASCII and binary (with VisCAM/SolidView 15-bit facet colours): every facet is a
// face, in file order, with its own three vertices. Produces an unfinalized Scene for
// loadScene() (load.cpp); behaviour documented in docs/loaders.md.
#include <bit>
#include <cmath>
#include <limits>

#include "scene/loaders.hpp"

namespace hsr::loaders {
namespace {

constexpr size_t kHeaderBytes = 84;  // 80-byte header + uint32 triangle count
constexpr size_t kRecordBytes = 50;  // normal, 3 vertices (12 floats), uint16 attribute

uint32_t le32(const char* p) {
  auto b = [p](int i) { return uint32_t(static_cast<unsigned char>(p[i])); };
  return b(0) | b(1) << 8 | b(2) << 16 | b(3) << 24;
}

Scene readBinary(const std::string& path, std::string_view bytes) {
  const uint64_t count = le32(bytes.data() + 80);
  const uint64_t needed = kHeaderBytes + kRecordBytes * count;
  if (needed > bytes.size())
    throw InputError(path + ": truncated binary STL: the header declares " + std::to_string(count) +
                     " triangles (" + std::to_string(needed) + " bytes) but the file has " +
                     std::to_string(bytes.size()) + " bytes");
  Scene scene;
  scene.source = path;
  if (needed < bytes.size())
    scene.problems.notes.push_back(path + ": " + std::to_string(bytes.size() - needed) +
                                   " bytes after the last triangle ignored");
  scene.positions.reserve(size_t(3 * count));
  for (uint64_t t = 0; t < count; ++t) {
    const size_t record = size_t(kHeaderBytes + kRecordBytes * t);
    const char* p = bytes.data() + record + 12;  // skip the facet normal: it is recomputed
    for (int k = 0; k < 3; ++k, p += 12) {
      dvec3 v{std::bit_cast<float>(le32(p)), std::bit_cast<float>(le32(p + 4)), std::bit_cast<float>(le32(p + 8))};
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw InputError(path + ": triangle " + std::to_string(t) + " has a non-finite coordinate (byte offset " +
                         std::to_string(p - bytes.data()) + ")");
      if (const char* huge = hugeCoordinate(v))
        throw InputError(path + ": triangle " + std::to_string(t) + " has " + huge + " (byte offset " +
                         std::to_string(p - bytes.data()) + ")");
      scene.positions.push_back(v);
    }
    // VisCAM/SolidView colour: bit 15 set marks a valid colour, 5 bits each of red (10-14),
    // green (5-9) and blue (0-4).
    uint32_t attribute = uint32_t(static_cast<unsigned char>(p[0])) | uint32_t(static_cast<unsigned char>(p[1])) << 8;
    Rgba8 color = kDefaultColor;
    if (attribute & 0x8000u) {
      auto level = [&](int shift) { return uint8_t(((attribute >> shift) & 31u) * 255u / 31u); };
      color = Rgba8{level(10), level(5), level(0), 255};
    }
    uint32_t base = uint32_t(3 * t);
    scene.addFace({base, base + 1, base + 2}, color);
  }
  return scene;
}

Scene readAscii(const std::string& path, std::string_view bytes) {
  Scene scene;
  scene.source = path;
  TextScanner sc(bytes, path, /*hashComments=*/false, /*lineContinuation=*/false);
  auto found = [](std::string_view tok) { return tok.empty() ? std::string("end of file") : quote(tok); };
  auto expect = [&](std::string_view word) {
    std::string_view tok = sc.anyToken();
    if (!iequals(tok, word)) sc.fail("expected '" + std::string(word) + "', found " + found(tok));
  };
  std::vector<uint32_t> indices;

  expect("solid");
  while (true) {
    std::string_view name = sc.restOfLine();
    scene.beginMesh(name.empty() ? "solid" : std::string(name));
    while (true) {
      std::string_view tok = sc.anyToken();
      if (iequals(tok, "endsolid")) {
        sc.restOfLine();
        break;
      }
      if (tok.empty()) {
        scene.problems.notes.push_back(path + ": no 'endsolid' at the end of the file");
        return scene;
      }
      if (!iequals(tok, "facet")) sc.fail("expected 'facet' or 'endsolid', found " + found(tok));
      expect("normal");
      for (int k = 0; k < 3; ++k)  // the normal is recomputed; exporters even write NaN here
        if (sc.anyToken().empty()) sc.fail("unexpected end of file in a facet normal");
      expect("outer");
      expect("loop");
      indices.clear();
      for (tok = sc.anyToken(); iequals(tok, "vertex"); tok = sc.anyToken()) {
        if (scene.positions.size() >= std::numeric_limits<uint32_t>::max()) sc.fail("more than 2^32 vertices");
        dvec3 v;
        v.x = sc.number("x coordinate");
        v.y = sc.number("y coordinate");
        v.z = sc.number("z coordinate");
        if (const char* huge = hugeCoordinate(v)) sc.fail(std::string("vertex has ") + huge);
        indices.push_back(uint32_t(scene.positions.size()));
        scene.positions.push_back(v);
      }
      if (!iequals(tok, "endloop")) sc.fail("expected 'vertex' or 'endloop', found " + found(tok));
      if (indices.size() < 3)
        sc.fail("a facet needs at least 3 vertices, found " + std::to_string(indices.size()));
      expect("endfacet");
      scene.addFace(indices, kDefaultColor);
    }
    std::string_view tok = sc.anyToken();
    if (tok.empty()) break;
    if (!iequals(tok, "solid")) sc.fail("expected 'solid' or the end of the file, found " + found(tok));
  }
  return scene;
}

bool startsWithSolid(std::string_view bytes) {
  size_t i = bytes.find_first_not_of(" \t\r\n");
  return i != std::string_view::npos && iequals(bytes.substr(i, 5), "solid");
}

}  // namespace

// Binary files may also begin with "solid" (many exporters put it in the header), so the size
// decides first: a file whose length is exactly what its triangle count implies is binary.
Scene loadStl(const std::string& path, std::string_view bytes) {
  if (bytes.size() >= kHeaderBytes &&
      kHeaderBytes + kRecordBytes * uint64_t(le32(bytes.data() + 80)) == bytes.size())
    return readBinary(path, bytes);
  if (startsWithSolid(skipBom(bytes))) return readAscii(path, skipBom(bytes));
  if (bytes.size() < kHeaderBytes)
    throw InputError(path + ": not an STL file (too short for a binary STL and no ASCII 'solid' line)");
  return readBinary(path, bytes);
}

}  // namespace hsr::loaders

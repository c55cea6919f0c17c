// Array files of io.hpp: NumPy .npy (depth and face ids), PFM and raw float32 depth, and the
// writeDepth dispatch by extension (EXR is in exr.cpp). Read by NumPy scripts and image tools
// that compare hsr with other renderers; layouts per docs/conventions.md "Output files".
#include "io/encode.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace hsr {

namespace io {

namespace {

// Appends `count` 4-byte values (host order) little-endian, as every format here stores them.
void appendLittleEndian32(Bytes& out, const void* values, size_t count) {
  size_t at = out.size();
  out.resize(at + count * 4);
  std::memcpy(out.data() + at, values, count * 4);
  if constexpr (std::endian::native == std::endian::big)
    for (size_t i = at; i < out.size(); i += 4) std::reverse(out.begin() + ptrdiff_t(i), out.begin() + ptrdiff_t(i + 4));
}

void appendText(Bytes& out, const std::string& text) { out.insert(out.end(), text.begin(), text.end()); }

}  // namespace

Bytes encodeNpy(const char* descr, int height, int width, const void* elements, int channels) {
  // NPY 1.0: magic, version, 16-bit little-endian header length, then a Python dict literal
  // padded with spaces and ended by '\n' so the data starts on a 64-byte boundary.
  constexpr size_t kPreamble = 10, kAlign = 64;
  std::string header = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (" +
                       std::to_string(height) + ", " + std::to_string(width) +
                       (channels > 1 ? ", " + std::to_string(channels) : std::string()) + "), }";
  size_t padded = (kPreamble + header.size() + 1 + kAlign - 1) / kAlign * kAlign - kPreamble;
  header.append(padded - header.size() - 1, ' ');
  header.push_back('\n');

  Bytes out{0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, uint8_t(header.size() & 0xff), uint8_t(header.size() >> 8)};
  appendText(out, header);
  appendLittleEndian32(out, elements, size_t(width) * size_t(height) * size_t(channels));
  return out;
}

Bytes encodePfm(int width, int height, const float* rowsTopFirst) {
  Bytes out;
  appendText(out, "Pf\n" + std::to_string(width) + " " + std::to_string(height) + "\n-1.0\n");
  for (int y = height - 1; y >= 0; --y) appendLittleEndian32(out, rowsTopFirst + size_t(y) * size_t(width), size_t(width));
  return out;
}

Bytes encodeRawF32(int width, int height, const float* rowsTopFirst) {
  Bytes out;
  appendLittleEndian32(out, rowsTopFirst, size_t(width) * size_t(height));
  return out;
}

}  // namespace io

void writeDepth(const Frame& frame, const std::string& path) {
  io::DepthFileFormat format = io::depthFileFormat(path);
  io::requirePixels(frame, frame.depth.size(), "depth", path);
  const float* depth = frame.depth.data();
  int w = frame.width, h = frame.height;
  switch (format) {
    case io::DepthFileFormat::Npy: io::writeBytes(io::encodeNpy("<f4", h, w, depth), path); return;
    case io::DepthFileFormat::Pfm: io::writeBytes(io::encodePfm(w, h, depth), path); return;
    case io::DepthFileFormat::F32: io::writeBytes(io::encodeRawF32(w, h, depth), path); return;
    case io::DepthFileFormat::Exr: io::writeBytes(io::encodeExrDepth(w, h, depth, path), path); return;
  }
}

}  // namespace hsr

// Internal to the writers (io.hpp): in-memory encoders for every output format and the mapping
// from file extension to format. The public writers encode into memory with these, then hand the
// bytes to writeFileAtomic; tests/io_test.cpp reads EXR files back with decodeExrDepth.
#pragma once
#include <hsr/io.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace hsr::io {

using Bytes = std::vector<uint8_t>;

/// Lower-case extension of `path` with its dot (".png"), or "" when there is none.
std::string extensionOf(const std::string& path);

enum class IdFileFormat : uint8_t { Png, Npy };
enum class DepthFileFormat : uint8_t { Npy, Pfm, Exr, F32 };
/// The format for `path`'s extension; InputError "path: ..." naming the allowed extensions.
IdFileFormat idFileFormat(const std::string& path);
DepthFileFormat depthFileFormat(const std::string& path);
void requirePng(const std::string& path);

/// writeFileAtomic of an encoded file.
inline void writeBytes(const Bytes& bytes, const std::string& path) {
  writeFileAtomic(path, bytes.data(), bytes.size());
}

/// Throws std::runtime_error "path: ..." unless the frame has pixels and its buffer `what`
/// holds `count` == width * height values: nothing is encoded from a partial frame.
void requirePixels(const Frame& frame, size_t count, const char* what, const std::string& path);

/// PNG of `channels` (1 grey, 3 RGB, 4 RGBA) 8-bit samples per pixel, rows top to bottom.
/// Throws std::runtime_error "name: ..." if encoding fails.
Bytes encodePng(int width, int height, int channels, const uint8_t* pixels, const std::string& name);

/// NPY v1.0 of a C-order (height, width) array — (height, width, channels) when channels > 1 —
/// whose elements have NumPy type `descr` ("<f4", "<i4"); `elements` holds height * width *
/// channels 4-byte values in host order, written little-endian. The header is padded so the
/// data starts at a multiple of 64 bytes.
Bytes encodeNpy(const char* descr, int height, int width, const void* elements, int channels = 1);
/// Grey PFM ("Pf", negative scale = little-endian), rows stored bottom to top as the format wants.
Bytes encodePfm(int width, int height, const float* rowsTopFirst);
/// Raw little-endian float32, row 0 = top.
Bytes encodeRawF32(int width, int height, const float* rowsTopFirst);
/// OpenEXR scanline image with one FLOAT channel "Z" (ZIP compressed), row 0 = top.
/// Throws std::runtime_error "name: ..." if OpenEXR fails.
Bytes encodeExrDepth(int width, int height, const float* rowsTopFirst, const std::string& name);

/// A decoded single-channel float image (rows top first).
struct FloatImage {
  int width = 0, height = 0;
  std::vector<float> pixels;
};
/// Reads back an EXR's "Z" channel with the OpenEXR API: the reverse of encodeExrDepth, for
/// checks (the tests cannot see OpenEXR's headers). Throws std::runtime_error "name: ...".
FloatImage decodeExrDepth(const Bytes& exr, const std::string& name);

}  // namespace hsr::io

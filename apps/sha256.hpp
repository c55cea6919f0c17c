// SHA-256 (FIPS 180-4), streamed: the checksum `hsr batch` records for every file it writes and
// checks again before it skips a view, the same as `sha256sum` prints. Plain C++, one thread
// per object. Tested against the NIST examples (tests/batch_test.cpp).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace hsr::cli {

class Sha256 {
 public:
  void update(const void* bytes, size_t size);
  /// The digest as 64 lower-case hex digits; the object is spent afterwards.
  std::string hexDigest();

 private:
  void compress(const uint8_t* block);

  std::array<uint32_t, 8> state_{0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  std::array<uint8_t, 64> block_{};
  size_t filled_ = 0;     // bytes waiting in block_
  uint64_t length_ = 0;   // bytes hashed in all
};

/// The SHA-256 of `bytes` as 64 hex digits.
std::string sha256Hex(std::string_view bytes);

}  // namespace hsr::cli

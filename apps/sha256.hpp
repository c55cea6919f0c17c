// SHA-256, streamed: the checksum `hsr batch` records for every file it writes and checks again
// before it skips a view, the same as `sha256sum` prints. OpenSSL's libcrypto computes it.
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace hsr::cli {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* bytes, size_t size);
  /// The digest as 64 lower-case hex digits; the object is spent afterwards.
  std::string hexDigest();

 private:
  struct Context;
  std::unique_ptr<Context> context_;
};

/// The SHA-256 of `bytes` as 64 hex digits.
std::string sha256Hex(std::string_view bytes);

}  // namespace hsr::cli

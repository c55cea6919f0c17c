// Shared by the fuzz targets (fuzz/*_fuzz.cpp): a reader of the fuzzer's bytes, a scratch folder
// for the inputs that the library reads from files, and the one rule every target checks — bad
// input may throw hsr::InputError, nothing else (another exception escapes and aborts: a finding).
#pragma once
#include <hsr/common.hpp>
#include <hsr/limits.hpp>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include <unistd.h>

namespace hsr::fuzz {

/// Takes values from the front of the fuzzer's input; past its end every value is 0.
class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  size_t left() const { return size_ - pos_; }
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  template <class T>
  T raw() {
    T value{};
    unsigned char bytes[sizeof(T)] = {};
    for (auto& b : bytes) b = byte();
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }
  /// A whole number in [lo, hi].
  uint32_t below(uint32_t count) { return count == 0 ? 0 : raw<uint32_t>() % count; }
  int range(int lo, int hi) { return lo + int(below(uint32_t(hi - lo + 1))); }
  bool flag() { return byte() & 1; }
  /// The rest of the input as text.
  std::string_view rest() {
    std::string_view out(reinterpret_cast<const char*>(data_) + pos_, size_ - pos_);
    pos_ = size_;
    return out;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

/// A folder of this process's own under the temporary directory, made once, for inputs that the
/// library reads from files (an MTL beside an OBJ, a glTF, the meshes a scene JSON names).
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / ("hsr-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline void writeFile(const std::filesystem::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

/// The memory limit for fuzzing: well under libFuzzer's default -rss_limit_mb=2048, so that an
/// input asking for too much is refused by hsr's own check, which is what is being tested.
inline void setLimits() {
  static const bool done = [] {
    hsr::setMemoryLimit(uint64_t(512) << 20);
    return true;
  }();
  (void)done;
}

/// Runs `f`, accepting an InputError (the clear refusal bad input must get).
template <class F>
void refusedOrDone(F&& f) {
  try {
    f();
  } catch (const hsr::InputError&) {
  }
}

}  // namespace hsr::fuzz

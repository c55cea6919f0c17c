// Putting bytes on disk for every writer of io.hpp: atomic replace (temporary file beside the
// target, then rename) and the extension -> format rules the writers and the CLI share.
// Called by the writers in images.cpp / arrays.cpp and by the `hsr` command line.
#include "io/encode.hpp"

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hsr {

namespace {

[[noreturn]] void throwErrno(const std::string& path, const char* what, int err) {
  throw std::runtime_error(path + ": " + what + ": " + std::strerror(err));
}

// Removes the temporary file on every exit path that does not rename it into place.
class TempFile {
 public:
  explicit TempFile(std::string path) : path_(std::move(path)) {}
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!path_.empty()) ::unlink(path_.c_str());
  }
  const std::string& path() const { return path_; }
  int& fd() { return fd_; }
  void release() { path_.clear(); }

 private:
  std::string path_;
  int fd_ = -1;
};

thread_local OutputBatch* currentBatch = nullptr;

// Why an existing `path` must not be replaced, or nullptr when it may (absent or regular).
const char* notRegular(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || S_ISREG(st.st_mode)) return nullptr;
  if (S_ISDIR(st.st_mode)) return "is a directory";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "is a device";
  if (S_ISFIFO(st.st_mode)) return "is a FIFO";
  if (S_ISSOCK(st.st_mode)) return "is a socket";
  return "is not a regular file";
}

}  // namespace

void checkOutputTarget(const std::string& path) {
  if (path.empty()) throw InputError("an output path is empty");
  if (const char* why = notRegular(path))
    throw InputError(path + ": " + why + ", not a regular file: refusing to replace it");
}

OutputBatch::OutputBatch() : outer_(currentBatch) { currentBatch = this; }

OutputBatch::~OutputBatch() {
  currentBatch = outer_;
  for (const auto& [temp, target] : staged_) ::unlink(temp.c_str());
}

void OutputBatch::stage(std::string temp, std::string target) { staged_.emplace_back(std::move(temp), std::move(target)); }

void OutputBatch::commit() {
  while (!staged_.empty()) {
    const auto& [temp, target] = staged_.front();
    if (const char* why = notRegular(target))
      throw std::runtime_error(target + ": " + why + ", not a regular file: refusing to replace it");
    if (::rename(temp.c_str(), target.c_str()) != 0) throwErrno(target, "cannot replace file", errno);
    staged_.erase(staged_.begin());
  }
}

void writeFileAtomic(const std::string& path, const void* bytes, size_t size) {
  // A unique name in the target's own directory, so the final rename never crosses file
  // systems and concurrent writers (threads or processes) never share a temporary file.
  static std::atomic<uint64_t> counter{0};
  if (const char* why = notRegular(path))
    throw std::runtime_error(path + ": " + why + ", not a regular file: refusing to replace it");
  TempFile temp(path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));

  temp.fd() = ::open(temp.path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (temp.fd() < 0) throwErrno(path, "cannot create file", errno);

  const auto* p = static_cast<const char*>(bytes);
  while (size > 0) {
    ssize_t n = ::write(temp.fd(), p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throwErrno(path, "cannot write", errno);
    p += n;
    size -= size_t(n);
  }
  // close() is where some file systems (NFS) report a failed write: check it.
  int fd = temp.fd();
  temp.fd() = -1;
  if (::close(fd) != 0) throwErrno(path, "cannot write", errno);

  if (currentBatch) {
    currentBatch->stage(temp.path(), path);  // renamed by OutputBatch::commit()
  } else if (::rename(temp.path().c_str(), path.c_str()) != 0) {
    throwErrno(path, "cannot replace file", errno);
  }
  temp.release();
}

void writeTextFile(const std::string& text, const std::string& path) {
  writeFileAtomic(path, text.data(), text.size());
}

namespace io {

std::string extensionOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

namespace {
[[noreturn]] void unknownExtension(const std::string& path, const char* what, const char* allowed) {
  std::string ext = extensionOf(path);
  throw InputError(path + ": " + (ext.empty() ? "no extension" : "unknown extension '" + ext + "'") +
                   " for " + what + " (use " + allowed + ")");
}
}  // namespace

IdFileFormat idFileFormat(const std::string& path) {
  std::string ext = extensionOf(path);
  if (ext == ".png") return IdFileFormat::Png;
  if (ext == ".npy") return IdFileFormat::Npy;
  unknownExtension(path, "a face-id file", ".png or .npy");
}

DepthFileFormat depthFileFormat(const std::string& path) {
  std::string ext = extensionOf(path);
  if (ext == ".npy") return DepthFileFormat::Npy;
  if (ext == ".pfm") return DepthFileFormat::Pfm;
  if (ext == ".exr") return DepthFileFormat::Exr;
  if (ext == ".f32") return DepthFileFormat::F32;
  unknownExtension(path, "a depth file", ".npy, .pfm, .exr or .f32");
}

void requirePng(const std::string& path) {
  if (extensionOf(path) != ".png") unknownExtension(path, "an image", ".png");
}

void requirePixels(const Frame& frame, size_t count, const char* what, const std::string& path) {
  if (frame.width <= 0 || frame.height <= 0)
    throw std::runtime_error(path + ": cannot write an empty frame (" + std::to_string(frame.width) +
                             "x" + std::to_string(frame.height) + ")");
  if (count != size_t(frame.width) * size_t(frame.height))
    throw std::runtime_error(path + ": the frame has no " + what + " buffer of its size");
}

}  // namespace io

void checkOutputPath(OutputKind kind, const std::string& path) {
  switch (kind) {
    case OutputKind::Color:
    case OutputKind::DepthImage:
    case OutputKind::OverdrawImage: io::requirePng(path); return;
    case OutputKind::FaceIds: io::idFileFormat(path); return;
    case OutputKind::Depth: io::depthFileFormat(path); return;
  }
}

}  // namespace hsr

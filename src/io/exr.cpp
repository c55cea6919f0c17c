// OpenEXR depth files: one FLOAT channel "Z" (the name compositors and vision tools expect),
// encoded through an in-memory stream so writeDepth can still write it atomically, and the
// matching in-memory decoder the tests read it back with. Used by writeDepth (arrays.cpp).
#include "io/encode.hpp"

#include <OpenEXR/Iex.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>

#include <cstring>

namespace hsr::io {

namespace {

// A growable byte buffer with the seek OpenEXR needs to patch the line-offset table.
class MemoryOStream : public Imf::OStream {
 public:
  explicit MemoryOStream(const std::string& name) : Imf::OStream(name.c_str()) {}
  void write(const char c[], int n) override {
    if (pos_ + size_t(n) > bytes_.size()) bytes_.resize(pos_ + size_t(n));
    std::memcpy(bytes_.data() + pos_, c, size_t(n));
    pos_ += size_t(n);
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = size_t(pos); }
  Bytes take() { return std::move(bytes_); }

 private:
  Bytes bytes_;
  size_t pos_ = 0;
};

class MemoryIStream : public Imf::IStream {
 public:
  MemoryIStream(const Bytes& bytes, const std::string& name) : Imf::IStream(name.c_str()), bytes_(bytes) {}
  bool read(char c[], int n) override {
    if (n < 0 || pos_ > bytes_.size() || size_t(n) > bytes_.size() - pos_)
      throw Iex::InputExc("unexpected end of file");
    std::memcpy(c, bytes_.data() + pos_, size_t(n));
    pos_ += size_t(n);
    return pos_ < bytes_.size();
  }
  uint64_t tellg() override { return pos_; }
  void seekg(uint64_t pos) override { pos_ = size_t(pos); }

 private:
  const Bytes& bytes_;
  size_t pos_ = 0;
};

}  // namespace

Bytes encodeExrDepth(int width, int height, const float* rowsTopFirst, const std::string& name) {
  try {
    Imf::Header header(width, height);
    header.compression() = Imf::ZIP_COMPRESSION;
    header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer frameBuffer;
    frameBuffer.insert("Z", Imf::Slice::Make(Imf::FLOAT, rowsTopFirst, header.dataWindow()));

    MemoryOStream stream(name);
    {
      // The line-offset table is written when the OutputFile is destroyed: finish it first.
      Imf::OutputFile file(stream, header);
      file.setFrameBuffer(frameBuffer);
      file.writePixels(height);
    }
    return stream.take();
  } catch (const std::exception& e) {
    throw std::runtime_error(name + ": OpenEXR: " + e.what());
  }
}

FloatImage decodeExrDepth(const Bytes& exr, const std::string& name) {
  try {
    MemoryIStream stream(exr, name);
    Imf::InputFile file(stream);
    const Imath::Box2i window = file.header().dataWindow();
    if (!file.header().channels().findChannel("Z")) throw std::runtime_error("no channel named Z");
    FloatImage image;
    image.width = window.max.x - window.min.x + 1;
    image.height = window.max.y - window.min.y + 1;
    image.pixels.resize(size_t(image.width) * size_t(image.height));
    Imf::FrameBuffer frameBuffer;
    frameBuffer.insert("Z", Imf::Slice::Make(Imf::FLOAT, image.pixels.data(), window));
    file.setFrameBuffer(frameBuffer);
    file.readPixels(window.min.y, window.max.y);
    return image;
  } catch (const std::exception& e) {
    throw std::runtime_error(name + ": OpenEXR: " + e.what());
  }
}

}  // namespace hsr::io

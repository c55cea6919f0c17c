// Fuzz target: the render path. The input chooses a scene of up to 48 vertices and 24 polygons
// whose coordinates mix ordinary values with zeros, denormals, huge values, Inf and NaN (those
// that finalize() accepts are rendered), a camera (either style, any values), an image of up to
// 48x48, any registered algorithm with any values of its parameters, any depth format, outputs,
// culling, shading and thread count; render() must draw it or refuse it with an InputError.
#include <hsr/algorithm.hpp>
#include <hsr/render.hpp>

#include <cmath>
#include <limits>

#include "fuzz/fuzz_util.hpp"

namespace {

using hsr::fuzz::Bytes;

double number(Bytes& in) {
  static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 2.0, 1e-3, 1e3, 1e-300, 1e300, 1e30, -1e30,
                                   std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::min(),
                                   std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity(),
                                   -std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::quiet_NaN(), 1e-7, 3.0, -3.0, 10.0, 0.1, 7.0};
  const uint8_t kind = in.byte();
  if (kind < 96) return special[kind % std::size(special)];
  if (kind < 224) return double(int8_t(in.byte())) / 16.0;  // small, on a grid: ties, coplanar faces
  if (kind < 240) return double(in.raw<float>());
  return in.raw<double>();
}

hsr::dvec3 point(Bytes& in) {
  const double x = number(in), y = number(in);
  return {x, y, number(in)};
}

hsr::Scene scene(Bytes& in) {
  hsr::Scene s;
  s.source = "fuzz";
  const int vertices = in.range(3, 48);
  for (int i = 0; i < vertices; ++i) s.positions.push_back(point(in));
  const int faces = in.range(1, 24);
  for (int f = 0; f < faces; ++f) {
    if (in.below(8) == 0) s.beginMesh("m" + std::to_string(f));
    std::vector<uint32_t> face(size_t(in.range(3, 8)));
    for (uint32_t& v : face) v = in.below(uint32_t(vertices));
    s.addFace(face, hsr::Rgba8{in.byte(), in.byte(), in.byte(), uint8_t(in.flag() ? 255 : in.byte())});
  }
  return s;
}

hsr::CameraSpec camera(Bytes& in) {
  hsr::CameraSpec c;
  if (in.below(4) == 0) {
    c.kind = hsr::CameraSpec::Kind::OpenCV;
    for (auto& row : c.K)
      for (double& v : row) v = number(in);
    for (auto& row : c.worldToCamera)
      for (double& v : row) v = number(in);
    if (in.flag()) c.K[2][0] = c.K[2][1] = 0, c.K[2][2] = 1;
    if (in.flag()) c.worldToCamera[3][0] = c.worldToCamera[3][1] = c.worldToCamera[3][2] = 0, c.worldToCamera[3][3] = 1;
  } else {
    c.eye = point(in);
    c.target = point(in);
    if (in.flag()) c.up = point(in);
    c.fovyDeg = in.flag() ? 60 : number(in) * 10;
    if (in.below(4) == 0) c.orthoHeight = number(in);
  }
  if (in.flag()) c.near = number(in);
  if (in.flag()) c.far = number(in);
  return c;
}

std::string paramValue(Bytes& in, const hsr::ParamSpec& p) {
  switch (p.type) {
    case hsr::ParamType::Choice: return p.choices[in.below(uint32_t(p.choices.size()))];
    case hsr::ParamType::Bool: return in.flag() ? "on" : "off";
    case hsr::ParamType::Int: {
      const uint8_t kind = in.byte() % 4;
      if (kind == 0) return std::to_string(int64_t(p.min));
      if (kind == 1) return std::to_string(int64_t(std::min(p.max, p.min + 64)));
      return std::to_string(int64_t(p.min) + int64_t(in.below(uint32_t(std::min(p.max - p.min, 4096.0)) + 1)));
    }
    case hsr::ParamType::Real: {
      const double x = std::clamp(number(in), p.min, p.max);
      return std::isfinite(x) ? std::to_string(x) : p.defaultValue;
    }
  }
  return p.defaultValue;
}

hsr::RenderOptions options(Bytes& in) {
  static const char* const formats[] = {"u16:z", "u16:reversed", "u16:inv", "u16:linear", "u24:z", "u24:reversed",
                                        "u24:inv", "u24:linear", "u32:z", "u32:reversed", "u32:inv", "u32:linear",
                                        "f32:z", "f32:reversed", "f32:inv", "f32:linear"};
  static const hsr::FrameOutputs outputs[] = {hsr::FrameOutputs::All, hsr::FrameOutputs::DepthOnly,
                                              hsr::FrameOutputs::FaceIds, hsr::FrameOutputs::IdsAndDepth,
                                              hsr::FrameOutputs::Color, hsr::FrameOutputs::FaceIds | hsr::FrameOutputs::Color};
  const auto& registry = hsr::algorithms();
  const hsr::AlgorithmInfo& algorithm = registry[in.below(uint32_t(registry.size()))];
  hsr::RenderOptions o;
  o.algorithm = algorithm.name;
  for (const hsr::ParamSpec& p : algorithm.params)
    if (in.flag()) o.params[p.name] = paramValue(in, p);
  o.depthFormat = hsr::DepthFormat::parse(formats[in.below(std::size(formats))]);
  o.outputs = outputs[in.below(std::size(outputs))];
  o.cull = hsr::Cull(in.below(3));
  o.shading = hsr::Shading(in.below(3));
  o.background = hsr::Rgba8{in.byte(), in.byte(), in.byte(), 255};
  o.threads = in.range(1, 3);
  o.verify = in.below(4) == 0;
  o.countWrites = in.below(4) == 0;
  return o;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hsr::fuzz::setLimits();
  Bytes in(data, size);
  hsr::fuzz::refusedOrDone([&] {
    const hsr::RenderOptions o = options(in);
    const int width = in.range(1, 48), height = in.range(1, 48);
    const hsr::CameraSpec spec = camera(in);
    hsr::Scene s = scene(in);
    s.finalize();
    const hsr::Camera cam = hsr::resolveCamera(spec, width, height, s.bounds());
    hsr::render(s, cam, o);
  });
  return 0;
}

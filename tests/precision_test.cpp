// Depth precision (hsr::DepthPrecision) against the closed forms of each mapping, written out
// here independently: the eye depths stored as one value are those whose mapped value rounds to
// the same code (integer storage) or float.
#include <hsr/hsr.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

using hsr::DepthFormat;
using hsr::DepthPrecision;

// The mapping d -> v and its inverse, as the documents write them (perspective).
double mapped(const std::string& mapping, double d, double n, double f) {
  if (mapping == "z") return f * (d - n) / ((f - n) * d);
  if (mapping == "reversed") return 1 - f * (d - n) / ((f - n) * d);
  if (mapping == "inv") return n / d;
  return (d - n) / (f - n);
}
double unmapped(const std::string& mapping, double v, double n, double f) {
  if (mapping == "z") return f * n / (f - v * (f - n));
  if (mapping == "reversed") return f * n / (n + v * (f - n));
  if (mapping == "inv") return n / v;
  return n + v * (f - n);
}

double closedFormStep(const std::string& storage, const std::string& mapping, double d, double n, double f) {
  const double v = mapped(mapping, d, n, f);
  double lo, hi;
  if (storage == "f32") {
    const float x = float(v);
    lo = 0.5 * (double(x) + double(std::nextafter(x, -1.0f)));
    hi = 0.5 * (double(x) + double(std::nextafter(x, 2.0f)));
  } else {
    const double scale = std::ldexp(1.0, storage == "u16" ? 16 : storage == "u24" ? 24 : 32) - 1;
    const double code = std::floor(v * scale + 0.5);
    lo = (code - 0.5) / scale;
    hi = (code + 0.5) / scale;
  }
  // Depths outside [near, far] are clipped: the interval is the part within the range.
  const auto clamped = [&](double v) { return std::clamp(unmapped(mapping, v, n, f), n, f); };
  return std::abs(clamped(hi) - clamped(lo));
}

TEST(Precision, StepsMatchTheClosedFormOfEveryFormat) {
  const double n = 0.5, f = 400;
  for (const char* storage : {"u16", "u24", "u32", "f32"})
    for (const char* mapping : {"z", "reversed", "inv", "linear"}) {
      const DepthPrecision p{DepthFormat::parse(std::string(storage) + ":" + mapping), n, f};
      for (double d : {0.7, 1.3, 5.0, 33.3, 150.0, 399.0}) {
        const double expected = closedFormStep(storage, mapping, d, n, f);
        EXPECT_NEAR(p.step(d), expected, 1e-6 * expected) << storage << ":" << mapping << " at " << d;
        EXPECT_GT(p.step(d), 0) << storage << ":" << mapping << " at " << d;
      }
    }
}

TEST(Precision, PerspectiveZCrowdsItsValuesNearTheCamera) {
  // Integer z codes are uniform in z, so the share of codes in the first part x of the range is
  // z(near + x (far - near)), up to one code.
  for (double ratio : {10.0, 100.0, 1000.0})
    for (double x : {0.02, 0.1, 0.5}) {
      const DepthPrecision p{DepthFormat::parse("u24:z"), 1.0, ratio};
      const double z = mapped("z", 1 + x * (ratio - 1), 1, ratio);
      EXPECT_NEAR(p.valueFraction(x), z, 1e-6) << ratio << " " << x;
    }
  // The KTH thesis's figures: 91.7 % in the first 10 % at far/near = 100; 95.3 % (not 98 %) in
  // the first 2 % at far/near = 1000.
  EXPECT_NEAR((DepthPrecision{DepthFormat::parse("u24:z"), 1, 100}.valueFraction(0.1)), 0.9174, 1e-4);
  EXPECT_NEAR((DepthPrecision{DepthFormat::parse("u24:z"), 1, 1000}.valueFraction(0.02)), 0.9533, 1e-4);
  // Linear depth spreads them evenly; reversed float puts most of them far away.
  EXPECT_NEAR((DepthPrecision{DepthFormat::parse("u16:linear"), 1, 100}.valueFraction(0.25)), 0.25, 1e-4);
  EXPECT_LT((DepthPrecision{DepthFormat::parse("f32:reversed"), 1, 100}.valueFraction(0.1)), 0.2);
}

TEST(Precision, CountsStoredValues) {
  EXPECT_EQ((DepthPrecision{DepthFormat::parse("u16:linear"), 1, 2}.valuesBetween(1, 2)), 65536u);
  EXPECT_EQ((DepthPrecision{DepthFormat::parse("u24:z"), 1, 2}.valuesBetween(1, 2)), 16777216u);
  EXPECT_EQ((DepthPrecision{DepthFormat::parse("u16:z"), 1, 2}.valuesBetween(1.5, 1.5)), 1u);
}

TEST(Orbit, TurnsTheCameraAroundTheCentre) {
  hsr::CameraSpec spec;
  spec.eye = {3, 1, 4};
  spec.target = {0, 0.5, 0};
  const hsr::Camera cam = hsr::resolveCamera(spec, 64, 48, hsr::Bounds3{{-1, -1, -1}, {1, 1, 1}});
  const hsr::dvec3 centre{0, 0.5, 0};
  const std::vector<hsr::Camera> orbit = hsr::orbitCameras(cam, centre, 4);
  ASSERT_EQ(orbit.size(), 4u);
  EXPECT_EQ(orbit[0].cameraFromWorld, cam.cameraFromWorld);
  for (const hsr::Camera& c : orbit) {
    EXPECT_NEAR(glm::length(c.eyeWorld() - centre), glm::length(cam.eyeWorld() - centre), 1e-9);
    EXPECT_NEAR(c.toCamera(centre).z, cam.toCamera(centre).z, 1e-9);  // still looking at it, as far
  }
  // Half a turn: the eye on the other side of the axis (the camera's up through the centre).
  const hsr::dvec3 up = glm::normalize(hsr::dvec3(glm::inverse(cam.cameraFromWorld) * hsr::dvec4(0, -1, 0, 0)));
  const hsr::dvec3 a = cam.eyeWorld() - centre, b = orbit[2].eyeWorld() - centre;
  EXPECT_NEAR(glm::dot(a, up), glm::dot(b, up), 1e-9);
  const hsr::dvec3 aAcross = a - glm::dot(a, up) * up, bAcross = b - glm::dot(b, up) * up;
  EXPECT_NEAR(glm::length(aAcross + bAcross), 0, 1e-9);
  EXPECT_GT(glm::length(aAcross), 1);
  // A full turn gives the camera back.
  const hsr::Camera back = hsr::orbitCamera(cam, centre, 2 * M_PI);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(back.cameraFromWorld[i][j], cam.cameraFromWorld[i][j], 1e-12);
}

}  // namespace

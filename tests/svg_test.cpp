// Vector output (include/hsr/svg.hpp): the SVG of newell's and bsp's painting order, rasterized
// by a real SVG renderer (rsvg-convert, Debian's librsvg2-bin) and decoded with faceid colours,
// shows raycast's face at every pixel away from polygon edges (where anti-aliasing blends); the
// painter's SVG of its failure scene does not. Also: the file's form (polygons parsed back,
// coordinates to 1/1000 pixel inside the image), culling, and the command line.
#include <hsr/hsr.hpp>

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "conformance.hpp"
#include "temp_dir.hpp"
#include "test_scenes.hpp"

namespace hsr {
namespace {

struct SvgPolygon {
  std::vector<dvec2> points;
  std::string fill;
  size_t element = 0;  // which element of the file it is in (a path holds several polygons)
};

std::vector<dvec2> parsePoints(const std::string& text) {
  std::vector<dvec2> points;
  std::istringstream in(text);
  std::string pair;
  while (in >> pair) {
    const size_t comma = pair.find(',');
    points.emplace_back(std::stod(pair.substr(0, comma)), std::stod(pair.substr(comma + 1)));
  }
  return points;
}

// Our SVG's polygons, read back with their exact text: every element after the <svg> element (no
// background element: the conventions' "nothing for the background") is a <polygon points="x,y ..." fill="#rrggbb"/> or a <path d="Mx,y ...ZMx,y ...Z" fill=.../>
// (optionally with fill-opacity), a path's subpaths being polygons of one fill.
std::vector<SvgPolygon> parsePolygons(const std::string& svg) {
  std::vector<SvgPolygon> out;
  static const std::regex element(
      R"re(<(polygon points|path d)="([^"]*)" fill="(#[0-9a-f]{6})"( fill-opacity="[0-9.]+")?/>)re");
  size_t index = 0;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), element); it != std::sregex_iterator(); ++it, ++index) {
    const std::string points = (*it)[2];
    if ((*it)[1] == "polygon points") {
      out.push_back({parsePoints(points), (*it)[3], index});
      continue;
    }
    for (size_t at = 0; at < points.size();) {  // "M...Z" subpaths
      const size_t z = points.find('Z', at);
      out.push_back({parsePoints(points.substr(at + 1, z - at - 1)), (*it)[3], index});
      at = z + 1;
    }
  }
  return out;
}

// The face a faceid colour shows, as docs/conventions.md says: R, G, B as a 24-bit integer, minus
// one (-1: the background, black).
int32_t decodeFace(const unsigned char* rgb) { return int32_t((rgb[0] << 16) | (rgb[1] << 8) | rgb[2]) - 1; }

// Pixels within about a pixel of any polygon's edge: anti-aliasing blends colours there.
std::vector<bool> nearEdges(const std::vector<SvgPolygon>& polygons, int w, int h) {
  std::vector<bool> mask(size_t(w) * size_t(h), false);
  for (const SvgPolygon& p : polygons)
    for (size_t i = 0; i < p.points.size(); ++i) {
      const dvec2 a = p.points[i], b = p.points[(i + 1) % p.points.size()];
      const int steps = 1 + int(4 * glm::length(b - a));
      for (int s = 0; s <= steps; ++s) {
        const dvec2 x = a + (b - a) * (double(s) / steps);
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int px = int(std::floor(x.x)) + dx, py = int(std::floor(x.y)) + dy;
            if (px >= 0 && py >= 0 && px < w && py < h) mask[size_t(py) * size_t(w) + size_t(px)] = true;
          }
      }
    }
  return mask;
}

struct Decoded {
  uint64_t tested = 0, wrong = 0, pixels = 0, polygons = 0;
};

class SvgTest : public test::TempDirTest {
 protected:
  // Renders `algorithm`'s SVG with faceid colours, rasterizes it with rsvg-convert and compares
  // the face each pixel away from edges decodes to with the reference's face.
  Decoded decode(const Scene& scene, const CameraSpec& spec, const std::string& algorithm, int w, int h) {
    const Camera camera = resolveCamera(spec, w, h, scene.bounds());
    RenderOptions options;
    options.algorithm = algorithm;
    options.shading = Shading::FaceId;
    const std::string svgPath = path("out.svg"), pngPath = path("out.png");
    writeSvg(scene, camera, options, svgPath);
    const std::string command = "rsvg-convert --background-color=black '" + svgPath + "' -o '" + pngPath + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command << " (scripts/install-deps.sh installs librsvg2-bin)";
    int pw = 0, ph = 0, channels = 0;
    unsigned char* pixels = stbi_load(pngPath.c_str(), &pw, &ph, &channels, 3);
    Decoded d;
    if (!pixels || pw != w || ph != h) {
      ADD_FAILURE() << "rsvg-convert's image: " << pw << "x" << ph << " for " << w << "x" << h;
      stbi_image_free(pixels);
      return d;
    }
    std::ifstream in(svgPath);
    const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::vector<SvgPolygon> polygons = parsePolygons(svg);
    d.polygons = polygons.size();
    const std::vector<bool> edge = nearEdges(polygons, w, h);
    RenderOptions ref;
    ref.algorithm = "raycast";
    const Frame reference = render(scene, camera, ref);
    for (size_t i = 0; i < size_t(w) * size_t(h); ++i) {
      ++d.pixels;
      if (edge[i]) continue;
      ++d.tested;
      d.wrong += decodeFace(pixels + 3 * i) != reference.faceId[i];
    }
    stbi_image_free(pixels);
    return d;
  }
};

TEST_F(SvgTest, NewellAndBspDecodeToTheReferenceAwayFromEdges) {
  const std::vector<std::pair<std::string, Scene>> scenes = [] {
    std::vector<std::pair<std::string, Scene>> s;
    for (const char* name : {"builtin:painter-cycle", "builtin:painter-midpoint", "builtin:interpenetrate",
                             "builtin:cubes", "builtin:random?n=300&seed=5", "builtin:city?blocks=3",
                             "builtin:sphere?n=2000"})
      s.emplace_back(name, loadScene(name));
    s.emplace_back("test:polygons", test::randomPolygons(40, 4));
    return s;
  }();
  for (const auto& [name, scene] : scenes)
    for (const char* algorithm : {"newell", "bsp"}) {
      std::vector<CameraSpec> cameras{conformance::ownPose(scene).spec};
      for (const conformance::Pose& p : conformance::posesAround(scene, 2, 17)) cameras.push_back(p.spec);
      for (const CameraSpec& spec : cameras) {
        const Decoded d = decode(scene, spec, algorithm, 200, 150);
        EXPECT_EQ(d.wrong, 0u) << algorithm << " on " << name << ": " << d.wrong << " of " << d.tested
                               << " pixels away from edges differ from raycast\n" << cameraSpecToJson(spec);
        if (spec.eye == conformance::ownPose(scene).spec.eye) EXPECT_GT(d.tested, d.pixels / 4) << name;
      }
    }
}

// Translucent faces become fill-opacity, and the SVG renderer blends newell's order as the
// A-buffer does: within one 8-bit step away from edges on builtin:glass.
TEST_F(SvgTest, NewellsTranslucentSvgBlendsAsTheAbuffer) {
  const Scene scene = loadScene("builtin:glass");
  const int w = 200, h = 150;
  const Camera camera = resolveCamera(*scene.camera, w, h, scene.bounds());
  RenderOptions options;
  options.algorithm = "newell";
  const std::string svgPath = path("glass.svg"), pngPath = path("glass.png");
  writeSvg(scene, camera, options, svgPath);
  std::ifstream in(svgPath);
  const std::string svg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(svg.find("fill-opacity=\""), std::string::npos);
  // The SVG has no background: the page under it is the raster's background, black.
  const std::string command = "rsvg-convert --background-color=black '" + svgPath + "' -o '" + pngPath + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  int pw = 0, ph = 0, channels = 0;
  unsigned char* pixels = stbi_load(pngPath.c_str(), &pw, &ph, &channels, 3);
  ASSERT_TRUE(pixels && pw == w && ph == h);
  RenderOptions ref;
  ref.algorithm = "abuffer";
  const Frame reference = render(scene, camera, ref);
  const std::vector<bool> edge = nearEdges(parsePolygons(svg), w, h);
  uint64_t tested = 0, beyond = 0;
  for (size_t i = 0; i < size_t(w) * size_t(h); ++i) {
    if (edge[i]) continue;
    ++tested;
    const Rgba8 want = reference.color[i];
    const unsigned char* got = pixels + 3 * i;
    beyond += std::abs(got[0] - want.r) > 1 || std::abs(got[1] - want.g) > 1 || std::abs(got[2] - want.b) > 1;
  }
  stbi_image_free(pixels);
  EXPECT_EQ(beyond, 0u) << "of " << tested;
  EXPECT_GT(tested, uint64_t(w * h) / 2);
}

// The check can fail: the painter's SVG of its cycle is wrong away from edges too.
TEST_F(SvgTest, PainterOnItsCycleDecodesWrong) {
  const Scene scene = loadScene("builtin:painter-cycle");
  const Decoded d = decode(scene, *scene.camera, "painter", 200, 150);
  EXPECT_GT(d.wrong, 50u);
}

// Pixels of a w x h image away from every visible edge: the 3x3 pixels around them show one face
// (or the background) at each of kSamples x kSamples points a pixel, in `fine`, face ids of the
// same view at kSamples times the size (so even a sliver thinner than a pixel is seen). Sets
// `ids` to each pixel's face.
constexpr int kSamples = 4;
std::vector<bool> interiorOf(const Frame& fine, int w, int h, std::vector<int32_t>& ids) {
  std::vector<bool> one(size_t(w) * size_t(h)), inside(one.size(), false);
  ids.assign(one.size(), -1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int32_t id = fine.faceId[size_t(kSamples * y) * size_t(fine.width) + size_t(kSamples * x)];
      bool same = true;
      for (int sy = 0; sy < kSamples; ++sy)
        for (int sx = 0; sx < kSamples; ++sx)
          same &= fine.faceId[size_t(kSamples * y + sy) * size_t(fine.width) + size_t(kSamples * x + sx)] == id;
      ids[size_t(y) * size_t(w) + size_t(x)] = id;
      one[size_t(y) * size_t(w) + size_t(x)] = same;
    }
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      bool same = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const size_t j = size_t(y + dy) * size_t(w) + size_t(x + dx);
          same &= one[j] && ids[j] == ids[i];
        }
      inside[i] = same;
    }
  return inside;
}

// Where bsp and newell split faces, the SVG paints a face's pieces as one <path> (and repaints
// the parts of earlier pieces beside later ones): rasterized by rsvg-convert with its default
// anti-aliasing, the pixels away from edges show their face, with few seams along the splits. (One
// <polygon> per piece gives 794 (bsp) and 179 (newell) seam pixels of 90,617 here.)
TEST_F(SvgTest, SplitFacesShowNoSeamsUnderAntiAliasing) {
  const Scene scene = loadScene("builtin:random?n=300&seed=5");
  const int w = 400, h = 300;
  const CameraSpec spec = conformance::ownPose(scene).spec;
  const Camera camera = resolveCamera(spec, w, h, scene.bounds());
  RenderOptions ref;
  ref.algorithm = "raycast";
  const Frame fine = render(scene, resolveCamera(spec, kSamples * w, kSamples * h, scene.bounds()), ref);
  std::vector<int32_t> ids;
  const std::vector<bool> inside = interiorOf(fine, w, h, ids);
  const uint64_t interior = uint64_t(std::count(inside.begin(), inside.end(), true));
  EXPECT_GT(interior, uint64_t(w * h) / 2);
  for (const char* algorithm : {"bsp", "newell"}) {
    RenderOptions options;
    options.algorithm = algorithm;
    options.shading = Shading::FaceId;
    const std::string svgPath = path(std::string(algorithm) + ".svg"), pngPath = path(std::string(algorithm) + ".png");
    writeSvg(scene, camera, options, svgPath);
    const std::string command = "rsvg-convert --background-color=black '" + svgPath + "' -o '" + pngPath + "'";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    int pw = 0, ph = 0, channels = 0;
    unsigned char* pixels = stbi_load(pngPath.c_str(), &pw, &ph, &channels, 3);
    ASSERT_TRUE(pixels && pw == w && ph == h);
    uint64_t seams = 0;
    for (size_t i = 0; i < inside.size(); ++i) seams += inside[i] && decodeFace(pixels + 3 * i) != ids[i];
    stbi_image_free(pixels);
    EXPECT_LE(seams, 40u) << algorithm << ": " << seams << " of " << interior << " pixels away from edges";
  }
}

// One faceid convention everywhere (docs/conventions.md): the colour image with faceid shading is
// the face-id PNG, byte for byte, and each SVG fill decodes to its polygon's face.
TEST_F(SvgTest, FaceIdColoursDecodeAsDocumented) {
  const std::string colour = path("c.png"), ids = path("ids.png");
  const std::string command = std::string(HSR_CLI_PATH) + " render builtin:cubes --algorithm zbuffer --size 96x72 " +
                              "--shading faceid -q --out '" + colour + "' --ids '" + ids + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  int w = 0, h = 0, n = 0, w2 = 0, h2 = 0;
  unsigned char* a = stbi_load(colour.c_str(), &w, &h, &n, 3);
  unsigned char* b = stbi_load(ids.c_str(), &w2, &h2, &n, 3);
  ASSERT_TRUE(a && b && w == 96 && h == 72 && w2 == w && h2 == h);
  EXPECT_TRUE(std::equal(a, a + 3 * w * h, b));
  std::set<int32_t> faces;
  for (int i = 0; i < w * h; ++i) faces.insert(decodeFace(a + 3 * i));
  EXPECT_GT(faces.size(), 3u);
  stbi_image_free(a);
  stbi_image_free(b);

  const Scene scene = loadScene("builtin:random?n=300&seed=5");
  const Camera camera = resolveCamera(conformance::ownPose(scene).spec, 200, 150, scene.bounds());
  RenderOptions options;
  options.algorithm = "bsp";
  options.shading = Shading::FaceId;
  const std::vector<SvgPolygon> svg = parsePolygons(renderSvg(scene, camera, options));
  const ScreenPolygons painted = screenPolygons(scene, camera, options);
  ASSERT_EQ(svg.size(), painted.polygons.size());
  for (size_t i = 0; i < svg.size(); ++i) {
    const unsigned char rgb[3] = {uint8_t(std::stoi(svg[i].fill.substr(1, 2), nullptr, 16)),
                                  uint8_t(std::stoi(svg[i].fill.substr(3, 2), nullptr, 16)),
                                  uint8_t(std::stoi(svg[i].fill.substr(5, 2), nullptr, 16))};
    EXPECT_EQ(decodeFace(rgb), int32_t(painted.polygons[i].face)) << svg[i].fill;
  }
}

// Whether every vertex of `part` lies in the convex polygon `piece` (to 1e-6 pixel; edges of less
// than 1e-7 pixel, a vertex repeated up to rounding, have no direction to test).
bool insideConvex(const ScreenPolygons& s, const ScreenPolygon& part, const ScreenPolygon& piece) {
  double area = 0;
  for (uint32_t k = 0; k < piece.count; ++k) {
    const dvec2 a = s.points[piece.first + k], b = s.points[piece.first + (k + 1) % piece.count];
    area += a.x * b.y - a.y * b.x;
  }
  for (uint32_t v = 0; v < part.count; ++v)
    for (uint32_t k = 0; k < piece.count; ++k) {
      const dvec2 a = s.points[piece.first + k], e = s.points[piece.first + (k + 1) % piece.count] - a;
      const dvec2 d = s.points[part.first + v] - a;
      const double length = glm::length(e);
      if (length > 1e-7 && (area > 0 ? 1 : -1) * (e.x * d.y - e.y * d.x) / length < -1e-6) return false;
    }
  return true;
}

// Paint groups: consecutive, numbered in order, one face and colour each; a repaint is a part of
// a piece of the same face painted in an earlier group.
TEST_F(SvgTest, PaintGroupsHoldOneFaceEach) {
  const Scene scene = loadScene("builtin:random?n=300&seed=5");
  const Camera camera = resolveCamera(conformance::ownPose(scene).spec, 200, 150, scene.bounds());
  RenderOptions options;
  options.algorithm = "bsp";
  const ScreenPolygons painted = screenPolygons(scene, camera, options);
  ASSERT_FALSE(painted.polygons.empty());
  EXPECT_EQ(painted.polygons.front().group, 0u);
  EXPECT_EQ(painted.polygons.back().group + 1, painted.groups);
  size_t merged = 0, repaints = 0;
  for (size_t i = 1; i < painted.polygons.size(); ++i) {
    const ScreenPolygon &a = painted.polygons[i - 1], &b = painted.polygons[i];
    ASSERT_TRUE(b.group == a.group || b.group == a.group + 1);
    if (b.group != a.group) continue;
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.color, b.color);
    merged += !b.repaint;
  }
  for (const ScreenPolygon& r : painted.polygons) {
    if (!r.repaint) continue;
    ++repaints;
    EXPECT_TRUE(std::any_of(painted.polygons.begin(), painted.polygons.end(), [&](const ScreenPolygon& p) {
      return !p.repaint && p.group < r.group && p.face == r.face && insideConvex(painted, r, p);
    }));
  }
  EXPECT_GT(merged, 0u);    // pieces of a face joined
  EXPECT_GT(repaints, 0u);  // and some faces still span groups
}

TEST_F(SvgTest, CoordinatesAreCompactAndInsideTheImage) {
  const Scene scene = loadScene("builtin:random?n=300&seed=5");
  const Camera camera = resolveCamera(conformance::posesAround(scene, 1, 3)[0].spec, 120, 90, scene.bounds());
  RenderOptions options;
  options.algorithm = "newell";
  const std::string svg = renderSvg(scene, camera, options);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("width=\"120\" height=\"90\" viewBox=\"0 0 120 90\""), std::string::npos);
  EXPECT_EQ(svg.substr(svg.size() - 7), "</svg>\n");
  const std::vector<SvgPolygon> polygons = parsePolygons(svg);
  ASSERT_GT(polygons.size(), 100u);
  size_t elements = 0;
  for (const char* tag : {"<polygon", "<path"})
    for (size_t at = svg.find(tag); at != std::string::npos; at = svg.find(tag, at + 1)) ++elements;
  EXPECT_EQ(elements, polygons.back().element + 1);  // every element in the form parsePolygons reads
  static const std::regex number(R"(-?[0-9]+(\.[0-9]{1,3})?)");
  for (const SvgPolygon& p : polygons) {
    EXPECT_GE(p.points.size(), 3u);
    for (const dvec2& v : p.points) {
      EXPECT_TRUE(v.x >= 0 && v.x <= 120 && v.y >= 0 && v.y <= 90) << v.x << "," << v.y;
    }
  }
  static const std::regex points(R"re((points|d)="([^"]*)")re");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), points); it != std::sregex_iterator(); ++it) {
    std::string text = (*it)[2].str();
    for (char& c : text)
      if (c == 'M' || c == 'Z') c = ' ';
    std::istringstream in(text);
    std::string pair;
    while (in >> pair) {
      const std::string x = pair.substr(0, pair.find(',')), y = pair.substr(pair.find(',') + 1);
      EXPECT_TRUE(std::regex_match(x, number) && std::regex_match(y, number)) << pair;
      EXPECT_TRUE(x.back() != '0' || x.find('.') == std::string::npos) << pair;  // no trailing zeros
    }
  }
}

TEST_F(SvgTest, BackFacesCulledAsTheRasterDoes) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera camera = resolveCamera(*scene.camera, 160, 120, scene.bounds());
  RenderOptions options;
  options.algorithm = "bsp";
  auto painted = [&] {  // the polygons painted once each (repaints are copies)
    size_t n = 0;
    for (const ScreenPolygon& p : screenPolygons(scene, camera, options).polygons) n += !p.repaint;
    return n;
  };
  const size_t all = painted();
  options.cull = Cull::Back;
  const size_t front = painted();
  options.cull = Cull::Front;
  const size_t back = painted();
  EXPECT_GT(front, 0u);
  EXPECT_GT(back, 0u);
  EXPECT_EQ(front + back, all);
}

TEST_F(SvgTest, OnlyPolygonPaintingAlgorithmsWriteSvg) {
  const Scene scene = loadScene("builtin:cubes");
  const Camera camera = resolveCamera(*scene.camera, 32, 24, scene.bounds());
  RenderOptions options;
  options.algorithm = "zbuffer";
  EXPECT_THROW(renderSvg(scene, camera, options), InputError);
  EXPECT_THROW(checkSvgPath(path("a.png")), InputError);
  EXPECT_NO_THROW(checkSvgPath(path("a.SVG")));
}

TEST_F(SvgTest, CommandLineWritesTheFileAndRefusesOtherAlgorithms) {
  const std::string svg = path("c.svg");
  const std::string ok = std::string(HSR_CLI_PATH) + " render builtin:painter-cycle --algorithm newell --size 64x48 -q --svg '" + svg + "'";
  ASSERT_EQ(std::system(ok.c_str()), 0);
  std::ifstream in(svg);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("<polygon"), std::string::npos);
  const std::string bad = std::string(HSR_CLI_PATH) + " render builtin:cubes --algorithm zbuffer -q --svg '" +
                          path("z.svg") + "' 2>/dev/null";
  const int status = std::system(bad.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2);
  EXPECT_FALSE(std::filesystem::exists(path("z.svg")));
}

}  // namespace
}  // namespace hsr

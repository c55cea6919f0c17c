// Built-in scenes after the figures of the source documents: the four cubes of the KTH thesis, the
// painter's-algorithm failures of the KTH report (Fig. 2/3 midpoint sort, Fig. 4 cycle), interpenetrating
// polygons and a z-fighting pair. Small, fixed scenes; called by makeBuiltin() (builtin.cpp).
//
// Coordinates use only +, *, / and sqrt, and rotations take exact (cos, sin) pairs such as
// (4/5, 3/5): no libm trigonometry, so every platform builds bit-identical scenes.
#include <cmath>

#include "scene/builtin_internal.hpp"

#ifdef __clang__
#pragma STDC FP_CONTRACT OFF  // no fused multiply-add: the same bits as GCC's ISO mode
#endif

namespace hsr::builtin {

// The KTH thesis's first comparison scene: 24 quads, four cubes of different sizes and turns at different
// depths, so that nearer cubes hide parts of farther ones.
Scene makeCubes(const Args&) {
  struct Cube {
    dvec3 center;
    double half;
    dmat3 axes;
  };
  const Cube cubes[4] = {
      {{-1.0, -0.25, 1.4}, 0.8, rotationY(12.0 / 13, 5.0 / 13)},
      {{0.3, 0.25, -0.8}, 1.0, rotationY(4.0 / 5, 3.0 / 5) * rotationX(15.0 / 17, 8.0 / 17)},
      {{1.5, -0.55, 2.0}, 0.6, rotationY(20.0 / 29, -21.0 / 29)},
      {{-0.6, 0.7, -4.2}, 1.4, rotationY(3.0 / 5, 4.0 / 5)},
  };
  Scene scene;
  for (int c = 0; c < 4; ++c) {
    scene.beginMesh("cube" + std::to_string(c));
    const Rgba8 base = paletteColor(uint64_t(c));
    addBox(scene, cubes[c].center, cubes[c].axes, dvec3(cubes[c].half),
           [&](int k) { return shade(base, faceShade(k)); });
  }
  scene.camera = perspectiveCamera({1.0, 2.2, 8.5}, {0, 0, -0.5}, 45, 1, 20);
  return scene;
}

// The KTH report, Fig. 2/3: a long bar whose depth rises along its length. Its centroid lies behind the
// square, but its near end passes in front of it; sorted by midpoint, the square is drawn last
// and wrongly covers the bar. Only a per-pixel test (z-buffer) or splitting draws it right.
Scene makePainterMidpoint(const Args&) {
  Scene scene;
  // The square, in the plane z = -1.5.
  scene.beginMesh("square");
  addPolygon(scene, {{2.2, -1.5, -1.5}, {4.0, -1.5, -1.5}, {4.0, 1.5, -1.5}, {2.2, 1.5, -1.5}},
             Rgba8{215, 60, 50, 255});
  // The bar: z = x - 2.4, its centroid at z = -2.4, 0.9 behind the square's; but it is in
  // front of the square's plane wherever x > 0.9, which includes all of it that overlaps the
  // square in the image.
  scene.beginMesh("tilted-bar");
  addPolygon(scene, {{-4.6, -0.5, -7.0}, {4.6, -0.5, 2.2}, {4.6, 0.5, 2.2}, {-4.6, 0.5, -7.0}},
             Rgba8{50, 95, 220, 255});
  scene.camera = perspectiveCamera({1.2, 1.2, 10}, {1.2, 0, -1.5}, 40, 1, 25);
  return scene;
}

// The KTH report, Fig. 4: three bars along the sides of a triangle, each rising in depth from its start to
// its end. Where bar i ends it crosses the start of bar i+1, high above it: 0 over 1, 1 over 2,
// 2 over 0. No two bars intersect, yet no drawing order of whole polygons is right.
Scene makePainterCycle(const Args&) {
  const double root3half = std::sqrt(3.0) / 2;
  const double radius = 2, extension = 0.6, halfWidth = 0.25, lowZ = -1, highZ = 1;
  // Triangle corners at 90, 210 and 330 degrees (counter-clockwise).
  const dvec2 corner[3] = {
      {0, radius}, {-root3half * radius, -0.5 * radius}, {root3half * radius, -0.5 * radius}};
  const Rgba8 colors[3] = {{220, 70, 60, 255}, {70, 180, 80, 255}, {60, 100, 220, 255}};
  Scene scene;
  for (int i = 0; i < 3; ++i) {
    const dvec2 from = corner[i], to = corner[(i + 1) % 3];
    const dvec2 along = glm::normalize(to - from);
    const dvec2 across(-along.y, along.x);  // to the left of `along`
    const dvec2 start = from - extension * along, end = to + extension * along;
    // Depth varies along the bar only, so the quad is planar.
    const auto at = [&](dvec2 p, double z) { return dvec3(p.x, p.y, z); };
    scene.beginMesh("bar" + std::to_string(i));
    addPolygon(scene,
               {at(start - halfWidth * across, lowZ), at(end - halfWidth * across, highZ),
                at(end + halfWidth * across, highZ), at(start + halfWidth * across, lowZ)},
               colors[i]);
  }
  scene.camera = perspectiveCamera({0, -0.7, 12}, {0, 0.3, 0}, 30, 2, 25);
  return scene;
}

// Two quads through each other: both contain the segment x = z = 0, |y| <= 1, and are turned
// 22.6 degrees either way about y, so each is in front on one side of the intersection line.
Scene makeInterpenetrate(const Args&) {
  Scene scene;
  const auto quad = [&](const char* name, const dmat3& turn, double halfX, double lowY,
                        double highY, Rgba8 color) {
    scene.beginMesh(name);
    addPolygon(scene,
               {turn * dvec3(-halfX, lowY, 0), turn * dvec3(halfX, lowY, 0),
                turn * dvec3(halfX, highY, 0), turn * dvec3(-halfX, highY, 0)},
               color);
  };
  quad("wide", rotationY(12.0 / 13, 5.0 / 13), 2.0, -1.0, 1.0, Rgba8{235, 170, 50, 255});
  quad("tall", rotationY(12.0 / 13, -5.0 / 13), 1.5, -1.0, 2.0, Rgba8{60, 150, 210, 255});
  scene.camera = perspectiveCamera({0, 1.5, 7}, {0, 0.3, 0}, 45, 1, 20);
  return scene;
}

// Transparency: an opaque floor, over it three translucent bars in a cycle (as painter-cycle,
// none in front of all the others) and two translucent quads through each other (as
// interpenetrate): no order of whole faces blends them right, every pixel of the overlaps needs
// its fragments in depth order.
Scene makeGlass(const Args&) {
  Scene scene;
  scene.beginMesh("floor");
  addPolygon(scene, {{-4, -4, -1.6}, {4, -4, -1.6}, {4, 4, -1.6}, {-4, 4, -1.6}}, Rgba8{200, 200, 190, 255});
  const double root3half = std::sqrt(3.0) / 2, radius = 2, extension = 0.6, halfWidth = 0.35;
  const dvec2 corner[3] = {{0, radius}, {-root3half * radius, -0.5 * radius}, {root3half * radius, -0.5 * radius}};
  const Rgba8 colors[3] = {{230, 60, 50, 150}, {60, 200, 80, 170}, {50, 90, 230, 128}};
  for (int i = 0; i < 3; ++i) {
    const dvec2 from = corner[i], to = corner[(i + 1) % 3];
    const dvec2 along = glm::normalize(to - from), across(-along.y, along.x);
    const dvec2 start = from - extension * along, end = to + extension * along;
    const auto at = [&](dvec2 p, double z) { return dvec3(p.x, p.y, z); };
    scene.beginMesh("bar" + std::to_string(i));
    addPolygon(scene,
               {at(start - halfWidth * across, -1), at(end - halfWidth * across, 1),
                at(end + halfWidth * across, 1), at(start + halfWidth * across, -1)},
               colors[i]);
  }
  const auto quad = [&](const char* name, const dmat3& turn, Rgba8 color) {
    scene.beginMesh(name);
    const dvec3 shift(0, 0.2, 0.3);
    addPolygon(scene,
               {shift + turn * dvec3(-0.9, -0.9, 0), shift + turn * dvec3(0.9, -0.9, 0),
                shift + turn * dvec3(0.9, 0.9, 0), shift + turn * dvec3(-0.9, 0.9, 0)},
               color);
  };
  quad("pane-a", rotationY(12.0 / 13, 5.0 / 13), Rgba8{240, 200, 40, 160});
  quad("pane-b", rotationY(12.0 / 13, -5.0 / 13), Rgba8{200, 60, 220, 140});
  scene.camera = perspectiveCamera({0, -3.5, 11}, {0, 0.2, -0.3}, 32, 2, 30);
  return scene;
}

// Z-fighting: a rectangle, and in front of it a diamond made by scaling the diamond's points in
// the rectangle's plane towards the eye by (1 - gap). Every point of the diamond is therefore
// nearer by exactly `gap` times its eye depth and projects where its source point does. The
// plane is turned 36.9 degrees so depth varies across the image (bands, not a uniform tie),
// and the rectangle comes first, so on a depth tie the farther surface wins. With near 0.1 and
// far 1000, u16 depth cannot separate a gap of 1e-4; f32:reversed and u24 can.
Scene makeZfight(const Args& args) {
  const double gap = args.real("gap");
  const dvec3 eye(0, 0, 10);
  const dmat3 plane = rotationY(4.0 / 5, 3.0 / 5);
  Scene scene;
  scene.beginMesh("back");
  addPolygon(scene,
             {plane * dvec3(-4, -3, 0), plane * dvec3(4, -3, 0), plane * dvec3(4, 3, 0),
              plane * dvec3(-4, 3, 0)},
             Rgba8{70, 110, 200, 255});
  const auto front = [&](double x, double y) {
    return eye + (plane * dvec3(x, y, 0) - eye) * (1 - gap);
  };
  scene.beginMesh("front");
  addPolygon(scene, {front(0, -2.4), front(3.2, 0), front(0, 2.4), front(-3.2, 0)},
             Rgba8{230, 140, 40, 255});
  scene.camera = perspectiveCamera(eye, {0, 0, 0}, 50, 0.1, 1000);
  return scene;
}

}  // namespace hsr::builtin

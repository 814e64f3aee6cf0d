// The Cornell box, from the measurements published by the Cornell Program of
// Computer Graphics ("Cornell Box Data"): coordinates in millimetres, camera
// at (278, 273, -800) looking down +z, 35 mm focal length on a 25 mm film.
// One change: the light is moved 0.1 mm below the ceiling (548.7 instead of
// 548.8) so the two are not coplanar. Reflectances and emission are the RGB
// values commonly used for this scene.
#include <array>

#include "scenes/procedural.h"

namespace raylab {

namespace {

using Quad = std::array<std::array<float, 3>, 4>;

void add_quad(Scene& s, const Quad& q, uint32_t material) {
  const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
  for (const auto& p : q) s.mesh.vertices.emplace_back(p[0], p[1], p[2]);
  s.mesh.triangles.push_back({base, base + 1, base + 2});
  s.mesh.triangles.push_back({base, base + 2, base + 3});
  s.material_ids.push_back(material);
  s.material_ids.push_back(material);
}

}  // namespace

Scene make_cornell_box() {
  Scene s;
  s.name = "cornell";
  enum : uint32_t { kWhite, kRed, kGreen, kLight };
  s.materials = {
      Material{Vec3f(0.725f, 0.71f, 0.68f), Vec3f::Zero()},
      Material{Vec3f(0.63f, 0.065f, 0.05f), Vec3f::Zero()},
      Material{Vec3f(0.14f, 0.45f, 0.091f), Vec3f::Zero()},
      Material{Vec3f(0.78f, 0.78f, 0.78f), Vec3f(17.0f, 12.0f, 4.0f)},
  };
  // Floor, ceiling, back wall.
  add_quad(s, {{{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}}}, kWhite);
  add_quad(s, {{{556.0f, 548.8f, 0}, {556.0f, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}}}, kWhite);
  add_quad(s, {{{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}}}, kWhite);
  // Green wall at x = 0 (camera's right), red wall at x = 552.8 (camera's left).
  add_quad(s, {{{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}}}, kGreen);
  add_quad(s, {{{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}}}, kRed);
  // Area light, front face pointing down into the box.
  add_quad(s, {{{343.0f, 548.7f, 227.0f}, {343.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 227.0f}}},
           kLight);
  // Short block.
  add_quad(s, {{{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}}}, kWhite);
  add_quad(s, {{{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}}}, kWhite);
  add_quad(s, {{{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}}}, kWhite);
  add_quad(s, {{{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}}}, kWhite);
  add_quad(s, {{{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}}, kWhite);
  // Tall block.
  add_quad(s, {{{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}}}, kWhite);
  add_quad(s, {{{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}}}, kWhite);
  add_quad(s, {{{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}}}, kWhite);
  add_quad(s, {{{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}}}, kWhite);
  add_quad(s, {{{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}}, kWhite);

  s.view.from = Vec3f(278.0f, 273.0f, -800.0f);
  s.view.at = Vec3f(278.0f, 273.0f, 0.0f);
  s.view.up = Vec3f::UnitY();
  s.view.fov_deg = 39.3077f;  // 2 * atan(12.5 / 35) in degrees
  s.view.width = 512;
  s.view.height = 512;
  s.background = Vec3f::Zero();
  return s;
}

}  // namespace raylab

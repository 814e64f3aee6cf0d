// "Teapot in a stadium" (Haines' term for the case that defeats uniform
// grids): a finely tessellated object, here a (2,3) torus knot tube about
// 1 unit across, on a pedestal in the middle of an open stadium `ratio`
// times larger, made of a few hundred large boxes (tiered stands). Almost
// all triangles sit in a tiny fraction of the bounding box.
#include <cmath>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

namespace {

using namespace library;

// Point on the (p, q) torus knot with unit major radius at parameter t.
Vec3f knot_point(float t, int p, int q) {
  const float r = 1.0f + 0.45f * std::cos(static_cast<float>(q) * t);
  return Vec3f(r * std::cos(static_cast<float>(p) * t), 0.45f * std::sin(static_cast<float>(q) * t),
               r * std::sin(static_cast<float>(p) * t));
}

// Closed tube of `radius` around the knot: `along` rings of `around`
// vertices; the frame is the Frenet frame (well defined: a torus knot has no
// inflection points), from central differences.
TriangleMesh make_knot(int along, int around, float radius) {
  TriangleMesh m;
  m.vertices.reserve(static_cast<size_t>(along) * around);
  const float dt = 2.0f * static_cast<float>(M_PI) / static_cast<float>(along);
  for (int i = 0; i < along; ++i) {
    const float t = dt * static_cast<float>(i);
    const float h = 1e-3f;
    const Vec3f c = knot_point(t, 2, 3), prev = knot_point(t - h, 2, 3), next = knot_point(t + h, 2, 3);
    const Vec3f tangent = (next - prev).normalized();
    const Vec3f accel = next - 2.0f * c + prev;
    const Vec3f binormal = tangent.cross(accel).normalized();
    const Vec3f normal = binormal.cross(tangent);
    for (int j = 0; j < around; ++j) {
      const float a = 2.0f * static_cast<float>(M_PI) * static_cast<float>(j) / static_cast<float>(around);
      m.vertices.push_back(c + radius * (std::cos(a) * normal + std::sin(a) * binormal));
    }
  }
  auto idx = [&](int i, int j) { return static_cast<uint32_t>((i % along) * around + (j % around)); };
  m.triangles.reserve(2 * static_cast<size_t>(along) * around);
  for (int i = 0; i < along; ++i)
    for (int j = 0; j < around; ++j) {
      // Outward: with the right-handed frame (tangent, normal, binormal),
      // tangent x d/da(ring point) points inwards, so the ring direction comes first.
      m.triangles.push_back({idx(i, j), idx(i + 1, j + 1), idx(i + 1, j)});
      m.triangles.push_back({idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)});
    }
  return m;
}

}  // namespace

SceneGenerator stadium_generator() {
  return {"stadium",
          "teapot in a stadium: a fine torus knot (2 along x around triangles) ~1 unit across in an open stadium ratio x larger",
          {{"along", "2048", "knot tube segments along the curve", integer_in(3, kUnbounded)},
           {"around", "48", "knot tube segments around", integer_in(3, kUnbounded)},
           {"ratio", "1000", "stadium diameter / object size", real_in(4, 1e7)},
           {"sectors", "48", "stand sectors around the field", integer_in(3, 4096)},
           {"tiers", "12", "stand tiers", integer_in(1, 1024)}},
          [](const Params& p) {
            const int along = p.integer("along"), around = p.integer("around");
            const int sectors = p.integer("sectors"), tiers = p.integer("tiers");
            const double ratio = p.real("ratio");
            if (static_cast<double>(along) * around > 5e7) throw SpecError("stadium: at most 5e7 knot cells (along x around)");
            Scene s;
            const uint32_t knot_mat = add_material(s, Vec3f(0.80f, 0.30f, 0.15f));
            const uint32_t pedestal = add_material(s, Vec3f(0.60f, 0.60f, 0.60f));
            const uint32_t field = add_material(s, Vec3f(0.20f, 0.45f, 0.15f));
            const uint32_t stands[2] = {add_material(s, Vec3f(0.55f, 0.55f, 0.60f)), add_material(s, Vec3f(0.25f, 0.35f, 0.65f))};
            // The object: knot scaled to ~1 unit across, resting on a pedestal.
            TriangleMesh knot = make_knot(along, around, 0.18f);
            const float knot_scale = 1.0f / 3.0f;  // the knot spans about 2 x 1.63 before scaling
            for (Vec3f& v : knot.vertices) v = knot_scale * v + Vec3f(0.0f, 0.5f, 0.0f);
            add_mesh(s, knot, knot_mat);
            add_box(s, Vec3f(-0.2f, 0.0f, -0.2f), Vec3f(0.2f, 0.27f, 0.2f), pedestal);
            // The stadium: a field of diameter ~ratio/2 and tiered stands up to ratio/2.
            const auto size = static_cast<float>(ratio);
            const float field_radius = 0.3f * size, outer = 0.5f * size, stand_height = 0.12f * size;
            add_ground(s, Vec3f::Zero(), outer, field);
            for (int k = 0; k < sectors; ++k) {
              const float a0 = 2.0f * static_cast<float>(M_PI) * static_cast<float>(k) / static_cast<float>(sectors);
              const float a1 = 2.0f * static_cast<float>(M_PI) * static_cast<float>(k + 1) / static_cast<float>(sectors);
              for (int t = 0; t < tiers; ++t) {
                // Each tier a slab of the sector, one step further out and higher.
                const float r0 = field_radius + (outer - field_radius) * static_cast<float>(t) / static_cast<float>(tiers);
                const float r1 = outer;
                const float y1 = stand_height * static_cast<float>(t + 1) / static_cast<float>(tiers);
                const float y0 = stand_height * static_cast<float>(t) / static_cast<float>(tiers);
                const Vec3f c0(std::cos(a0), 0, std::sin(a0)), c1(std::cos(a1), 0, std::sin(a1));
                const uint32_t mat = stands[(k + t) % 2];
                // Wedge-shaped slab: 8 corners (inner/outer x two angles x bottom/top), 12 triangles.
                const Vec3f corner[8] = {r0 * c0 + Vec3f(0, y0, 0), r0 * c1 + Vec3f(0, y0, 0), r1 * c0 + Vec3f(0, y0, 0),
                                         r1 * c1 + Vec3f(0, y0, 0), r0 * c0 + Vec3f(0, y1, 0), r0 * c1 + Vec3f(0, y1, 0),
                                         r1 * c0 + Vec3f(0, y1, 0), r1 * c1 + Vec3f(0, y1, 0)};
                uint32_t v[8];
                for (int i = 0; i < 8; ++i) v[i] = add_vertex(s, corner[i]);
                // Faces as corner quads, each listed clockwise seen from outside (the
                // sector turns about -y from c0 to c1), hence added in reverse order.
                const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
                for (const auto& q : quads) {
                  add_triangle(s, v[q[0]], v[q[2]], v[q[1]], mat);
                  add_triangle(s, v[q[0]], v[q[3]], v[q[2]], mat);
                }
              }
            }
            return with_view(std::move(s), look_at(Vec3f(0.0f, 0.5f, 0.0f), Vec3f(0.55f, 0.22f, 1.0f), 2.6f, 50.0f));
          }};
}

}  // namespace raylab

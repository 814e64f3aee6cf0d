// The scenes and rays of `raylab stress` (checks/stress.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include <fmt/format.h>

#include "base/spec.h"
#include "tracer/ray_sets.h"
#include "checks/stress.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "base/pcg.h"

namespace raylab {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct ScenarioInfo {
  const char* name;
  const char* description;
};

const std::vector<ScenarioInfo>& scenario_infos() {
  static const std::vector<ScenarioInfo> infos = {
      {"watertight_sphere", "closed UV sphere (48x24): rays aimed at shared edges and vertices from outside, and from inside"},
      {"watertight_box", "closed box, 12x12 quads per face: rays at shared edges and vertices (corners too), and from inside"},
      {"watertight_torus", "closed torus (48x24): rays at shared edges and vertices from outside, and from inside"},
      {"watertight_far", "sphere and torus of radius 4 moved ~3e5 from the origin: edge/vertex rays and rays from inside"},
      {"far_1e3", "Cornell box translated by 1e3 along each axis (primary and random rays)"},
      {"far_1e5", "Cornell box translated by 1e5"},
      {"far_1e7", "Cornell box translated by 1e7 (float spacing 1 there)"},
      {"tiny", "Cornell box scaled by 1e-6"},
      {"huge", "Cornell box scaled by 1e6"},
      {"flat", "every triangle in one axis-aligned plane (zero-thickness bounds), rays also in and along the plane"},
      {"slivers", "long thin needles (1e-4 wide) crossing the whole scene, plus random triangles"},
      {"duplicates", "1,000 copies of one triangle plus a closed sphere"},
      {"degenerate", "zero-area (three equal vertices) and exactly collinear triangles mixed into a sphere and soup: never hit"},
      {"stadium", "a fine torus knot 1000x smaller than the open stadium around it (grids' classic failure)"},
      {"single", "one triangle; random rays and rays at its edges and vertices"},
      {"empty", "no triangles: every ray misses"},
      {"rays", "ray corner cases on the Cornell box: axis-parallel, +-0 components, origins on box faces and split planes, "
               "on surfaces, tmin = tmax, negative tmin, tmax = +inf, denormal components"},
  };
  return infos;
}

// The scene of a scenario that takes one: the given spec loaded, else the Cornell box.
Scene base_scene(const std::string& scene_spec) { return scene_spec.empty() ? make_cornell_box() : load_scene(scene_spec); }

// Scale then translate, vertices and view.
Scene transformed(Scene s, float scale, const Vec3f& offset) {
  for (auto& v : s.mesh.vertices) v = v * scale + offset;
  s.view.from = s.view.from * scale + offset;
  s.view.at = s.view.at * scale + offset;
  return s;
}

void append_rays(std::vector<Ray>& out, const RaySet& set) { out.insert(out.end(), set.rays.begin(), set.rays.end()); }

// Half jittered primary rays of the scene's view, half random segments in its bounds.
std::vector<Ray> standard_rays(const Scene& scene, size_t n, uint64_t seed) {
  std::vector<Ray> rays;
  append_rays(rays, make_jittered_primary_rays(scene, n / 2, seed));
  append_rays(rays, make_random_rays(scene, n - n / 2, seed + 1));
  return rays;
}

size_t scaled(size_t n, double scale) { return std::max<size_t>(16, static_cast<size_t>(std::llround(n * scale))); }

Vec3f random_unit(Pcg32& rng) {
  const float z = 2.0f * rng.uniform() - 1.0f;
  const float phi = 6.2831853f * rng.uniform();
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

// Rays at a closed mesh: aimed from outside at random points of shared edges
// and at vertices (head-on along `outward(p)`, tilted by up to ~30 degrees),
// and from strictly inside (`inside(rng)`) in random directions.
template <typename Outward, typename Inside>
void watertight_rays(const TriangleMesh& m, size_t n_edge, size_t n_vertex, size_t n_inside, float dist, Outward outward,
                     Inside inside, Pcg32& rng, std::vector<Ray>& rays, std::vector<LeakKind>& kinds) {
  auto aim = [&](const Vec3f& target) {
    Vec3f n = outward(target).normalized();
    n = (n + 0.5f * rng.uniform() * random_unit(rng)).normalized();
    const Vec3f org = target + n * (dist * (0.5f + rng.uniform()));
    rays.push_back(Ray(org, target - org));
    kinds.push_back(LeakKind::Outside);
  };
  const size_t nt = m.num_triangles();
  for (size_t i = 0; i < n_edge; ++i) {
    const size_t t = std::min(nt - 1, static_cast<size_t>(rng.uniform() * nt));
    const int e = std::min(2, static_cast<int>(rng.uniform() * 3));
    const Vec3f& a = m.vertex(t, e);
    const Vec3f& b = m.vertex(t, (e + 1) % 3);
    const float s = rng.uniform();
    aim(a + s * (b - a));
  }
  for (size_t i = 0; i < n_vertex; ++i) {
    const size_t v = std::min(m.num_vertices() - 1, static_cast<size_t>(rng.uniform() * m.num_vertices()));
    aim(m.vertices[v]);
  }
  for (size_t i = 0; i < n_inside; ++i) {
    rays.push_back(Ray(inside(rng), random_unit(rng)));
    kinds.push_back(LeakKind::Inside);
  }
}

void sphere_rays(const TriangleMesh& m, const Vec3f& c, float r, size_t n, Pcg32& rng, std::vector<Ray>& rays,
                 std::vector<LeakKind>& kinds) {
  watertight_rays(
      m, n * 4 / 10, n * 3 / 10, n * 3 / 10, 0.5f * r, [c](const Vec3f& p) { return Vec3f(p - c); },
      [c, r](Pcg32& g) { return Vec3f(c + random_unit(g) * (0.6f * r * g.uniform())); }, rng, rays, kinds);
}

void torus_rays(const TriangleMesh& m, const Vec3f& c, float major, float minor, size_t n, Pcg32& rng,
                std::vector<Ray>& rays, std::vector<LeakKind>& kinds) {
  auto core = [c, major](const Vec3f& p) {
    Vec3f q = p - c;
    q.z() = 0.0f;
    return Vec3f(c + q.normalized() * major);
  };
  watertight_rays(
      m, n * 4 / 10, n * 3 / 10, n * 3 / 10, 0.3f * minor, [core](const Vec3f& p) { return Vec3f(p - core(p)); },
      [c, major, minor](Pcg32& g) {
        const float phi = 6.2831853f * g.uniform();
        const Vec3f on_core = c + major * Vec3f(std::cos(phi), std::sin(phi), 0.0f);
        return Vec3f(on_core + random_unit(g) * (0.6f * minor * g.uniform()));
      },
      rng, rays, kinds);
}

StressScenario watertight_scenario(const std::string& name, double scale, uint64_t seed) {
  StressScenario sc;
  Pcg32 rng(mix64(seed * 7919 + std::hash<std::string>{}(name)), 0x57E55);
  const size_t n = scaled(100000, scale);
  TriangleMesh mesh;
  std::vector<Ray> rays;
  std::vector<LeakKind> kinds;
  if (name == "watertight_sphere") {
    mesh = make_uv_sphere(48, 24, Vec3f::Zero(), 1.0f);
    sphere_rays(mesh, Vec3f::Zero(), 1.0f, n, rng, rays, kinds);
  } else if (name == "watertight_box") {
    mesh = make_closed_box(12, Vec3f::Zero(), 1.0f);
    sphere_rays(mesh, Vec3f::Zero(), 1.0f, n, rng, rays, kinds);
  } else if (name == "watertight_torus") {
    mesh = make_torus(48, 24, Vec3f::Zero(), 1.0f, 0.35f);
    torus_rays(mesh, Vec3f::Zero(), 1.0f, 0.35f, n, rng, rays, kinds);
  } else {  // watertight_far
    const Vec3f cs(3e5f, 1e5f, -2e5f), ct(-3e5f, 2e5f, 1e5f);
    mesh = make_uv_sphere(48, 24, cs, 4.0f);
    const TriangleMesh torus = make_torus(48, 24, ct, 4.0f, 1.5f);
    sphere_rays(mesh, cs, 4.0f, n / 2, rng, rays, kinds);
    torus_rays(torus, ct, 4.0f, 1.5f, n - n / 2, rng, rays, kinds);
    mesh.append(torus);
  }
  sc.scene = scene_from_mesh(name, std::move(mesh));
  sc.rays = std::move(rays);
  sc.leak_kind = std::move(kinds);
  return sc;
}

// The ray corner cases on a normal scene (the Cornell box).
std::vector<Ray> corner_case_rays(const Scene& scene, size_t n, uint64_t seed, const std::vector<Ray>& primary_hits_src,
                                  const std::vector<float>& hit_t) {
  Pcg32 rng(mix64(seed * 31 + 5), 0xC0C0);
  const Aabb b = scene.bounds();
  const TriangleMesh& m = scene.mesh;
  std::vector<Ray> rays;
  auto rand_in_box = [&] {
    Vec3f p;
    for (int a = 0; a < 3; ++a) p[a] = b.lo[a] + rng.uniform() * (b.hi[a] - b.lo[a]);
    return p;
  };
  auto rand_sign = [&](float x) { return rng.uniform() < 0.5f ? -x : x; };
  // A coordinate where structures put boundaries: a box face, a grid cell
  // boundary (k/16 of the extent, exact in float for power-of-two counts) or a
  // vertex coordinate (k-d tree split planes are triangle bounds).
  auto special_coord = [&](int a) {
    const float u = rng.uniform();
    if (u < 0.3f) return rng.uniform() < 0.5f ? b.lo[a] : b.hi[a];
    if (u < 0.6f) return b.lo[a] + (b.hi[a] - b.lo[a]) * (std::floor(rng.uniform() * 17.0f) / 16.0f);
    const size_t v = std::min(m.num_vertices() - 1, static_cast<size_t>(rng.uniform() * m.num_vertices()));
    return m.vertices[v][a];
  };
  const size_t per = std::max<size_t>(1, n / 8);
  // 1. Axis-parallel directions with +-0 in the other components.
  for (size_t i = 0; i < per; ++i) {
    Vec3f d(rand_sign(0.0f), rand_sign(0.0f), rand_sign(0.0f));
    d[static_cast<int>(rng.uniform() * 3) % 3] = rand_sign(1.0f);
    rays.push_back(Ray(rand_in_box(), d));
  }
  // 2. One +-0 component (rays parallel to a coordinate plane).
  for (size_t i = 0; i < per; ++i) {
    Vec3f d = random_unit(rng);
    d[static_cast<int>(rng.uniform() * 3) % 3] = rand_sign(0.0f);
    rays.push_back(Ray(rand_in_box(), d));
  }
  // 3. Origins on face/split/cell planes, direction lying in that plane (+-0) or crossing it.
  for (size_t i = 0; i < per; ++i) {
    Vec3f o = rand_in_box();
    const int a = static_cast<int>(rng.uniform() * 3) % 3;
    o[a] = special_coord(a);
    if (rng.uniform() < 0.5f) o[(a + 1) % 3] = special_coord((a + 1) % 3);
    Vec3f d = random_unit(rng);
    if (rng.uniform() < 0.7f) d[a] = rand_sign(0.0f);
    rays.push_back(Ray(o, d, rng.uniform() < 0.5f ? 0.0f : 1e-3f));
  }
  // 4. Origins on a surface (barycentric points of triangles), both hemispheres, tmin 0 or 1e-3.
  for (size_t i = 0; i < per; ++i) {
    const size_t t = std::min(m.num_triangles() - 1, static_cast<size_t>(rng.uniform() * m.num_triangles()));
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    const Vec3f p = m.vertex(t, 0) + u * (m.vertex(t, 1) - m.vertex(t, 0)) + v * (m.vertex(t, 2) - m.vertex(t, 0));
    rays.push_back(Ray(p, random_unit(rng), rng.uniform() < 0.5f ? 0.0f : 1e-3f));
  }
  // 5. tmin == tmax: at a hit distance of the same ray, and at random distances.
  for (size_t i = 0; i < per && !primary_hits_src.empty(); ++i) {
    const size_t k = std::min(primary_hits_src.size() - 1, static_cast<size_t>(rng.uniform() * primary_hits_src.size()));
    Ray r = primary_hits_src[k];
    const float t = std::isfinite(hit_t[k]) ? hit_t[k] : 100.0f * rng.uniform();
    r.tmin = r.tmax = (i % 2) ? t : 1000.0f * rng.uniform();
    rays.push_back(r);
  }
  // 6. Negative tmin (the segment starts behind the origin), finite and infinite tmax.
  for (size_t i = 0; i < per; ++i) {
    Ray r(rand_in_box(), random_unit(rng), -1000.0f * rng.uniform(), rng.uniform() < 0.5f ? kInf : 1000.0f * rng.uniform());
    rays.push_back(r);
  }
  // 7. tmax = +inf from outside the box, and tiny/denormal direction components.
  for (size_t i = 0; i < per; ++i) {
    const Vec3f target = rand_in_box();
    const Vec3f o = target + random_unit(rng) * (b.diagonal().norm() * 2.0f);
    Vec3f d = target - o;
    if (i % 2) d[static_cast<int>(rng.uniform() * 3) % 3] = rand_sign(1e-40f);  // denormal
    rays.push_back(Ray(o, d, 0.0f, kInf));
  }
  // 8. Invalid rays: NaN or infinite origins, zero or NaN directions, NaN
  // tmin/tmax, tmin > tmax. Every accelerator must report a miss (and not crash).
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Ray invalid[] = {
      Ray(Vec3f(nan, 1, 1), Vec3f(0, 0, 1)),          Ray(Vec3f(kInf, 1, 1), Vec3f(0, 0, 1)),
      Ray(Vec3f(1, -kInf, 1), Vec3f(0, 1, 0)),        Ray(Vec3f(278, 273, -800), Vec3f(0, 0, 0)),
      Ray(Vec3f(278, 273, -800), Vec3f(-0.0f, 0, -0.0f)), Ray(Vec3f(278, 273, -800), Vec3f(0, nan, 1)),
      Ray(Vec3f(278, 273, -800), Vec3f(0, 0, kInf)),  Ray(Vec3f(278, 273, -800), Vec3f(0, 0, 1), nan, kInf),
      Ray(Vec3f(278, 273, -800), Vec3f(0, 0, 1), 0.0f, nan), Ray(Vec3f(278, 273, -800), Vec3f(0, 0, 1), 900.0f, 10.0f),
  };
  for (size_t i = 0; i < per / 8; ++i) rays.push_back(invalid[i % std::size(invalid)]);
  // 9. Axis-parallel rays through vertices and along edges of the scene (edges lying in box faces).
  while (rays.size() < n) {
    const size_t t = std::min(m.num_triangles() - 1, static_cast<size_t>(rng.uniform() * m.num_triangles()));
    const Vec3f& p = m.vertex(t, static_cast<int>(rng.uniform() * 3) % 3);
    const int a = static_cast<int>(rng.uniform() * 3) % 3;
    Vec3f d(rand_sign(0.0f), rand_sign(0.0f), rand_sign(0.0f));
    d[a] = rand_sign(1.0f);
    Vec3f o = p;
    o[a] = d[a] > 0 ? b.lo[a] - 10.0f : b.hi[a] + 10.0f;
    rays.push_back(Ray(o, d));
  }
  return rays;
}

}  // namespace

TriangleMesh make_closed_box(int n, const Vec3f& center, float half) {
  TriangleMesh m;
  std::map<std::tuple<int, int, int>, uint32_t> index;
  auto vertex = [&](int i, int j, int k) {
    const auto key = std::make_tuple(i, j, k);
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const Vec3f p = center + half * Vec3f(2.0f * i / n - 1.0f, 2.0f * j / n - 1.0f, 2.0f * k / n - 1.0f);
    const uint32_t id = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(p);
    index.emplace(key, id);
    return id;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      for (int u = 0; u < n; ++u) {
        for (int v = 0; v < n; ++v) {
          auto lattice = [&](int du, int dv) {
            int c[3];
            c[axis] = side * n;
            c[(axis + 1) % 3] = u + du;
            c[(axis + 2) % 3] = v + dv;
            return vertex(c[0], c[1], c[2]);
          };
          uint32_t q[4] = {lattice(0, 0), lattice(1, 0), lattice(1, 1), lattice(0, 1)};
          // (axis+1, axis+2) is right-handed with axis: counter-clockwise seen from +axis.
          if (side == 0) std::swap(q[1], q[3]);
          m.triangles.push_back({q[0], q[1], q[2]});
          m.triangles.push_back({q[0], q[2], q[3]});
        }
      }
    }
  }
  return m;
}

TriangleMesh make_torus(int segments, int rings, const Vec3f& center, float major, float minor) {
  TriangleMesh m;
  for (int i = 0; i < segments; ++i) {
    const float phi = 6.2831853f * i / segments;
    for (int j = 0; j < rings; ++j) {
      const float theta = 6.2831853f * j / rings;
      const float r = major + minor * std::cos(theta);
      m.vertices.push_back(center + Vec3f(r * std::cos(phi), r * std::sin(phi), minor * std::sin(theta)));
    }
  }
  auto id = [&](int i, int j) { return static_cast<uint32_t>((i % segments) * rings + (j % rings)); };
  for (int i = 0; i < segments; ++i) {
    for (int j = 0; j < rings; ++j) {
      // Outward: (phi, theta) increasing gives the normal via d/dphi x d/dtheta.
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

const std::vector<std::string>& stress_scenario_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& i : scenario_infos()) v.push_back(i.name);
    return v;
  }();
  return names;
}

std::string describe_stress_scenarios() {
  std::string s;
  for (const auto& i : scenario_infos()) s += fmt::format("{:<18} {}\n", i.name, i.description);
  return s;
}

std::vector<std::string> expand_stress_scenarios(const std::string& list) {
  std::vector<std::string> out;
  auto add = [&](const std::string& n) {
    if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
  };
  for (const auto& item : split_spec_list(list)) {
    if (item == "all") {
      for (const auto& n : stress_scenario_names()) add(n);
      continue;
    }
    bool found = false;
    for (const auto& n : stress_scenario_names()) {
      if (n == item || n.rfind(item + "_", 0) == 0) {
        add(n);
        found = true;
      }
    }
    if (!found) {
      std::string names;
      for (const auto& n : stress_scenario_names()) names += (names.empty() ? "" : ", ") + n;
      throw SpecError(fmt::format("unknown stress scenario '{}' (available: {}, or a prefix such as 'watertight', or 'all')", item, names));
    }
  }
  if (out.empty()) throw SpecError("no stress scenario given");
  return out;
}

namespace {

// Coplanar triangles, plus rays lying in their plane and along it.
StressScenario flat_scenario(double scale, uint64_t seed) {
  StressScenario sc;
  sc.scene = make_coplanar_scene(2000, 32, 1, seed);
  sc.rays = standard_rays(sc.scene, scaled(49152, scale), seed);
  // Rays lying in the plane y = 0.5 (+-0 y component) and rays along it from outside.
  Pcg32 rng(mix64(seed + 99), 0xF1A7);
  const size_t extra = scaled(16384, scale);
  for (size_t i = 0; i < extra; ++i) {
    const Vec3f o(rng.uniform() * 1.2f - 0.1f, 0.5f, rng.uniform() * 1.2f - 0.1f);
    Vec3f d = random_unit(rng);
    if (i % 2) d.y() = (i % 4 == 1) ? 0.0f : -0.0f;
    sc.rays.push_back(Ray(o + (i % 2 ? Vec3f::Zero() : Vec3f(0, 1, 0)), i % 2 ? d : Vec3f(d.x(), -std::fabs(d.y()) - 0.1f, d.z())));
  }
  return sc;
}

// Good triangles with degenerate ones shuffled among them (must never be hit).
StressScenario degenerate_scenario(double scale, uint64_t seed) {
  StressScenario sc;
  TriangleMesh m = make_uv_sphere(32, 16, Vec3f(0.5f, 0.5f, 0.5f), 0.3f);
  m.append(make_triangle_soup(1000, seed, 1.0f).mesh);
  const size_t good = m.num_triangles();
  Pcg32 rng(mix64(seed + 17), 0xDE6E);
  // Coordinates on a 1/4096 lattice so that a + k * e is exact: collinear triangles are exactly collinear.
  auto lattice = [&] { return std::floor(rng.uniform() * 4096.0f) / 4096.0f; };
  for (size_t i = 0; i < 1500; ++i) {
    const Vec3f a(lattice(), lattice(), lattice());
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    if (i % 3 == 0) {  // three equal vertices
      m.vertices.insert(m.vertices.end(), {a, a, a});
    } else if (i % 3 == 1) {  // two equal vertices, one apart
      m.vertices.insert(m.vertices.end(), {a, a, Vec3f(lattice(), lattice(), lattice())});
    } else {  // three distinct collinear vertices
      const Vec3f e(std::floor(rng.uniform() * 64.0f) / 4096.0f, std::floor(rng.uniform() * 64.0f) / 4096.0f,
                    std::floor(rng.uniform() * 64.0f) / 4096.0f);
      m.vertices.insert(m.vertices.end(), {a, Vec3f(a + 3.0f * e), Vec3f(a + 1.0f * e)});
    }
    m.triangles.push_back({base, base + 1, base + 2});
  }
  // Shuffle the degenerate triangles among the good ones (deterministically).
  std::vector<uint8_t> flag(m.num_triangles(), 0);
  for (size_t i = good; i < flag.size(); ++i) flag[i] = 1;
  for (size_t i = flag.size(); i > 1; --i) {
    const size_t j = std::min(i - 1, static_cast<size_t>(rng.uniform() * i));
    std::swap(m.triangles[i - 1], m.triangles[j]);
    std::swap(flag[i - 1], flag[j]);
  }
  sc.scene = scene_from_mesh("degenerate", std::move(m));
  sc.must_not_hit = std::move(flag);
  sc.rays = standard_rays(sc.scene, scaled(65536, scale), seed);
  return sc;
}

// One triangle, with rays aimed at its edges and vertices.
StressScenario single_scenario(double scale, uint64_t seed) {
  StressScenario sc;
  TriangleMesh m;
  m.vertices = {Vec3f(0.1f, 0.2f, 0.3f), Vec3f(0.9f, 0.3f, 0.4f), Vec3f(0.3f, 0.8f, 0.6f)};
  m.triangles = {{0, 1, 2}};
  sc.scene = scene_from_mesh("single", std::move(m));
  sc.rays = standard_rays(sc.scene, scaled(32768, scale), seed);
  Pcg32 rng(mix64(seed + 5), 0x5151);
  const auto& v = sc.scene.mesh.vertices;
  for (size_t i = 0; i < scaled(8192, scale); ++i) {
    const int e = static_cast<int>(i % 3);
    const Vec3f target = (i % 2) ? v[e] : Vec3f(v[e] + rng.uniform() * (v[(e + 1) % 3] - v[e]));
    const Vec3f o = target + random_unit(rng) * 2.0f;
    sc.rays.push_back(Ray(o, target - o));
  }
  return sc;
}

// The Cornell box (or the given scene) with ray corner cases (tmin == tmax, huge and tiny directions, ...).
StressScenario corner_case_scenario(double scale, uint64_t seed, const std::string& scene_spec) {
  StressScenario sc;
  sc.scene = base_scene(scene_spec);
  const RaySet prim = make_jittered_primary_rays(sc.scene, 4096, seed + 7);
  // Hit distances for the tmin == tmax rays: the plane distance along the
  // view axis is good enough (the oracle judges the answers, not this).
  std::vector<float> t(prim.rays.size(), std::numeric_limits<float>::quiet_NaN());
  const Vec3f mid = sc.scene.bounds().center();
  for (size_t i = 0; i < t.size(); ++i) {
    const Ray& r = prim.rays[i];
    if (!scene_spec.empty()) t[i] = (mid - r.org).norm() / r.dir.norm();  // to the scene's middle
    // Distance to the back wall plane z = 559.2 (published Cornell box).
    else if (r.dir.z() != 0.0f) t[i] = (559.2f - r.org.z()) / r.dir.z();
  }
  sc.rays = corner_case_rays(sc.scene, scaled(65536, scale), seed, prim.rays, t);
  return sc;
}

}  // namespace

bool stress_scenario_takes_scene(const std::string& name) {
  return name == "rays" || name.rfind("far_", 0) == 0 || name == "tiny" || name == "huge";
}

StressScenario make_stress_scenario(const std::string& name, double scale, uint64_t seed, const std::string& scene_spec) {
  const auto& names = stress_scenario_names();
  if (std::find(names.begin(), names.end(), name) == names.end())
    throw SpecError(fmt::format("unknown stress scenario '{}'", name));
  if (!scene_spec.empty() && !stress_scenario_takes_scene(name))
    throw SpecError(fmt::format("stress scenario '{}' makes its own scene; a scene is taken by rays, far_1e3, far_1e5, "
                                "far_1e7, tiny and huge",
                                name));
  StressScenario sc;
  if (name.rfind("watertight_", 0) == 0) {
    sc = watertight_scenario(name, scale, seed);
  } else if (name.rfind("far_", 0) == 0 || name == "tiny" || name == "huge") {
    const float off = name == "far_1e3" ? 1e3f : name == "far_1e5" ? 1e5f : name == "far_1e7" ? 1e7f : 0.0f;
    const float s = name == "tiny" ? 1e-6f : name == "huge" ? 1e6f : 1.0f;
    sc.scene = transformed(base_scene(scene_spec), s, Vec3f::Constant(off));
    sc.rays = standard_rays(sc.scene, scaled(65536, scale), seed);
  } else if (name == "flat") {
    sc = flat_scenario(scale, seed);
  } else if (name == "slivers") {
    sc.scene = make_needles_scene(4000, 2000, seed, 1e-4f);
    sc.scene.name = "slivers";
    sc.rays = standard_rays(sc.scene, scaled(65536, scale), seed);
  } else if (name == "duplicates") {
    TriangleMesh m = make_triangle_copies(1000).mesh;
    m.append(make_uv_sphere(32, 16, Vec3f(0.5f, 0.5f, 0.5f), 0.3f));
    sc.scene = scene_from_mesh("duplicates", std::move(m));
    sc.rays = standard_rays(sc.scene, scaled(65536, scale), seed);
  } else if (name == "degenerate") {
    sc = degenerate_scenario(scale, seed);
  } else if (name == "stadium") {
    sc.scene = load_scene("stadium");
    sc.rays = standard_rays(sc.scene, scaled(32768, scale), seed);
  } else if (name == "single") {
    sc = single_scenario(scale, seed);
  } else if (name == "empty") {
    sc.scene.name = "empty";
    sc.scene.materials = {Material{}};
    Pcg32 rng(mix64(seed + 11), 0xE);
    for (size_t i = 0; i < scaled(16384, scale); ++i)
      sc.rays.push_back(Ray(random_unit(rng) * 10.0f * rng.uniform(), random_unit(rng), 0.0f, (i % 2) ? kInf : 100.0f));
  } else if (name == "rays") {
    sc = corner_case_scenario(scale, seed, scene_spec);
  }
  if (sc.scene.name.empty()) sc.scene.name = name;
  sc.name = name;
  for (const auto& i : scenario_infos())
    if (name == i.name) sc.description = i.description;
  return sc;
}

}  // namespace raylab

#include "tests/accel_test_util.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/test_util.h"

namespace raylab::test {

NamedMesh soup(size_t n, uint64_t seed, float size) {
  return {fmt::format("soup:n={},seed={}", n, seed), triangle_soup_mesh(n, seed, size)};
}

TriangleMesh flat_tiles_mesh(int tiles, size_t extra, uint64_t seed) {
  TriangleMesh m;
  const float z = 0.5f;
  for (int i = 0; i < tiles; ++i)
    for (int j = 0; j < tiles; ++j) {
      const float x0 = static_cast<float>(i) / tiles, x1 = static_cast<float>(i + 1) / tiles;
      const float y0 = static_cast<float>(j) / tiles, y1 = static_cast<float>(j + 1) / tiles;
      append_triangle(m, {x0, y0, z}, {x1, y0, z}, {x1, y1, z});
      append_triangle(m, {x0, y0, z}, {x1, y1, z}, {x0, y1, z});
    }
  Pcg32 rng(seed, 5);
  for (size_t i = 0; i < extra; ++i) {
    const Vec3f c(rng.uniform(), rng.uniform(), z);
    append_triangle(m, c, c + Vec3f(0.05f * rng.uniform(), 0.01f, 0), c + Vec3f(0.01f, 0.05f * rng.uniform(), 0));
  }
  return m;
}

TriangleMesh teapot_in_stadium_mesh() {
  TriangleMesh m;
  const float h = 500.0f;
  const Vec3f c[8] = {{-h, -h, -h}, {h, -h, -h}, {h, h, -h}, {-h, h, -h},
                      {-h, -h, h},  {h, -h, h},  {h, h, h},  {-h, h, h}};
  auto quad = [&](int a, int b, int cc, int d) {
    append_triangle(m, c[a], c[b], c[cc]);
    append_triangle(m, c[a], c[cc], c[d]);
  };
  quad(0, 1, 5, 4);  // y = -h
  quad(3, 7, 6, 2);  // y = +h
  quad(0, 4, 7, 3);  // x = -h
  quad(1, 2, 6, 5);  // x = +h
  quad(4, 5, 6, 7);  // z = +h
  // Floor z = -h as a 20x20 tiling.
  const int n = 20;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const float x0 = -h + 2 * h * i / n, x1 = -h + 2 * h * (i + 1) / n;
      const float y0 = -h + 2 * h * j / n, y1 = -h + 2 * h * (j + 1) / n;
      append_triangle(m, {x0, y0, -h}, {x1, y1, -h}, {x1, y0, -h});
      append_triangle(m, {x0, y0, -h}, {x0, y1, -h}, {x1, y1, -h});
    }
  append_triangle(m, {-300, -300, 0.99f}, {300, -300, 0.99f}, {0, 300, 0.99f});
  m.append(make_uv_sphere(90, 45, kStadiumObject, 0.5f));
  return m;
}

std::vector<Ray> camera_rays(const TriangleMesh& mesh, int width, int height) {
  const Aabb b = mesh.bounds();
  const Vec3f c = b.center(), d = 1.1f * b.diagonal();
  const float size = std::max(d.norm(), 1e-3f);
  const Vec3f eye = c + size * Vec3f(0.15f, 0.1f, -1.5f);
  std::vector<Ray> rays;
  rays.reserve(static_cast<size_t>(width) * height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const Vec3f target(c.x() + d.x() * ((i + 0.5f) / width - 0.5f), c.y() + d.y() * ((j + 0.5f) / height - 0.5f),
                         c.z());
      rays.emplace_back(eye, (target - eye).normalized());
    }
  return rays;
}

std::vector<Ray> mesh_test_rays(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  Pcg32 rng(seed, 11);
  const Aabb b = mesh.bounds();
  const Vec3f d = b.diagonal();
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    const Vec3f org = b.lo - 0.1f * d + Vec3f(rng.uniform(), rng.uniform(), rng.uniform()).cwiseProduct(1.2f * d);
    if (i % 2 == 0 || mesh.num_triangles() == 0) {
      rays.emplace_back(org, random_direction(rng));
    } else {
      const size_t t = rng.next() % mesh.num_triangles();
      float u = rng.uniform(), v = rng.uniform();
      if (u + v > 1) u = 1 - u, v = 1 - v;
      if (i % 6 == 1) v = 0;          // on an edge
      if (i % 12 == 3) u = v = 0;     // on a vertex
      const Vec3f target = (1 - u - v) * mesh.vertex(t, 0) + u * mesh.vertex(t, 1) + v * mesh.vertex(t, 2);
      const Vec3f dir = target - org;
      if (dir.squaredNorm() > 0) rays.emplace_back(org, dir.normalized());
    }
  }
  return rays;
}

CountedHits counted_hits(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  CountedHits out{std::vector<Hit>(rays.size()), {}};
  accel->intersect(rays, out.hits, &out.stats);
  EXPECT_EQ(out.stats.rays, rays.size()) << spec;
  return out;
}

std::vector<Ray> segment_rays(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  const Aabb b = mesh.bounds();
  const Vec3f margin = Vec3f::Constant(0.05f * std::max(b.diagonal().norm(), 1e-30f));
  const Vec3f lo = b.lo - margin, ext = b.diagonal() + 2.0f * margin;
  Pcg32 rng(seed, 17);
  std::vector<Ray> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const Vec3f a = lo + ext.cwiseProduct(Vec3f(rng.uniform(), rng.uniform(), rng.uniform()));
    const Vec3f c = lo + ext.cwiseProduct(Vec3f(rng.uniform(), rng.uniform(), rng.uniform()));
    const float len = (c - a).norm();
    if (len > 0.0f) rays.emplace_back(a, Vec3f((c - a) / len), 0.0f, len);
  }
  return rays;
}

std::vector<Ray> surface_rays(const TriangleMesh& mesh, std::span<const Ray> rays, std::span<const Hit> hits,
                              uint64_t seed) {
  Pcg32 rng(seed, 13);
  const float offset = 1e-5f * mesh.bounds().diagonal().norm();
  std::vector<Ray> out;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].valid()) continue;
    const Hit& h = hits[i];
    const Vec3f p = (1 - h.u - h.v) * mesh.vertex(h.prim, 0) + h.u * mesh.vertex(h.prim, 1) +
                    h.v * mesh.vertex(h.prim, 2);
    Vec3f n = (mesh.vertex(h.prim, 1) - mesh.vertex(h.prim, 0)).cross(mesh.vertex(h.prim, 2) - mesh.vertex(h.prim, 0));
    if (n.squaredNorm() == 0) continue;
    n.normalize();
    if (n.dot(rays[i].dir) > 0) n = -n;  // the side the ray came from
    Vec3f w = random_direction(rng);
    if (w.dot(n) < 0) w = -w;
    out.emplace_back(Vec3f(p + offset * n), w);
  }
  return out;
}

std::vector<std::string> specs_checked_against_brute() {
  std::vector<std::string> specs;
  for (const auto& spec : coverage_specs()) {
    const std::string name = Spec::parse(spec).name;
    if (accelerator_info(name).caps.reference || name == "brute" || spec.find("tri=mt") != std::string::npos) continue;
    specs.push_back(spec);
  }
  return specs;
}

std::string gtest_name(const std::string& spec) {
  std::string s = spec;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

size_t closed_sphere_leaks(const std::string& spec, const Vec3f& center, size_t rays, size_t remove) {
  TriangleMesh sphere = make_uv_sphere(48, 24, center, 1.0f);
  const TriangleMesh full = sphere;
  if (remove < sphere.num_triangles()) sphere.triangles.erase(sphere.triangles.begin() + remove);
  auto accel = make_accelerator(spec);
  accel->build(sphere);
  Pcg32 rng(42, 3);
  std::vector<Ray> batch;
  for (size_t i = 0; i < rays; ++i) {
    batch.push_back(ray_at_shared_edge(full, center, i, rng));  // targets on the complete sphere
    batch.emplace_back(center, random_direction(rng));
  }
  std::vector<Hit> hits(batch.size());
  std::vector<uint8_t> occ(batch.size());
  accel->intersect(batch, hits);
  accel->occluded(batch, occ);
  size_t leaks = 0;
  for (size_t i = 0; i < batch.size(); ++i) leaks += !hits[i].valid() + !occ[i];
  return leaks;
}

std::vector<Ray> rays_at_triangles(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  Pcg32 rng(seed, 7);
  const Aabb box = mesh.bounds();
  const float diag = std::max(box.diagonal().norm(), 1e-3f);
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    if (i % 3 == 2 || mesh.num_triangles() == 0) {
      const Vec3f o = box.center() + 0.75f * diag * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
      rays.emplace_back(o, random_direction(rng));
      continue;
    }
    const size_t tri = rng.next() % mesh.num_triangles();
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    if (rng.next() % 4 == 0) u = static_cast<float>(rng.next() % 2), v = 0.0f;
    const Vec3f p = (1.0f - u - v) * mesh.vertex(tri, 0) + u * mesh.vertex(tri, 1) + v * mesh.vertex(tri, 2);
    const Vec3f o = p + diag * (0.05f + rng.uniform()) * random_direction(rng);
    rays.emplace_back(o, p - o);
  }
  return rays;
}

std::vector<Ray> secondary_rays(const TriangleMesh& mesh, std::span<const Ray> primary, uint64_t seed) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  std::vector<Hit> hits(primary.size());
  brute->intersect(primary, hits);
  Pcg32 rng(seed, 9);
  std::vector<Ray> rays;
  for (size_t i = 0; i < primary.size(); ++i)
    if (hits[i].valid()) rays.emplace_back(primary[i].at(hits[i].t), random_direction(rng), 0.0f);
  return rays;
}

std::string describe_ray(const Ray& r) {
  return fmt::format("org ({:a} {:a} {:a}) dir ({:a} {:a} {:a}) t [{:a} {:a}]", r.org.x(), r.org.y(), r.org.z(),
                     r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax);
}

}  // namespace raylab::test

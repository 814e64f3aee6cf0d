#include "tests/brute_agreement.h"

#include <gtest/gtest.h>

#include <cmath>

#include <fmt/format.h>

#include "accel/registry.h"
#include "tests/accel_test_util.h"

namespace raylab::test {

namespace {

std::string describe(const Hit& h) {
  return h.valid() ? fmt::format("prim {} t {:a} u {:a} v {:a}", h.prim, h.t, h.u, h.v) : std::string("miss");
}

}  // namespace

BruteReference brute_reference(const TriangleMesh& mesh, std::span<const Ray> rays) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  BruteReference ref{std::vector<Hit>(rays.size()), std::vector<uint8_t>(rays.size())};
  brute->intersect(rays, ref.hits);
  brute->occluded(rays, ref.occluded);
  return ref;
}

Disagreement compare_with_brute(const Accelerator& accel, const BruteReference& ref, std::span<const Ray> rays,
                                const BruteComparison& how) {
  const size_t n = rays.size();
  std::vector<Hit> got(n), counted;
  std::vector<uint8_t> occ(n);
  accel.intersect(rays, got);
  accel.occluded(rays, occ);
  if (how.counting_kernel) {
    counted.resize(n);
    TraversalStats stats;
    accel.intersect(rays, counted, &stats);
  }
  Disagreement d;
  int examples = 0;
  const auto example = [&](size_t i, const std::string& what) {
    if (examples++ < 3) d.examples += fmt::format("ray {} {}: {}\n", i, describe_ray(rays[i]), what);
  };
  for (size_t i = 0; i < n; ++i) {
    const Hit& a = got[i];
    const Hit& b = ref.hits[i];
    d.reference_hits += b.valid();
    const float scale = rays[i].org.cwiseAbs().maxCoeff() + std::fabs(b.t);
    const bool tie = !how.same_triangle && (a.t == b.t || std::fabs(a.t - b.t) <= how.tie_rel * scale);
    if (a.valid() != b.valid() || (a.valid() && a.prim != b.prim && !tie)) {
      ++d.closest;
      example(i, describe(a) + ", brute force " + describe(b));
    } else if (a.valid() && a.prim == b.prim && (a.t != b.t || a.u != b.u || a.v != b.v)) {
      ++d.barycentric;
      example(i, describe(a) + ", brute force " + describe(b));
    }
    if ((occ[i] != 0) != (ref.occluded[i] != 0)) {
      ++d.occlusion;
      example(i, fmt::format("occluded {}, brute force {}", occ[i], ref.occluded[i]));
    }
    if (how.counting_kernel) {
      const Hit& c = counted[i];
      if (c.valid() != a.valid() || (a.valid() && (c.t != a.t || c.prim != a.prim))) {
        ++d.counted;
        example(i, "counting kernel " + describe(c) + ", plain kernel " + describe(a));
      }
    }
  }
  return d;
}

size_t count_brute_mismatches(const Accelerator& accel, const TriangleMesh& mesh, std::span<const Ray> rays,
                              std::string* examples) {
  const Disagreement d = compare_with_brute(accel, brute_reference(mesh, rays), rays, {.counting_kernel = true});
  if (examples) *examples = d.examples;
  return d.total();
}

size_t mismatches_vs_brute(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays,
                           std::string* examples) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  return count_brute_mismatches(*accel, mesh, rays, examples);
}

void expect_specs_agree_with_brute(std::span<const char* const> specs, const TriangleMesh& mesh,
                                   std::initializer_list<std::span<const Ray>> ray_sets) {
  for (const char* spec : specs) {
    auto accel = make_accelerator(spec);
    accel->build(mesh);
    for (const auto& rays : ray_sets) {
      std::string examples;
      EXPECT_EQ(count_brute_mismatches(*accel, mesh, rays, &examples), 0u) << spec << ":\n" << examples;
    }
  }
}

}  // namespace raylab::test

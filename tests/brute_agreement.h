#pragma once
// Agreement with the brute-force structure: the one comparison the structure
// tests make. Brute force runs the same watertight kernel on the same
// triangles, so a node or cell a walk misses shows up as a different answer.
// A structure agrees with it on a ray when
// - it hits when brute force hits, at the same distance bit for bit, or,
//   with tie_rel > 0, within tie_rel of the coordinates involved
//   (|origin| + t): two overlapping coplanar triangles give distances that
//   differ by rounding at that scale, and a structure may cull the second
//   one's box by an ulp once the first is found;
// - it names brute force's triangle with the same (t, u, v), or (unless
//   same_triangle) another triangle at such a tie;
// - its any-hit answer is brute force's;
// - (counting_kernel) its counting kernel answers as its plain one does.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <string>
#include <vector>

#include "accel/accelerator.h"
#include "base/ray.h"
#include "base/triangle_mesh.h"

namespace raylab::test {

// Closest hits and any-hit answers of the brute-force structure.
struct BruteReference {
  std::vector<Hit> hits;
  std::vector<uint8_t> occluded;
};
BruteReference brute_reference(const TriangleMesh& mesh, std::span<const Ray> rays);

struct BruteComparison {
  float tie_rel = 0.0f;
  bool same_triangle = false;    // another triangle at a tie is a disagreement too
  bool counting_kernel = false;  // also trace with TraversalStats and compare
};

struct Disagreement {
  size_t closest = 0;      // different hit or miss, or another triangle (not at an accepted tie)
  size_t barycentric = 0;  // the same triangle at a different (t, u, v)
  size_t occlusion = 0;    // any-hit answer differs from brute force's
  size_t counted = 0;      // the counting kernel's closest hit differs from the plain kernel's
  size_t reference_hits = 0;
  std::string examples;  // the first three disagreements, one line each
  size_t total() const { return closest + barycentric + occlusion + counted; }
};

Disagreement compare_with_brute(const Accelerator& accel, const BruteReference& ref, std::span<const Ray> rays,
                                const BruteComparison& how = {});

// Disagreements of a built structure, counting kernel included, with brute
// force built on `mesh`; `examples` receives the first ones.
size_t count_brute_mismatches(const Accelerator& accel, const TriangleMesh& mesh, std::span<const Ray> rays,
                              std::string* examples = nullptr);
// The same for the structure made from `spec` and built on `mesh`.
size_t mismatches_vs_brute(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays,
                           std::string* examples = nullptr);
// Each spec's structure agrees with brute force on every ray set given.
void expect_specs_agree_with_brute(std::span<const char* const> specs, const TriangleMesh& mesh,
                                   std::initializer_list<std::span<const Ray>> ray_sets);

}  // namespace raylab::test

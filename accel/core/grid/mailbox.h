#pragma once
// Per-ray mailbox (Amanatides & Woo 1987; Arnaldi, Priol & Bouatouch 1987):
// a triangle listed in several cells is tested once per ray.
//
// Instead of a stamp per triangle shared by all rays (which needs a ray
// counter per thread and memory proportional to the scene), each ray keeps
// a small direct-mapped table of the ids it has tested, on the stack. It is
// thread-safe by construction and needs no allocation; a collision only
// evicts an older id, which can at worst cause one redundant test (the test
// is exact, so answers never depend on the mailbox).
#include <cstdint>

#include "base/hit.h"

namespace raylab {

class RayMailbox {
 public:
  static constexpr uint32_t kSlots = 64;  // power of two

  RayMailbox() {
    for (auto& s : slots_) s = kInvalidPrim;
  }

  // True when `prim` was already tested by this ray; otherwise records it.
  bool seen(uint32_t prim) {
    uint32_t& s = slots_[prim & (kSlots - 1)];
    if (s == prim) return true;
    s = prim;
    return false;
  }

  // How many of a SIMD block's triangles (lanes past the first repeat
  // prim[0]: padding) were not yet tested by this ray; records them. The
  // same seen() calls, in the same order, as the scalar walk of the block's
  // ids, so both walks skip (and count) the same triangles.
  template <int W>
  uint32_t fresh(const uint32_t (&prim)[W]) {
    uint32_t n = seen(prim[0]) ? 0 : 1;
    for (int i = 1; i < W && prim[i] != prim[0]; ++i) n += seen(prim[i]) ? 0 : 1;
    return n;
  }

 private:
  uint32_t slots_[kSlots];
};

}  // namespace raylab

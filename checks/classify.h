#pragma once
// The one rule that classifies a disagreement between an accelerator and the
// reference (Embree), used by verify, stress and the agreement column of
// bench. Two answers that name different triangles at the same distance
// (within kTieTolerance, relative) are a tie: float arithmetic may pick
// either. Every other disagreement goes to the oracle (oracle.h), whose
// verdicts on both answers decide who was wrong; a disagreement where neither
// is wrong (grazing rays, exact ties) is a tie too.
#include <cstddef>
#include <cstdint>

#include "base/hit.h"
#include "base/ray.h"
#include "base/triangle_mesh.h"
#include "checks/oracle.h"

namespace raylab {

// Before the oracle: the two answers agree (both miss, or the same
// triangle), tie (different triangles at the same distance), or disagree.
enum class Screen : uint8_t { Agree, Tie, Disagree };
Screen screen_closest(const Hit& got, const Hit& ref, double tol = kTieTolerance);

// After the oracle: what a disagreement was, and who was wrong.
enum class DisagreementKind : uint8_t { Tie, HitMiss, Prim };
struct Disagreement {
  DisagreementKind kind = DisagreementKind::Tie;
  bool raylab_wrong = false;
  bool embree_wrong = false;
};

// A closest-hit disagreement (screen_closest said Disagree) judged against `truth`.
Disagreement classify_disagreement(const TriangleMesh& mesh, const Ray& ray, const Hit& got, const Hit& ref,
                                   const OracleHit& truth, double tol = kTieTolerance);
// An occlusion disagreement (got != ref) judged against `truth`.
Disagreement classify_occlusion_disagreement(const Ray& ray, bool got, bool ref, const OracleHit& truth);

// Tallies, as verify and stress report them.
struct DisagreementCounts {
  size_t hit_miss = 0, prim = 0, ties = 0, raylab_wrong = 0, embree_wrong = 0;

  void add(const Disagreement& d) {
    raylab_wrong += d.raylab_wrong;
    embree_wrong += d.embree_wrong;
    if (d.kind == DisagreementKind::Tie) ties++;
    else if (d.kind == DisagreementKind::HitMiss) hit_miss++;
    else prim++;
  }
  DisagreementCounts& operator+=(const DisagreementCounts& o) {
    hit_miss += o.hit_miss;
    prim += o.prim;
    ties += o.ties;
    raylab_wrong += o.raylab_wrong;
    embree_wrong += o.embree_wrong;
    return *this;
  }
};

}  // namespace raylab

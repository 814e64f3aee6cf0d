#include "checks/classify.h"

#include <algorithm>
#include <cmath>

namespace raylab {

Screen screen_closest(const Hit& got, const Hit& ref, double tol) {
  if (got.valid() != ref.valid()) return Screen::Disagree;
  if (!got.valid() || got.prim == ref.prim) return Screen::Agree;
  return same_distance(got.t, ref.t, tol) ? Screen::Tie : Screen::Disagree;
}

namespace {

Disagreement from_verdicts(Verdict got, Verdict ref, DisagreementKind if_wrong) {
  Disagreement d;
  d.raylab_wrong = got == Verdict::Wrong;
  d.embree_wrong = ref == Verdict::Wrong;
  d.kind = (d.raylab_wrong || d.embree_wrong) ? if_wrong : DisagreementKind::Tie;
  return d;
}

}  // namespace

Disagreement classify_disagreement(const TriangleMesh& mesh, const Ray& ray, const Hit& got, const Hit& ref,
                                   const OracleHit& truth, double tol) {
  return from_verdicts(oracle_judge(mesh, ray, got, truth, tol), oracle_judge(mesh, ray, ref, truth, tol),
                       got.valid() != ref.valid() ? DisagreementKind::HitMiss : DisagreementKind::Prim);
}

Disagreement classify_occlusion_disagreement(const Ray& ray, bool got, bool ref, const OracleHit& truth) {
  return from_verdicts(oracle_judge_occluded(ray, got, truth), oracle_judge_occluded(ray, ref, truth),
                       DisagreementKind::HitMiss);
}

}  // namespace raylab

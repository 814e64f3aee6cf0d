#pragma once
// The JSON keys `raylab verify` and `raylab stress` share, so the two reports
// stay comparable: VerifyRecord and StressRecord carry the same counters.
#include <nlohmann/json.hpp>

namespace raylab::cli {

template <class Record>
nlohmann::json check_counts_json(const Record& r) {
  return {{"accel", r.accel},
          {"rays", r.rays},
          {"hit_miss_disagree", r.hit_miss_disagree},
          {"prim_disagree", r.prim_disagree},
          {"ties", r.ties},
          {"raylab_wrong", r.raylab_wrong},
          {"embree_wrong", r.embree_wrong},
          {"occlusion_disagree", r.occlusion_disagree},
          {"max_rel_t_err", r.max_rel_t_err},
          {"build_ms", r.build_ms},
          {"ok", !r.failed()}};
}

}  // namespace raylab::cli

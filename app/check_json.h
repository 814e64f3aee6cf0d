#pragma once
// The JSON keys `raylab verify` and `raylab stress` share, so the two reports
// stay comparable: VerifyRecord and StressRecord carry the same counters.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "bench/report.h"

namespace raylab::cli {

// Writes the records (when a JSON path is given) with "complete" saying
// whether the run finished; after Ctrl-C says how many records were kept and
// returns kExitInterrupted, else 0 (the caller goes on to its verdict).
inline int write_check_report(const char* command, const std::string& json_path, const nlohmann::json& records,
                              bool interrupted) {
  if (!json_path.empty()) {
    nlohmann::json header = report_header(command);
    header["complete"] = !interrupted;
    write_json_report(json_path, header, records);
  }
  if (!interrupted) return 0;
  std::fprintf(stderr, "raylab %s: interrupted: %zu finished records kept%s%s\n", command, records.size(),
               json_path.empty() ? "" : " in ", json_path.c_str());
  return kExitInterrupted;
}

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

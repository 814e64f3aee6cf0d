#pragma once
// The JSON keys `raylab verify` and `raylab stress` share, so the two reports
// stay comparable: VerifyRecord and StressRecord carry the same counters.
#include <cstdio>
#include <exception>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "bench/report.h"
#include "checks/structure_skip.h"
#include "checks/verify.h"

namespace raylab::cli {

// Writes the records (when a JSON path is given) with "complete" saying
// whether the run finished; after Ctrl-C says how many records were kept and
// returns kExitInterrupted, else 0 (the caller goes on to its verdict).
// `extra` (an object) is merged into the header.
inline int write_check_report(const char* command, const std::string& json_path, const nlohmann::json& records,
                              bool interrupted, const nlohmann::json& extra = nlohmann::json::object()) {
  if (!json_path.empty()) {
    nlohmann::json header = report_header(command);
    header["complete"] = !interrupted;
    header.update(extra);
    write_json_report(json_path, header, records);
  }
  if (!interrupted) return 0;
  std::fprintf(stderr, "raylab %s: interrupted: %zu finished records kept%s%s\n", command, records.size(),
               json_path.empty() ? "" : " in ", json_path.c_str());
  return kExitInterrupted;
}

// The report of a check run (verify, stress) as it goes: every finished
// record and every structure left out are written at once (the file says
// "complete": false until finish), so a run stopped by the memory guard, a
// Ctrl-C or a crash keeps what it finished.
class CheckReport {
 public:
  CheckReport(const char* command, std::string json_path) : command_(command), path_(std::move(json_path)) {}

  void add(nlohmann::json record) {
    records_.push_back(std::move(record));
    write(false);
  }
  // A structure left out: one line on stdout with the reason, and in the report's "skipped".
  void skip(const StructureSkip& s) {
    std::printf("%s %s: %s skipped: %s\n", command_, s.scene.c_str(), s.accel.c_str(), s.reason.c_str());
    std::fflush(stdout);
    skipped_.push_back(s.to_json());
    write(false);
  }
  // The run cannot go on (a shared step does not fit): the report so far
  // with the reason, the message on stderr, exit 2.
  int stop(const std::exception& e) {
    stopped_ = e.what();
    write(false);
    std::fprintf(stderr, "raylab %s: %s%s%s\n", command_, e.what(), path_.empty() ? "" : "; report so far in ",
                 path_.c_str());
    return kExitBadInput;
  }
  // The final report; the exit code: 130 interrupted, 1 a check failed, 2 a
  // structure was left out (the run did not check everything asked), else 0.
  int finish(bool interrupted, bool failed) {
    if (const int rc = write_check_report(command_, path_, records_, interrupted, extra())) return rc;
    if (failed) return kExitCheckFailed;
    if (!skipped_.empty()) {
      std::fprintf(stderr, "raylab %s: %zu structure%s left out (see the lines above)\n", command_, skipped_.size(),
                   skipped_.size() == 1 ? "" : "s");
      return kExitBadInput;
    }
    return 0;
  }
  const nlohmann::json& records() const { return records_; }

 private:
  nlohmann::json extra() const {
    nlohmann::json j = {{"skipped", skipped_}};
    if (!stopped_.empty()) j["stopped"] = stopped_;
    return j;
  }
  void write(bool complete) const {
    if (path_.empty()) return;
    nlohmann::json header = report_header(command_);
    header["complete"] = complete;
    header.update(extra());
    write_json_report(path_, header, records_);
  }

  const char* command_;
  std::string path_;
  nlohmann::json records_ = nlohmann::json::array(), skipped_ = nlohmann::json::array();
  std::string stopped_;
};

// The disagreements the oracle judged, as verify lists them per record.
inline nlohmann::json judged_rays_json(const std::vector<JudgedRay>& judged) {
  auto answer = [](const Hit& h) {
    return h.valid() ? nlohmann::json{{"prim", h.prim}, {"t", h.t}} : nlohmann::json(nullptr);
  };
  nlohmann::json out = nlohmann::json::array();
  for (const JudgedRay& j : judged)
    out.push_back({{"ray", j.ray}, {"structure", answer(j.got)}, {"reference", answer(j.ref)},
                   {"oracle", j.oracle_hit ? nlohmann::json{{"prim", j.oracle_prim}, {"t", j.oracle_t}} : nlohmann::json(nullptr)},
                   {"verdict", j.verdict}});
  return out;
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

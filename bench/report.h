#pragma once
// Header fields of every JSON report: machine, build and revision, so a
// figure can be traced to what produced it.
#include <string>

#include <nlohmann/json.hpp>

namespace raylab {

// Version of the JSON reports' layout (docs/json-reports.md). Raised when a
// field changes meaning or type: 2 added trace_s to bench records and null
// for figures that do not apply (Embree's tree shape and traversal counters);
// 3 named every ratio's reference (stress: ratio_to_embree_robust), made
// trace_s per trace of the set (trace_passes per timed repeat, --min-time),
// and split compare's speed change into mrays_change_pct and
// ratio_to_embree_change_pct.
inline constexpr int kReportSchemaVersion = 3;

// {"schema_version", "command", "date", "cpu", ...}.
nlohmann::json report_header(const std::string& command);

std::string cpu_model();
std::string git_revision();

// Writes {header..., "records": records} atomically.
void write_json_report(const std::string& path, nlohmann::json header, const nlohmann::json& records);

}  // namespace raylab

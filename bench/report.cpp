#include "bench/report.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "accel/registry.h"
#include "base/atomic_file.h"
#include "tracer/trace.h"
#include "raylab_build_revision.h"

#ifndef RAYLAB_SOURCE_DIR
#define RAYLAB_SOURCE_DIR "."
#endif
#ifndef RAYLAB_CXX_FLAGS
#define RAYLAB_CXX_FLAGS ""
#endif

namespace raylab {

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto pos = line.find(':');
      if (pos != std::string::npos) return line.substr(pos + 2);
    }
  }
  return "unknown";
}

// The revision of the source this binary was built from (`git describe
// --always --dirty` at build time, cmake/write_build_revision.cmake), not of
// whatever the checkout holds when the binary runs.
std::string git_revision() { return RAYLAB_BUILD_REVISION; }

nlohmann::json report_header(const std::string& command) {
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  nlohmann::json h;
  h["schema_version"] = kReportSchemaVersion;
  h["command"] = command;
  h["date"] = date;
  h["cpu"] = cpu_model();
  h["hardware_threads"] = hardware_threads();
  // Each structure's run-time facts from the registry: "embree" (version
  // and ISA joined) and "embree_version", "embree_isa"; "bvh", "bvh_isa".
  for (const auto& info : accelerator_registry()) {
    if (!info.describe) continue;
    const Description d = info.describe();
    h[info.name] = description_text(d);
    for (const auto& [key, value] : d) h[info.name + "_" + key] = value;
  }
  h["compiler"] = std::string("g++ ") + __VERSION__;
  h["flags"] = RAYLAB_CXX_FLAGS;
  // null when the binary was built outside a git checkout (not a made-up "unknown").
  const std::string rev = git_revision();
  h["revision"] = rev.empty() || rev == "unknown" ? nlohmann::json(nullptr) : nlohmann::json(rev);
  return h;
}

void write_json_report(const std::string& path, nlohmann::json header, const nlohmann::json& records) {
  header["records"] = records;
  write_file_atomically(path, header.dump(2) + "\n");
}

}  // namespace raylab

#include "bench/report.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "accel/embree/embree_accel.h"
#include "accel/util/atomic_file.h"
#include "bench/trace.h"

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

std::string git_revision() {
  std::string cmd = std::string("git -C '") + RAYLAB_SOURCE_DIR + "' describe --always --dirty 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return "unknown";
  char buf[128] = {0};
  std::string out;
  if (fgets(buf, sizeof buf, p)) out = buf;
  pclose(p);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out.empty() ? "unknown" : out;
}

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
  h["embree"] = embree_version_string();
  {
    const std::string e = h["embree"].get<std::string>();
    const auto sp = e.rfind(' ');
    h["embree_isa"] = sp == std::string::npos ? std::string("unknown") : e.substr(sp + 1);
  }
  h["compiler"] = std::string("g++ ") + __VERSION__;
  h["flags"] = RAYLAB_CXX_FLAGS;
  h["revision"] = git_revision();
  return h;
}

void write_json_report(const std::string& path, nlohmann::json header, const nlohmann::json& records) {
  header["records"] = records;
  write_file_atomically(path, header.dump(2) + "\n");
}

}  // namespace raylab

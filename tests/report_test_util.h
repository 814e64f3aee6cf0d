#pragma once
// Reading what the commands write (JSON reports, CSV and text files), for the
// tests of the layers that write them (bench, app).
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace raylab::test {

inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

inline std::vector<std::string> read_lines(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// `raylab ARGS -o <fresh temp dir>/out.json`: the command's result and
// its report (null when none was written).
struct JsonRun {
  CommandResult result;
  nlohmann::json report;
};
inline JsonRun run_raylab_json(const std::string& name, const std::string& args) {
  const auto dir = temp_dir(name);
  const auto path = dir / "out.json";
  JsonRun run{run_raylab(args + " -o " + path.string()), nullptr};
  if (std::filesystem::exists(path)) run.report = read_json(path);
  std::filesystem::remove_all(dir);
  return run;
}

}  // namespace raylab::test

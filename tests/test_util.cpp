#include "tests/test_util.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>

#include <fmt/format.h>

namespace raylab::test {

CommandResult run_shell(const std::string& cmd) {
  CommandResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

CommandResult run_raylab(const std::string& args) { return run_shell(fmt::format("{} {} 2>&1", RAYLAB_BINARY, args)); }

CommandResult run_raylab_in(const std::filesystem::path& dir, const std::string& args) {
  return run_shell("cd '" + dir.string() + "' && " + std::string(RAYLAB_BINARY) + " " + args + " 2>&1");
}

}  // namespace raylab::test

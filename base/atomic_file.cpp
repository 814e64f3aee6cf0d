#include "base/atomic_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <fmt/format.h>

namespace raylab {

namespace fs = std::filesystem;

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  if (path.empty()) throw OutputError("empty output path");
  const fs::path target(path);
  std::error_code ec;
  // Nothing is created where none was asked for: a missing directory is the caller's error.
  if (target.has_parent_path() && !fs::is_directory(target.parent_path(), ec))
    throw OutputError(fmt::format("{}: directory {} does not exist", path, target.parent_path().string()));
  if (fs::is_directory(target, ec)) throw OutputError(fmt::format("{}: is a directory", path));
  const std::string tmp = fmt::format("{}.tmp.{}", path, static_cast<long>(::getpid()));
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw OutputError(fmt::format("{}: cannot open for writing", path));
      write(out);
      out.flush();
      if (!out) throw OutputError(fmt::format("{}: write failed", path));
    }
    fs::rename(tmp, target, ec);
    if (ec) throw OutputError(fmt::format("{}: cannot rename temporary file: {}", path, ec.message()));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
  write_file_atomically(path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace raylab

#include "checks/process_memory.h"

#include <algorithm>
#include <fstream>
#include <limits>
#include <sstream>


namespace raylab {

namespace {

// "VmHWM:    123456 kB" -> 123456 * 1024, from a /proc file with "Key: value kB" lines.
size_t proc_kib_field(const char* path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) == 0 && line.size() > key.size() && line[key.size()] == ':') {
      std::istringstream fields(line.substr(key.size() + 1));
      size_t kib = 0;
      fields >> kib;
      return kib * 1024;
    }
  }
  return 0;
}

// The first line of a small file as a number; nullopt-like max() for "max" or a missing file.
size_t read_number(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return std::numeric_limits<size_t>::max();
  try {
    return static_cast<size_t>(std::stoull(text));
  } catch (...) {
    return std::numeric_limits<size_t>::max();
  }
}

// The cgroup v2 directory of this process ("0::/path" in /proc/self/cgroup).
std::string cgroup_dir() {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("0::", 0) == 0) return "/sys/fs/cgroup" + line.substr(3);
  return {};
}

}  // namespace

size_t resident_bytes() { return proc_kib_field("/proc/self/status", "VmRSS"); }

size_t peak_resident_bytes() { return proc_kib_field("/proc/self/status", "VmHWM"); }

bool reset_peak_resident() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

size_t mem_available_bytes() { return proc_kib_field("/proc/meminfo", "MemAvailable"); }

size_t available_memory_bytes() {
  size_t avail = mem_available_bytes();
  if (avail == 0) avail = std::numeric_limits<size_t>::max();
  // The limit may sit on any ancestor cgroup (Slurm puts it on the job's, the
  // step is below): the tightest room left along the path counts.
  std::string dir = cgroup_dir();
  while (!dir.empty() && dir != "/sys/fs/cgroup" && dir.size() > std::string("/sys/fs/cgroup").size()) {
    const size_t limit = read_number(dir + "/memory.max");
    const size_t used = read_number(dir + "/memory.current");
    if (limit != std::numeric_limits<size_t>::max() && used != std::numeric_limits<size_t>::max())
      avail = std::min(avail, limit > used ? limit - used : size_t{0});
    dir = dir.substr(0, dir.rfind('/'));
  }
  return avail;
}

}  // namespace raylab

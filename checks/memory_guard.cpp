#include "checks/memory_guard.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <tuple>

#include <fmt/format.h>

#include "base/hit.h"
#include "base/ray.h"
#include "checks/memory_estimate.h"
#include "checks/memory_probe.h"
#include "checks/process_memory.h"

namespace raylab {

size_t parse_byte_size(const std::string& text) {
  const auto bad = [&] {
    return std::invalid_argument(fmt::format("{}: expected a size such as 2G, 300M or 65536K, got '{}'",
                                             kMemoryLimitVariable, text));
  };
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw bad();
  }
  std::string suffix = text.substr(used);
  for (char& c : suffix) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (suffix.size() > 1 && suffix.back() == 'b') suffix.pop_back();  // "GB", "GiB"
  if (suffix.size() > 1 && suffix.back() == 'i') suffix.pop_back();
  double scale = 1;
  if (suffix == "k") scale = 1024.0;
  else if (suffix == "m") scale = 1024.0 * 1024;
  else if (suffix == "g") scale = 1024.0 * 1024 * 1024;
  else if (suffix == "t") scale = 1024.0 * 1024 * 1024 * 1024;
  else if (!suffix.empty() && suffix != "b") throw bad();
  if (!std::isfinite(value) || value < 0) throw bad();
  return static_cast<size_t>(value * scale);
}

MemoryRoom memory_room() {
  MemoryRoom room{available_memory_bytes(), "MemAvailable"};
  if (room.bytes < mem_available_bytes()) room.source = "cgroup memory.max";
  if (const char* cap = std::getenv(kMemoryLimitVariable); cap && *cap) {
    const size_t limit = parse_byte_size(cap);
    if (limit < room.bytes) room = {limit, fmt::format("{}={}", kMemoryLimitVariable, cap)};
  }
  return room;
}

MemoryStep structure_step(const std::string& accel_spec, size_t triangles, size_t answers_per_set) {
  MemoryStep s;
  s.what = accel_spec;
  s.bytes_per_unit = build_peak_bytes_per_triangle(accel_spec);
  // The structure's answers to one ray set (closest hits and any-hit flags)
  // live beside it while it is checked.
  s.fixed_bytes = kBuildFixedBytes + answers_per_set * (sizeof(Hit) + 1);
  s.units = triangles;
  s.unit = "triangles";
  s.bytes = s.fixed_bytes + static_cast<size_t>(s.bytes_per_unit * static_cast<double>(triangles));
  s.basis = "its registry figure";
  return s;
}

MemoryStep structure_step(const std::string& accel_spec, const TriangleMesh& mesh, size_t answers_per_set) {
  MemoryStep s = structure_step(accel_spec, mesh.num_triangles(), answers_per_set);
  if (mesh.num_triangles() < kProbeFromTriangles) return s;
  // One probe per spec and mesh (bench asks twice when a structure fits only without Embree).
  static std::map<std::tuple<std::string, const TriangleMesh*, size_t>, BuildProbe> probes;
  const auto key = std::make_tuple(accel_spec, &mesh, mesh.num_triangles());
  auto it = probes.find(key);
  if (it == probes.end()) {
    BuildProbe probe;
    try {
      probe = probe_build_peak(accel_spec, mesh, probe_triangles(mesh.num_triangles()));
    } catch (const std::exception&) {
      // A build that fails on the piece fails on the scene too, where the
      // caller reports it; the registry's figure stands meanwhile.
    }
    it = probes.emplace(key, probe).first;
  }
  const BuildProbe& probe = it->second;
  if (!probe.measured) return s;
  s.bytes_per_unit = kProbeSafety * probe.bytes_per_triangle;
  s.bytes = s.fixed_bytes + static_cast<size_t>(s.bytes_per_unit * static_cast<double>(s.units));
  s.basis = fmt::format("{} x its peak's growth per triangle between pieces of {} and a quarter of that of this scene",
                        kProbeSafety, group_digits(probe.triangles));
  return s;
}

MemoryStep ray_sets_step(size_t rays_per_set, size_t sets) {
  MemoryStep s;
  s.what = fmt::format("{} ray set{} of {} rays and the reference's answers", sets, sets == 1 ? "" : "s", rays_per_set);
  // Per ray: the ray, the reference's closest hit (or any-hit flag), and
  // while the sets are made the primary hits diffuse and shadow rays start from.
  s.bytes_per_unit = static_cast<double>(sets) * (sizeof(Ray) + sizeof(Hit) + 1) + sizeof(Hit);
  s.units = rays_per_set;
  s.unit = "rays per set";
  s.bytes = static_cast<size_t>(s.bytes_per_unit * static_cast<double>(rays_per_set));
  return s;
}

bool MemoryGuard::fits(const MemoryStep& step, size_t released) {
  last_ = step;
  room_ = memory_room();
  released_ = released;
  return headroom_ <= 0 ||
         static_cast<double>(step.bytes) <= headroom_ * (static_cast<double>(room_.bytes) + static_cast<double>(released));
}

std::string MemoryGuard::shortage() const {
  const MemoryStep& s = last_;
  const bool per_triangle = s.unit == "triangles";
  std::string how;
  if (s.bytes_per_unit > 0 && s.units > 0)
    how = fmt::format(" ({} {} x {:.0f} bytes{}{})", group_digits(s.units), s.unit, s.bytes_per_unit,
                      s.basis.empty() ? "" : " by " + s.basis,
                      s.fixed_bytes ? " + " + format_bytes(static_cast<double>(s.fixed_bytes)) : "");
  const double usable = headroom_ * (static_cast<double>(room_.bytes) + static_cast<double>(released_));
  std::string would_fit;
  if (s.bytes_per_unit > 0 && s.units > 0) {
    const double units = std::floor((usable - static_cast<double>(s.fixed_bytes)) / s.bytes_per_unit);
    const size_t n = units >= 1 ? static_cast<size_t>(units) : 0;
    if (n == 0) would_fit = "nothing this large";
    else if (per_triangle) would_fit = fmt::format("a scene of up to {} triangles", group_digits(n));
    else would_fit = fmt::format("--rays {}", n);
  }
  if (!s.instead.empty()) would_fit += (would_fit.empty() ? "" : ", or ") + s.instead;
  return fmt::format("{} needs ~{} by its estimate{}, {} available ({}{}){}", s.what,
                     format_bytes(static_cast<double>(s.bytes)), how,
                     format_bytes(static_cast<double>(room_.bytes)), room_.source,
                     released_ ? ", + " + format_bytes(static_cast<double>(released_)) + " released first" : "",
                     would_fit.empty() ? "" : "; would fit: " + would_fit);
}

void MemoryGuard::require(const MemoryStep& step, size_t released) {
  if (!fits(step, released)) throw MemoryShortage("not enough memory: " + shortage(), step.bytes, room_.bytes);
}

size_t MemoryPlan::peak_bytes() const {
  size_t largest = 0;
  for (const MemoryStep& s : steps) largest = std::max(largest, s.bytes);
  return process_bytes + scene_bytes + rays.bytes + largest;
}

MemoryPlan plan_memory(const std::string& command, const std::vector<std::string>& accel_specs, size_t triangles,
                       size_t scene_bytes, size_t rays_per_set, size_t sets, const TriangleMesh* mesh,
                       const std::string& reference) {
  MemoryPlan plan;
  plan.scene_bytes = scene_bytes;
  const bool checks = command == "verify" || command == "stress" || command == "bench";
  if (checks) plan.rays = ray_sets_step(rays_per_set, sets);
  auto step = [&](const std::string& spec, size_t answers) {
    return mesh ? structure_step(spec, *mesh, answers) : structure_step(spec, triangles, answers);
  };
  if (checks) {
    const std::string ref = !reference.empty() ? reference : command == "bench" ? "embree" : "embree:robust=1";
    MemoryStep r = step(ref, 0);
    r.what = "the reference " + ref;
    plan.steps.push_back(r);
  }
  for (const auto& spec : accel_specs) plan.steps.push_back(step(spec, checks ? rays_per_set : 0));
  return plan;
}

void require_structure_fits(const std::string& accel_spec, const TriangleMesh& mesh) {
  MemoryGuard().require(structure_step(accel_spec, mesh));
}

std::string group_digits(size_t n) {
  std::string d = std::to_string(n), out;
  for (size_t i = 0; i < d.size(); ++i) {
    if (i > 0 && (d.size() - i) % 3 == 0) out += ',';
    out += d[i];
  }
  return out;
}

std::string format_bytes(double bytes) {
  constexpr double kMiB = 1024.0 * 1024.0, kGiB = kMiB * 1024.0;
  return bytes >= kGiB ? fmt::format("{:.1f} GiB", bytes / kGiB) : fmt::format("{:.1f} MiB", bytes / kMiB);
}

}  // namespace raylab

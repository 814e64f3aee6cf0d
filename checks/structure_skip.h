#pragma once
// A structure left out of a run, with the reason: its estimated peak memory
// does not fit ("needs ~31.2 GiB by its estimate, 20.1 GiB available ..."),
// or its build failed on this scene. verify and bench list them in their
// reports ("skipped") instead of dying half-way.
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace raylab {

struct StructureSkip {
  std::string scene, accel, reason;
  size_t triangles = 0;
  size_t estimated_bytes = 0, available_bytes = 0;

  nlohmann::json to_json() const {
    return {{"scene", scene},   {"triangles", triangles},             {"accel", accel},
            {"reason", reason}, {"estimated_bytes", estimated_bytes}, {"available_bytes", available_bytes}};
  }
};

}  // namespace raylab

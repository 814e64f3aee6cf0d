#include "app/camera_options.h"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include <fmt/format.h>

#include "base/spec.h"

namespace raylab::cli {

namespace {

bool parse_float(const std::string& s, float& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
}

}  // namespace

void apply_camera_option(const std::string& text, View& view) {
  // Commas separate both keys and coordinates: a token with '=' starts a key,
  // the tokens after it (up to the next key) are its values.
  std::string key;
  std::vector<float> values;
  View v = view;
  auto finish = [&]() {
    if (key.empty()) return;
    auto vec3 = [&]() {
      if (values.size() != 3)
        throw std::invalid_argument(fmt::format("--camera {}: '{}' takes three numbers x,y,z, got {}", text, key, values.size()));
      return Vec3f(values[0], values[1], values[2]);
    };
    if (key == "from") v.from = vec3();
    else if (key == "at") v.at = vec3();
    else if (key == "up") v.up = vec3();
    else if (key == "fov") {
      if (values.size() != 1) throw std::invalid_argument(fmt::format("--camera {}: 'fov' takes one angle in degrees", text));
      v.fov_deg = values[0];
    } else {
      throw std::invalid_argument(fmt::format("--camera {}: unknown key '{}' (keys: from, at, up, fov)", text, key));
    }
  };
  for (const auto& token : split_at(text, ',')) {
    const auto eq = token.find('=');
    std::string number = token;
    if (eq != std::string::npos) {
      finish();
      key = token.substr(0, eq);
      values.clear();
      number = token.substr(eq + 1);
    } else if (key.empty()) {
      throw std::invalid_argument(fmt::format("--camera {}: expected KEY=values (from=x,y,z,at=x,y,z,up=x,y,z,fov=deg)", text));
    }
    float f = 0;
    if (!parse_float(number, f)) throw std::invalid_argument(fmt::format("--camera {}: '{}' is not a number", text, number));
    values.push_back(f);
  }
  finish();
  const std::string problem = view_problem(v);
  if (!problem.empty()) throw std::invalid_argument(fmt::format("--camera {}: {}", text, problem));
  view = v;
}

void apply_up_axis(const std::string& axis, Scene& scene) {
  const bool negative = !axis.empty() && axis[0] == '-';
  const std::string name = negative ? axis.substr(1) : (!axis.empty() && axis[0] == '+' ? axis.substr(1) : axis);
  if (name.size() != 1 || (name[0] != 'x' && name[0] != 'y' && name[0] != 'z'))
    throw std::invalid_argument(fmt::format("--up {}: expected x, y, z, -x, -y or -z", axis));
  // A proper rotation taking the given axis to +y.
  Eigen::Matrix3f r = Eigen::Matrix3f::Identity();
  if (name == "z") r << 1, 0, 0, 0, 0, 1, 0, -1, 0;       // z -> y, y -> -z
  else if (name == "x") r << 0, -1, 0, 1, 0, 0, 0, 0, 1;  // x -> y, y -> -x
  if (negative) r = Eigen::Matrix3f(Eigen::AngleAxisf(3.14159265358979f, Vec3f::UnitX())) * r;  // flip y
  if (r.isIdentity()) return;
  for (auto& p : scene.mesh.vertices) p = r * p;
  const View old = scene.view;
  scene.view = frame_bounds(scene.bounds(), old.width, old.height, old.fov_deg);
}

Vec3f parse_background(const std::string& text) {
  const auto parts = split_at(text, ',');
  float c[3];
  if (parts.size() != 1 && parts.size() != 3)
    throw std::invalid_argument(fmt::format("--background {}: expected one value (grey) or r,g,b", text));
  for (size_t i = 0; i < parts.size(); ++i)
    if (!parse_float(parts[i], c[i]) || c[i] < 0)
      throw std::invalid_argument(fmt::format("--background {}: '{}' is not a non-negative number", text, parts[i]));
  return parts.size() == 1 ? Vec3f::Constant(c[0]) : Vec3f(c[0], c[1], c[2]);
}

}  // namespace raylab::cli

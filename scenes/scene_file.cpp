#include "scenes/scene_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "scenes/mesh_import.h"
#include "scenes/scene_registry.h"

namespace raylab {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A JSON pointer (RFC 6901) to the value being read, for error messages.
std::string child(const std::string& ptr, const std::string& key) {
  std::string k;
  for (char c : key) k += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
  return ptr + "/" + k;
}
std::string child(const std::string& ptr, size_t index) { return ptr + "/" + std::to_string(index); }

std::string type_name(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::string: return "a string";
    case json::value_t::array: return fmt::format("an array of {}", j.size());
    case json::value_t::object: return "an object";
    default: return "a number";
  }
}

// Reads one scene file; every error names the file and the JSON pointer.
class SceneFileReader {
 public:
  explicit SceneFileReader(const std::string& path) : path_(path) {}

  Scene read() {
    const json doc = parse();
    if (!doc.is_object()) fail("", "expected an object with \"meshes\" (a scene file)");
    if (doc.contains("from") && !doc.contains("meshes"))
      fail("", "this is a view file (from/at/up) for the mesh beside it, not a scene file: give the mesh file instead");
    allow_keys(doc, "", {"camera", "background", "materials", "meshes"});
    if (doc.contains("materials")) read_materials(doc["materials"], "/materials");
    if (!doc.contains("meshes")) fail("", "missing \"meshes\" (an array of meshes)");
    const json& meshes = doc["meshes"];
    if (!meshes.is_array() || meshes.empty()) fail("/meshes", "expected a non-empty array of meshes, got " + type_name(meshes));

    Scene scene;
    scene.name = path_;
    for (size_t i = 0; i < meshes.size(); ++i) add_mesh(scene, meshes[i], child("/meshes", i));
    try {
      scene.validate();
    } catch (const MeshError& e) {
      fail("/meshes", e.what());
    }
    if (doc.contains("camera")) {
      scene.view = read_camera(doc["camera"], "/camera");
    } else {
      scene.view = frame_bounds(scene.bounds());
    }
    if (doc.contains("background")) {
      scene.background = color(doc["background"], "/background", false);
    } else {
      scene.background = scene.has_emitters() ? Vec3f::Zero() : Vec3f::Constant(1.0f);
    }
    return scene;
  }

 private:
  [[noreturn]] void fail(const std::string& ptr, const std::string& what) const {
    throw SceneLoadError(ptr.empty() ? fmt::format("{}: {}", path_, what) : fmt::format("{}: {}: {}", path_, ptr, what));
  }

  json parse() const {
    std::ifstream in(path_);
    if (!in) fail("", "cannot open for reading");
    try {
      return json::parse(in);
    } catch (const json::parse_error& e) {
      std::string what = e.what();
      const auto bracket = what.find("] ");
      if (bracket != std::string::npos) what = what.substr(bracket + 2);
      if (what.size() > 200) what = what.substr(0, 200) + "...";  // "last read" may quote a long string
      fail("", "malformed JSON (" + what + ")");
    }
  }

  void allow_keys(const json& obj, const std::string& ptr, std::initializer_list<const char*> allowed) const {
    for (const auto& [key, value] : obj.items()) {
      bool ok = key == "comment";
      for (const char* a : allowed) ok |= key == a;
      if (ok) {
        if (key == "comment" && !value.is_string()) fail(child(ptr, key), "expected a string, got " + type_name(value));
        continue;
      }
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      fail(child(ptr, key), fmt::format("unknown key (allowed here: {}, comment)", list));
    }
  }

  float number(const json& j, const std::string& ptr) const {
    if (!j.is_number()) fail(ptr, "expected a number, got " + type_name(j));
    const double v = j.get<double>();
    if (!std::isfinite(static_cast<float>(v))) fail(ptr, "the number is not a finite float");
    return static_cast<float>(v);
  }

  int image_size(const json& j, const std::string& ptr) const {
    if (!j.is_number_integer() || j.get<int64_t>() < 1 || j.get<int64_t>() > 65536)
      fail(ptr, "expected an integer from 1 to 65536");
    return j.get<int>();
  }

  Vec3f vec3(const json& j, const std::string& ptr) const {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
      fail(ptr, "expected an array of 3 numbers, got " + type_name(j));
    return Vec3f(number(j[0], child(ptr, 0)), number(j[1], child(ptr, 1)), number(j[2], child(ptr, 2)));
  }

  // A number (grey) or [r, g, b]; non-negative, below 1 if `albedo`.
  Vec3f color(const json& j, const std::string& ptr, bool albedo) const {
    Vec3f c;
    if (j.is_number()) {
      c = Vec3f::Constant(number(j, ptr));
    } else if (j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() && j[2].is_number()) {
      c = vec3(j, ptr);
    } else {
      fail(ptr, "expected a number or an array of 3 numbers, got " + type_name(j));
    }
    if (c.minCoeff() < 0.0f) fail(ptr, "values must be >= 0");
    if (albedo && c.maxCoeff() >= 1.0f) fail(ptr, "a diffuse albedo must be below 1 (a surface reflects at most what it receives)");
    return c;
  }

  Material material(const json& j, const std::string& ptr) const {
    if (!j.is_object()) fail(ptr, "expected a material object ({\"diffuse\": ..., \"emission\": ...}), got " + type_name(j));
    allow_keys(j, ptr, {"diffuse", "emission"});
    Material m;
    if (j.contains("diffuse")) m.albedo = color(j["diffuse"], child(ptr, "diffuse"), true);
    if (j.contains("emission")) m.emission = color(j["emission"], child(ptr, "emission"), false);
    return m;
  }

  void read_materials(const json& j, const std::string& ptr) {
    if (!j.is_object()) fail(ptr, "expected an object of named materials, got " + type_name(j));
    for (const auto& [name, value] : j.items()) {
      if (name == "comment") continue;
      named_[name] = material(value, child(ptr, name));
    }
  }

  View read_camera(const json& j, const std::string& ptr) const {
    if (!j.is_object()) fail(ptr, "expected a camera object, got " + type_name(j));
    allow_keys(j, ptr, {"from", "at", "up", "fov_deg", "width", "height"});
    View v;
    v.up = Vec3f::UnitY();
    v.fov_deg = 45.0f;
    v.width = v.height = 512;
    if (!j.contains("from")) fail(ptr, "missing \"from\" (the eye point)");
    if (!j.contains("at")) fail(ptr, "missing \"at\" (the look-at point)");
    v.from = vec3(j["from"], child(ptr, "from"));
    v.at = vec3(j["at"], child(ptr, "at"));
    if (j.contains("up")) v.up = vec3(j["up"], child(ptr, "up"));
    if (j.contains("fov_deg")) v.fov_deg = number(j["fov_deg"], child(ptr, "fov_deg"));
    if (j.contains("width")) v.width = image_size(j["width"], child(ptr, "width"));
    if (j.contains("height")) v.height = image_size(j["height"], child(ptr, "height"));
    if (const std::string why = view_problem(v); !why.empty()) fail(ptr, why);
    return v;
  }

  // The affine map of a "transform" object: translate * rotate * scale.
  Eigen::Affine3f transform(const json& j, const std::string& ptr) const {
    if (!j.is_object()) fail(ptr, "expected a transform object ({\"translate\", \"rotate\", \"scale\"}), got " + type_name(j));
    allow_keys(j, ptr, {"translate", "rotate", "scale"});
    Vec3f scale = Vec3f::Ones(), translate = Vec3f::Zero();
    Eigen::Matrix3f rotate = Eigen::Matrix3f::Identity();
    if (j.contains("scale")) {
      const std::string p = child(ptr, "scale");
      const json& s = j["scale"];
      if (s.is_number()) scale = Vec3f::Constant(number(s, p));
      else if (s.is_array() && s.size() == 3 && s[0].is_number() && s[1].is_number() && s[2].is_number()) scale = vec3(s, p);
      else fail(p, "expected a number or an array of 3 numbers, got " + type_name(s));
      if (scale.cwiseAbs().minCoeff() == 0.0f) fail(p, "scale factors must be non-zero");
    }
    if (j.contains("rotate")) {
      const std::string p = child(ptr, "rotate");
      const json& r = j["rotate"];
      constexpr float kDeg = static_cast<float>(M_PI / 180.0);
      if (r.is_object()) {
        allow_keys(r, p, {"axis", "degrees"});
        if (!r.contains("axis")) fail(p, "missing \"axis\" (an array of 3 numbers)");
        if (!r.contains("degrees")) fail(p, "missing \"degrees\" (the rotation angle)");
        const Vec3f axis = vec3(r["axis"], child(p, "axis"));
        if (!(axis.norm() > 0.0f)) fail(child(p, "axis"), "the axis must not be the zero vector");
        rotate = Eigen::AngleAxisf(kDeg * number(r["degrees"], child(p, "degrees")), axis.normalized()).toRotationMatrix();
      } else if (r.is_array() && r.size() == 3 && r[0].is_number() && r[1].is_number() && r[2].is_number()) {
        const Vec3f e = kDeg * vec3(r, p);
        rotate = (Eigen::AngleAxisf(e.z(), Vec3f::UnitZ()) * Eigen::AngleAxisf(e.y(), Vec3f::UnitY()) *
                  Eigen::AngleAxisf(e.x(), Vec3f::UnitX()))
                     .toRotationMatrix();
      } else {
        fail(p, "expected {\"axis\": [x, y, z], \"degrees\": a} or Euler angles [x, y, z] in degrees, got " + type_name(r));
      }
    }
    if (j.contains("translate")) translate = vec3(j["translate"], child(ptr, "translate"));
    Eigen::Affine3f xf = Eigen::Affine3f::Identity();
    xf.linear() = rotate * scale.asDiagonal();
    xf.translation() = translate;
    return xf;
  }

  std::string param_text(const json& v, const std::string& ptr) const {
    if (v.is_string()) return v.get<std::string>();
    if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
    if (v.is_number_integer()) return std::to_string(v.get<int64_t>());
    if (v.is_number()) return v.dump();
    fail(ptr, "expected a number, string or boolean, got " + type_name(v));
  }

  Scene load_part(const json& m, const std::string& ptr) const {
    const bool has_file = m.contains("file"), has_generator = m.contains("generator");
    if (has_file == has_generator) fail(ptr, has_file ? "give either \"file\" or \"generator\", not both" : "missing \"file\" or \"generator\"");
    if (m.contains("params") && !has_generator) fail(child(ptr, "params"), "\"params\" belongs to a \"generator\"");
    if (has_file) {
      const std::string p = child(ptr, "file");
      if (!m["file"].is_string() || m["file"].get<std::string>().empty()) fail(p, "expected a file path (a string)");
      const fs::path rel = m["file"].get<std::string>();
      const fs::path file = rel.is_absolute() ? rel : fs::path(path_).parent_path() / rel;
      std::string ext = file.extension().string();
      for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (ext == ".json") fail(p, "scene files cannot include other scene files");
      try {
        return load_mesh_file(file.string());
      } catch (const SceneLoadError& e) {
        fail(p, e.what());
      }
    }
    const std::string p = child(ptr, "generator");
    if (!m["generator"].is_string()) fail(p, "expected a procedural scene spec (a string such as \"sphere:segments=32\")");
    try {
      Spec spec = Spec::parse(m["generator"].get<std::string>());
      if (m.contains("params")) {
        const std::string pp = child(ptr, "params");
        if (!m["params"].is_object()) fail(pp, "expected an object of parameters, got " + type_name(m["params"]));
        for (const auto& [key, value] : m["params"].items()) {
          if (key == "comment") continue;
          if (spec.params.count(key)) fail(child(pp, key), "given both here and in the generator spec");
          spec.params[key] = param_text(value, child(pp, key));
        }
      }
      return make_procedural_scene(spec);
    } catch (const SpecError& e) {
      fail(m.contains("params") ? child(ptr, "params") : p, e.what());
    } catch (const SceneLoadError&) {
      throw;
    } catch (const std::exception& e) {
      fail(p, e.what());
    }
  }

  void add_mesh(Scene& scene, const json& m, const std::string& ptr) const {
    if (!m.is_object()) fail(ptr, "expected a mesh object ({\"file\": ...} or {\"generator\": ...}), got " + type_name(m));
    allow_keys(m, ptr, {"file", "generator", "params", "material", "transform"});
    Scene part = load_part(m, ptr);
    if (m.contains("material")) {
      const std::string p = child(ptr, "material");
      const json& mat = m["material"];
      Material chosen;
      if (mat.is_string()) {
        const auto it = named_.find(mat.get<std::string>());
        if (it == named_.end()) {
          std::string names;
          for (const auto& [n, unused] : named_) names += (names.empty() ? "" : ", ") + n;
          fail(p, fmt::format("no material named '{}' in \"materials\" ({})", mat.get<std::string>(),
                              names.empty() ? "none defined" : "defined: " + names));
        }
        chosen = it->second;
      } else {
        chosen = material(mat, p);
      }
      part.materials = {chosen};
      part.material_ids.assign(part.num_triangles(), 0);
    }
    if (m.contains("transform")) {
      const Eigen::Affine3f xf = transform(m["transform"], child(ptr, "transform"));
      for (Vec3f& v : part.mesh.vertices) v = xf * v;
      if (xf.linear().determinant() < 0.0f)
        for (auto& t : part.mesh.triangles) std::swap(t[1], t[2]);  // keep front faces in front
    }
    if (scene.mesh.vertices.empty() && scene.mesh.triangles.empty() && scene.materials.empty()) {
      // The first mesh moves in whole: a one-mesh scene file costs no copy.
      scene.mesh = std::move(part.mesh);
      scene.materials = std::move(part.materials);
      scene.material_ids = std::move(part.material_ids);
      return;
    }
    const auto vertex_base = static_cast<uint64_t>(scene.mesh.num_vertices());
    const auto material_base = static_cast<uint32_t>(scene.materials.size());
    if (vertex_base + part.mesh.num_vertices() >= 0xFFFFFFFFull) fail(ptr, "the scene has more vertices than 32-bit indices can address");
    // Not TriangleMesh::append, which reserves the exact size on every call.
    scene.mesh.vertices.insert(scene.mesh.vertices.end(), part.mesh.vertices.begin(), part.mesh.vertices.end());
    for (const auto& t : part.mesh.triangles)
      scene.mesh.triangles.push_back({static_cast<uint32_t>(vertex_base + t[0]), static_cast<uint32_t>(vertex_base + t[1]),
                                      static_cast<uint32_t>(vertex_base + t[2])});
    scene.materials.insert(scene.materials.end(), part.materials.begin(), part.materials.end());
    for (uint32_t id : part.material_ids) scene.material_ids.push_back(material_base + id);
  }

  std::string path_;
  std::map<std::string, Material> named_;
};

}  // namespace

Scene load_scene_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw SceneLoadError(fmt::format("{}: no such file", path));
  if (fs::is_directory(path, ec)) throw SceneLoadError(fmt::format("{}: is a directory, not a scene file", path));
  return SceneFileReader(path).read();
}

}  // namespace raylab

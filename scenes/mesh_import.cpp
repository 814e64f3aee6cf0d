#include "scenes/mesh_import.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace raylab {

namespace {

namespace fs = std::filesystem;

struct Merger {
  const aiScene* scene;
  const std::string& path;
  Scene& out;
  std::vector<int> material_map;  // aiMaterial index -> our material index (-1 = not yet added)

  uint32_t material_for(unsigned ai_index) {
    if (ai_index >= material_map.size()) return 0;
    if (material_map[ai_index] >= 0) return static_cast<uint32_t>(material_map[ai_index]);
    Material m;
    const aiMaterial* am = scene->mMaterials[ai_index];
    aiColor3D c;
    if (am->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS && std::isfinite(c.r) && std::isfinite(c.g) &&
        std::isfinite(c.b) && (c.r > 0 || c.g > 0 || c.b > 0))
      m.albedo = Vec3f(c.r, c.g, c.b).cwiseMax(0.0f).cwiseMin(0.99f);
    aiColor3D e;
    if (am->Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS && std::isfinite(e.r) && std::isfinite(e.g) &&
        std::isfinite(e.b))
      m.emission = Vec3f(e.r, e.g, e.b).cwiseMax(0.0f);
    out.materials.push_back(m);
    material_map[ai_index] = static_cast<int>(out.materials.size() - 1);
    return static_cast<uint32_t>(material_map[ai_index]);
  }

  void add_mesh(const aiMesh* mesh, const aiMatrix4x4& xf) {
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) return;
    const auto base = out.mesh.vertices.size();
    if (base + mesh->mNumVertices >= 0xFFFFFFFFull)
      throw SceneLoadError(fmt::format("{}: too many vertices", path));
    out.mesh.vertices.reserve(base + mesh->mNumVertices);
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D p = xf * mesh->mVertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
        throw SceneLoadError(fmt::format("{}: vertex {} of mesh '{}' has a non-finite coordinate", path, i,
                                         mesh->mName.C_Str()));
      out.mesh.vertices.emplace_back(p.x, p.y, p.z);
    }
    const uint32_t material = material_for(mesh->mMaterialIndex);
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      std::array<uint32_t, 3> tri;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw SceneLoadError(fmt::format("{}: face {} of mesh '{}' refers to vertex {}, but the mesh has {}", path,
                                           f, mesh->mName.C_Str(), face.mIndices[k], mesh->mNumVertices));
        tri[k] = static_cast<uint32_t>(base + face.mIndices[k]);
      }
      out.mesh.triangles.push_back(tri);
      out.material_ids.push_back(material);
    }
  }

  void walk(const aiNode* node, const aiMatrix4x4& parent, int depth) {
    if (depth > 256) throw SceneLoadError(fmt::format("{}: node hierarchy deeper than 256 levels", path));
    const aiMatrix4x4 xf = parent * node->mTransformation;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene->mNumMeshes)
        throw SceneLoadError(fmt::format("{}: node refers to mesh {} of {}", path, node->mMeshes[i], scene->mNumMeshes));
      add_mesh(scene->mMeshes[node->mMeshes[i]], xf);
    }
    for (unsigned i = 0; i < node->mNumChildren; ++i) walk(node->mChildren[i], xf, depth + 1);
  }
};

Vec3f json_vec3(const nlohmann::json& j, const char* key, const std::string& file) {
  const auto& a = j.at(key);
  if (!a.is_array() || a.size() != 3) throw SceneLoadError(fmt::format("{}: '{}' must be an array of 3 numbers", file, key));
  return Vec3f(a[0].get<float>(), a[1].get<float>(), a[2].get<float>());
}

void apply_view_file(const fs::path& file, View& v) {
  std::ifstream in(file);
  if (!in) return;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    v.from = json_vec3(j, "from", file.string());
    v.at = json_vec3(j, "at", file.string());
    v.up = json_vec3(j, "up", file.string());
    v.fov_deg = j.at("fov_deg").get<float>();
    v.width = j.value("width", v.width);
    v.height = j.value("height", v.height);
  } catch (const nlohmann::json::exception& e) {
    throw SceneLoadError(fmt::format("{}: invalid view file: {}", file.string(), e.what()));
  }
}

}  // namespace

Scene load_mesh_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw SceneLoadError(fmt::format("{}: no such file", path));
  if (fs::is_directory(path, ec)) throw SceneLoadError(fmt::format("{}: is a directory, not a mesh file", path));
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw SceneLoadError(fmt::format("{}: cannot open for reading", path));
  }

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* ai = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_SortByPType);
  if (!ai) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown format or unreadable";
    throw SceneLoadError(fmt::format("{}: cannot load mesh: {}", path, why));
  }
  if (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE || !ai->mRootNode)
    throw SceneLoadError(fmt::format("{}: file is incomplete (no mesh data)", path));

  Scene s;
  s.name = path;
  Merger m{ai, path, s, std::vector<int>(ai->mNumMaterials, -1)};
  if (ai->mNumMaterials == 0) s.materials.push_back(Material{});
  m.walk(ai->mRootNode, aiMatrix4x4(), 0);
  if (s.mesh.num_triangles() == 0) throw SceneLoadError(fmt::format("{}: contains no triangles", path));
  if (s.materials.empty()) s.materials.push_back(Material{});
  try {
    s.validate();
  } catch (const MeshError& e) {
    throw SceneLoadError(fmt::format("{}: {}", path, e.what()));
  }

  s.view = frame_bounds(s.bounds());
  const fs::path view_file = fs::path(path).replace_extension(".json");
  if (fs::exists(view_file, ec)) apply_view_file(view_file, s.view);
  s.background = s.has_emitters() ? Vec3f::Constant(0.05f) : Vec3f::Constant(1.0f);
  return s;
}

}  // namespace raylab

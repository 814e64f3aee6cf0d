#include "scenes/mesh_import.h"
#include "scenes/mesh_precheck.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>
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

// Imports with Assimp in this process. Throws SceneLoadError.
void import_with_assimp(const std::string& path, Scene& s) {
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* ai =
      importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_SortByPType);
  if (!ai) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown format or unreadable";
    if (why.find("No meshes remaining") != std::string::npos) why = "contains no triangles (only points or lines)";
    throw SceneLoadError(fmt::format("{}: cannot load mesh: {}", path, why));
  }
  if (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE || !ai->mRootNode)
    throw SceneLoadError(fmt::format("{}: file is incomplete (no mesh data)", path));
  Merger m{ai, path, s, std::vector<int>(ai->mNumMaterials, -1)};
  m.walk(ai->mRootNode, aiMatrix4x4(), 0);
}

// Assimp (5.2 as packaged by Debian) can crash, abort on an internal assert
// or loop forever on truncated or malformed files. The import therefore runs
// in a forked child that writes the merged mesh into an anonymous memory file;
// a crash, abort or timeout of the child becomes a SceneLoadError here. The
// price is one copy of the mesh through that file.
struct ImportHeader {
  uint64_t magic = 0x52594C4142494D50ull;  // "RYLABIMP"
  uint64_t error_bytes = 0, vertices = 0, triangles = 0, materials = 0;
};

bool write_all(int fd, const void* data, size_t bytes) {
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::write(fd, p, bytes);
    if (n <= 0) return false;
    p += n;
    bytes -= static_cast<size_t>(n);
  }
  return true;
}

bool read_all(int fd, void* data, size_t bytes) {
  char* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::read(fd, p, bytes);
    if (n <= 0) return false;
    p += n;
    bytes -= static_cast<size_t>(n);
  }
  return true;
}

[[noreturn]] void child_import(const std::string& path, int fd) {
  // Assimp prints its internal assertion messages to stderr; the parent
  // reports one clear error instead.
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (devnull >= 0) ::dup2(devnull, STDERR_FILENO);
  ImportHeader h;
  Scene s;
  std::string error;
  try {
    import_with_assimp(path, s);
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = path + ": cannot load mesh: unknown error";
  }
  bool ok = true;
  if (!error.empty()) {
    h.error_bytes = error.size();
    ok = write_all(fd, &h, sizeof h) && write_all(fd, error.data(), error.size());
  } else {
    h.vertices = s.mesh.vertices.size();
    h.triangles = s.mesh.triangles.size();
    h.materials = s.materials.size();
    ok = write_all(fd, &h, sizeof h) && write_all(fd, s.mesh.vertices.data(), h.vertices * sizeof(Vec3f)) &&
         write_all(fd, s.mesh.triangles.data(), h.triangles * sizeof(std::array<uint32_t, 3>)) &&
         write_all(fd, s.material_ids.data(), h.triangles * sizeof(uint32_t)) &&
         write_all(fd, s.materials.data(), h.materials * sizeof(Material));
  }
  ::_exit(ok ? 0 : 3);
}

double import_timeout_seconds(const std::string& path) {
  if (const char* env = std::getenv("RAYLAB_IMPORT_TIMEOUT")) {
    const double v = std::atof(env);
    if (v > 0) return v;
  }
  std::error_code ec;
  const double mb = static_cast<double>(fs::file_size(path, ec)) / (1 << 20);
  return 30.0 + 2.0 * (ec ? 0.0 : mb);  // generous: real files load at > 50 MB/s
}

void import_isolated(const std::string& path, Scene& s) {
  const int fd = ::memfd_create("raylab-import", MFD_CLOEXEC);
  if (fd < 0) throw SceneLoadError(fmt::format("{}: cannot create memory file: {}", path, std::strerror(errno)));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw SceneLoadError(fmt::format("{}: cannot fork the importer: {}", path, std::strerror(errno)));
  if (pid == 0) child_import(path, fd);

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(import_timeout_seconds(path));
  int status = 0;
  while (true) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw SceneLoadError(fmt::format("{}: lost the importer process", path));
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer did not finish (malformed or truncated file?)", path));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  if (WIFSIGNALED(status))
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer crashed ({}); the file is malformed or truncated",
                                     path, strsignal(WTERMSIG(status))));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer failed (exit code {})", path,
                                     WIFEXITED(status) ? WEXITSTATUS(status) : -1));

  ImportHeader h;
  ::lseek(fd, 0, SEEK_SET);
  if (!read_all(fd, &h, sizeof h) || h.magic != ImportHeader{}.magic)
    throw SceneLoadError(fmt::format("{}: cannot load mesh: importer returned no data", path));
  if (h.error_bytes > 0) {
    std::string error(h.error_bytes, '\0');
    read_all(fd, error.data(), error.size());
    throw SceneLoadError(error);
  }
  s.mesh.vertices.resize(h.vertices);
  s.mesh.triangles.resize(h.triangles);
  s.material_ids.resize(h.triangles);
  s.materials.resize(h.materials);
  if (!read_all(fd, s.mesh.vertices.data(), h.vertices * sizeof(Vec3f)) ||
      !read_all(fd, s.mesh.triangles.data(), h.triangles * sizeof(std::array<uint32_t, 3>)) ||
      !read_all(fd, s.material_ids.data(), h.triangles * sizeof(uint32_t)) ||
      !read_all(fd, s.materials.data(), h.materials * sizeof(Material)))
    throw SceneLoadError(fmt::format("{}: cannot load mesh: importer data truncated", path));
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

  precheck_mesh_file(path);
  Scene s;
  s.name = path;
  import_isolated(path, s);
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

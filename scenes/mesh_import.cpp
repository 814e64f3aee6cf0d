#include "scenes/mesh_import.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <regex>
#include <thread>

#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "scenes/mesh_precheck.h"
#include "scenes/nff_view.h"

namespace raylab {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Isolation. Assimp (5.2 as packaged by Debian) can crash, abort on an
// internal assert or loop forever on truncated or malformed files. The import
// therefore runs in a forked child which writes the merged mesh straight from
// Assimp's arrays into a memory file (memfd) that it maps; the parent reads
// it once into the scene's vectors. A crash, abort or timeout of the child
// becomes a SceneLoadError. The price is that one copy through the memory
// file; nothing else is copied (no intermediate vectors in the child).
//
// Layout of the memory file: ImportHeader, then vertices (Vec3f), triangles
// (3 x uint32), per-triangle material ids (uint32), materials (Material); or,
// on failure, ImportHeader with error_bytes > 0 followed by the message.
struct ImportHeader {
  uint64_t magic = 0x52594C4142494D50ull;  // "RYLABIMP"
  uint64_t error_bytes = 0, vertices = 0, triangles = 0, materials = 0;
  // The file's first camera (glTF, Collada, ...): has_camera, from, at, up,
  // vertical field of view in degrees.
  float has_camera = 0, camera_from[3] = {}, camera_at[3] = {}, camera_up[3] = {}, camera_fov_deg = 0;

  uint64_t payload_bytes() const {
    return vertices * sizeof(Vec3f) + triangles * (sizeof(std::array<uint32_t, 3>) + sizeof(uint32_t)) +
           materials * sizeof(Material);
  }
};

// Rewrites Assimp's messages into plain statements of what is wrong with the
// file (Assimp's own text is kept where it is already clear).
std::string explain_assimp_error(std::string why) {
  if (why.empty()) return "unknown format or unreadable";
  std::smatch m;
  if (why.find("No suitable reader found") != std::string::npos)
    return "unknown or unsupported file format (no Assimp reader accepts it)";
  if (why.find("No meshes remaining") != std::string::npos) return "contains no triangles (only points or lines)";
  static const std::regex number(R"(Cannot parse string \"([^\"]*)\" as a real number)");
  if (std::regex_search(why, m, number)) {
    std::string token = m[1].str();
    token = token.substr(0, std::min(token.find_first_of(" \t\r\n?"), size_t{32}));
    return token.empty() ? "malformed: a number is missing (truncated file?)"
                         : fmt::format("malformed number '{}'", token);
  }
  static const std::regex index(R"(aiMesh::mFaces\[(\d+)\]::mIndices\[\d+\] is out of range)");
  if (std::regex_search(why, m, index))
    return fmt::format("face {} refers to a vertex index out of range", m[1].str());
  if (why.find("is a LINE but") != std::string::npos || why.find("is a POINT but") != std::string::npos)
    return "a face has fewer than 3 vertices (truncated or malformed face record)";
  if (why.find("OBJ: Invalid face index") != std::string::npos)
    return "invalid face index (0, or not a number; OBJ indices start at 1)";
  if (why.rfind("Validation failed: ", 0) == 0) why = "inconsistent data (" + why.substr(19) + ")";
  return why;
}

// The line of the first whitespace-delimited occurrence of `token` in a text
// file (0 if absent), so a "malformed number" names where to look: Assimp's
// text readers report the token but not its line.
uint64_t line_of_token(const std::string& path, const std::string& token) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (uint64_t n = 1; std::getline(in, line) && n < (uint64_t{1} << 32); ++n) {
    for (size_t at = line.find(token); at != std::string::npos; at = line.find(token, at + 1)) {
      const bool starts = at == 0 || std::isspace(static_cast<unsigned char>(line[at - 1]));
      const size_t end = at + token.size();
      const bool ends = end == line.size() || std::isspace(static_cast<unsigned char>(line[end]));
      if (starts && ends) return n;
    }
  }
  return 0;
}

std::string explain_assimp_error_in(const std::string& path, const std::string& why) {
  std::string text = explain_assimp_error(why);
  static const std::regex number(R"(^malformed number '([^']+)'$)");
  std::smatch m;
  if (std::regex_match(text, m, number)) {
    const uint64_t line = line_of_token(path, m[1].str());
    if (line > 0) text += fmt::format(" at line {}", line);
  }
  return text;
}

struct Instance {
  const aiMesh* mesh;
  aiMatrix4x4 xf;
};

void collect(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, int depth, const std::string& path,
             std::vector<Instance>& out) {
  if (depth > 256) throw SceneLoadError(fmt::format("{}: node hierarchy deeper than 256 levels", path));
  const aiMatrix4x4 xf = parent * node->mTransformation;
  for (unsigned i = 0; i < node->mNumMeshes; ++i) {
    if (node->mMeshes[i] >= scene->mNumMeshes)
      throw SceneLoadError(fmt::format("{}: a node refers to mesh {}, but the file has {}", path, node->mMeshes[i],
                                       scene->mNumMeshes));
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
    if (mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) out.push_back({mesh, xf});
  }
  for (unsigned i = 0; i < node->mNumChildren; ++i) collect(scene, node->mChildren[i], xf, depth + 1, path, out);
}

Material material_from(const aiMaterial* am) {
  Material m;  // default grey
  aiColor3D c;
  // Pure white (1, 1, 1) is what Assimp reports when the file gives no colour
  // (PLY, STL, and glTF's default baseColorFactor); as an albedo it would
  // reflect all light forever, and a white object under the white default
  // sky is invisible. It is read as "no colour": the default grey.
  if (am->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS && std::isfinite(c.r) && std::isfinite(c.g) &&
      std::isfinite(c.b) && (c.r > 0 || c.g > 0 || c.b > 0) && !(c.r == 1.0f && c.g == 1.0f && c.b == 1.0f))
    m.albedo = Vec3f(c.r, c.g, c.b).cwiseMax(0.0f).cwiseMin(0.99f);  // albedo 1 would never lose energy
  aiColor3D e;
  if (am->Get(AI_MATKEY_COLOR_EMISSIVE, e) == AI_SUCCESS && std::isfinite(e.r) && std::isfinite(e.g) &&
      std::isfinite(e.b))
    m.emission = Vec3f(e.r, e.g, e.b).cwiseMax(0.0f);
  return m;
}

// The first camera of the file, placed by its node's world transform.
// Assimp (5.2) documents mHorizontalFOV as half the horizontal angle, but its
// importers store the full angle (Collada, FBX, Blender, 3DS; assimp issue
// #2256, whose fix changed the comment to "horizontal field of view"): a
// Collada yfov of 37.8 degrees at aspect 1.5 arrives as 54.4 degrees. The
// glTF 2 importer departs further: it copies the node's translation into
// mPosition (so it would count twice) and stores yfov x aspect. raylab's
// views take the full vertical angle.
void store_first_camera(const aiScene* ai, ImportHeader& h, bool gltf) {
  if (ai->mNumCameras == 0 || !ai->mCameras[0]) return;
  const aiCamera* cam = ai->mCameras[0];
  aiMatrix4x4 xf;
  for (const aiNode* node = ai->mRootNode->FindNode(cam->mName); node; node = node->mParent)
    xf = node->mTransformation * xf;
  aiMatrix3x3 rot(xf);
  const aiVector3D from = xf * (gltf ? aiVector3D(0, 0, 0) : cam->mPosition);
  const aiVector3D dir = rot * cam->mLookAt;
  const aiVector3D up = rot * cam->mUp;
  const float aspect = cam->mAspect > 0 ? cam->mAspect : 1.0f;
  const float hfov = cam->mHorizontalFOV > 0 ? cam->mHorizontalFOV : 0.785398f;
  const float vfov_rad = gltf ? hfov / aspect : 2.0f * std::atan(std::tan(0.5f * hfov) / aspect);
  const float vfov = vfov_rad * 180.0f / 3.14159265f;
  const float values[] = {from.x, from.y, from.z, from.x + dir.x, from.y + dir.y, from.z + dir.z, up.x, up.y, up.z, vfov};
  for (float v : values)
    if (!std::isfinite(v)) return;
  View v;
  v.from = Vec3f(from.x, from.y, from.z);
  v.at = Vec3f(values[3], values[4], values[5]);
  v.up = Vec3f(up.x, up.y, up.z);
  v.fov_deg = vfov;
  if (!view_problem(v).empty()) return;  // a degenerate camera: keep the default framing
  h.has_camera = 1;
  std::copy(values, values + 3, h.camera_from);
  std::copy(values + 3, values + 6, h.camera_at);
  std::copy(values + 6, values + 9, h.camera_up);
  h.camera_fov_deg = vfov;
}

// Reads `path` with Assimp and writes the merged mesh into the memory file.
// Runs in the child. Throws SceneLoadError.
void import_into_memfd(const std::string& path, int fd) {
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* ai =
      importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_SortByPType);
  if (!ai)
    throw SceneLoadError(
        fmt::format("{}: cannot load mesh: {}", path, explain_assimp_error_in(path, importer.GetErrorString())));
  if (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE || !ai->mRootNode)
    throw SceneLoadError(fmt::format("{}: file is incomplete (no mesh data)", path));

  std::vector<Instance> instances;
  collect(ai, ai->mRootNode, aiMatrix4x4(), 0, path, instances);
  // Sizes first, so the memory file is sized once and filled in place.
  ImportHeader h;
  std::vector<int> material_of_ai(ai->mNumMaterials, -1);
  for (const Instance& in : instances) {
    h.vertices += in.mesh->mNumVertices;
    for (unsigned f = 0; f < in.mesh->mNumFaces; ++f) h.triangles += in.mesh->mFaces[f].mNumIndices == 3;
    const unsigned mi = in.mesh->mMaterialIndex;
    if (mi < material_of_ai.size() && material_of_ai[mi] < 0) material_of_ai[mi] = static_cast<int>(h.materials++);
  }
  if (h.vertices >= 0xFFFFFFFFull)
    throw SceneLoadError(fmt::format("{}: {} vertices, more than 32-bit indices can address", path, h.vertices));
  const bool default_material = h.materials == 0 || std::any_of(instances.begin(), instances.end(), [&](const Instance& in) {
                                  return in.mesh->mMaterialIndex >= material_of_ai.size();
                                });
  const uint32_t default_id = static_cast<uint32_t>(h.materials);
  if (default_material) ++h.materials;

  {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    store_first_camera(ai, h, ext == ".gltf" || ext == ".glb");
  }
  const uint64_t bytes = sizeof h + h.payload_bytes();
  if (::ftruncate(fd, static_cast<off_t>(bytes)) != 0)
    throw SceneLoadError(fmt::format("{}: cannot size the import buffer ({} bytes): {}", path, bytes, std::strerror(errno)));
  void* map = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (map == MAP_FAILED) throw SceneLoadError(fmt::format("{}: cannot map the import buffer: {}", path, std::strerror(errno)));
  char* base = static_cast<char*>(map);
  auto* vertices = reinterpret_cast<Vec3f*>(base + sizeof h);
  auto* triangles = reinterpret_cast<std::array<uint32_t, 3>*>(vertices + h.vertices);
  auto* material_ids = reinterpret_cast<uint32_t*>(triangles + h.triangles);
  auto* materials = reinterpret_cast<Material*>(material_ids + h.triangles);

  uint64_t vi = 0, ti = 0;
  for (const Instance& in : instances) {
    const aiMesh* mesh = in.mesh;
    const auto first = static_cast<uint32_t>(vi);
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D p = in.xf * mesh->mVertices[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        const aiVector3D q = mesh->mVertices[i];
        throw SceneLoadError(fmt::format("{}: vertex {}{} has a non-finite coordinate ({}, {}, {})", path, i,
                                         instances.size() > 1 ? fmt::format(" of mesh '{}'", mesh->mName.C_Str()) : "",
                                         q.x, q.y, q.z));
      }
      vertices[vi++] = Vec3f(p.x, p.y, p.z);
    }
    const unsigned mi = mesh->mMaterialIndex;
    const uint32_t material = mi < material_of_ai.size() ? static_cast<uint32_t>(material_of_ai[mi]) : default_id;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines carry no surface
      std::array<uint32_t, 3> tri;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          throw SceneLoadError(fmt::format("{}: face {} refers to vertex {}, but the mesh has {} vertices", path, f,
                                           face.mIndices[k], mesh->mNumVertices));
        tri[k] = first + face.mIndices[k];
      }
      material_ids[ti] = material;
      triangles[ti++] = tri;
    }
  }
  for (size_t i = 0; i < material_of_ai.size(); ++i)
    if (material_of_ai[i] >= 0) materials[material_of_ai[i]] = material_from(ai->mMaterials[i]);
  if (default_material) materials[default_id] = Material{};
  std::memcpy(base, &h, sizeof h);  // the header last: a child killed mid-way leaves no valid magic
  ::munmap(map, bytes);
}

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

bool pread_all(int fd, void* data, size_t bytes, uint64_t offset) {
  char* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd, p, bytes, static_cast<off_t>(offset));
    if (n <= 0) return false;
    p += n;
    offset += static_cast<uint64_t>(n);
    bytes -= static_cast<size_t>(n);
  }
  return true;
}

[[noreturn]] void child_import(const std::string& path, int fd) {
  // Assimp prints its internal assertion messages to stderr; the parent
  // reports one clear error instead.
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (devnull >= 0) ::dup2(devnull, STDERR_FILENO);
  std::string error;
  try {
    import_into_memfd(path, fd);
    ::_exit(0);
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = path + ": cannot load mesh: unknown error";
  }
  ImportHeader h;
  h.error_bytes = error.size();
  const bool ok = ::ftruncate(fd, 0) == 0 && ::lseek(fd, 0, SEEK_SET) == 0 && write_all(fd, &h, sizeof h) &&
                  write_all(fd, error.data(), error.size());
  ::_exit(ok ? 0 : 3);
}

double import_timeout_seconds(const std::string& path) {
  if (const char* env = std::getenv("RAYLAB_IMPORT_TIMEOUT")) {
    const double v = std::atof(env);
    if (v > 0) return v;
  }
  std::error_code ec;
  const double mb = static_cast<double>(fs::file_size(path, ec)) / (1 << 20);
  return 30.0 + 2.0 * (ec ? 0.0 : mb);  // generous: real files load at > 20 MB/s
}

// Runs the import in a child; `meanwhile` runs in this process at the same
// time (the prechecks: on two cores they cost no wall time), and if it
// throws, the child is killed and its exception wins.
void import_isolated(const std::string& path, Scene& s, const std::function<void()>& meanwhile,
                     std::optional<View>& file_camera) {
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
  int status = 0;
  try {
    meanwhile();
  } catch (...) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
    throw;
  }

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(import_timeout_seconds(path));
  auto poll = std::chrono::microseconds(200);
  while (true) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw SceneLoadError(fmt::format("{}: lost the importer process", path));
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw SceneLoadError(
          fmt::format("{}: cannot load mesh: the importer did not finish (malformed or truncated file?)", path));
    }
    std::this_thread::sleep_for(poll);
    poll = std::min(poll * 2, std::chrono::microseconds(5000));
  }
  if (WIFSIGNALED(status))
    throw SceneLoadError(fmt::format(
        "{}: cannot load mesh: the importer crashed ({}); the file is malformed or truncated", path, strsignal(WTERMSIG(status))));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer failed (exit code {})", path,
                                     WIFEXITED(status) ? WEXITSTATUS(status) : -1));

  ImportHeader h;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !pread_all(fd, &h, sizeof h, 0) || h.magic != ImportHeader{}.magic)
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer returned no data", path));
  const auto file_bytes = static_cast<uint64_t>(st.st_size);
  if (h.error_bytes > 0) {
    std::string error(std::min<uint64_t>(h.error_bytes, 4096), '\0');
    pread_all(fd, error.data(), error.size(), sizeof h);
    throw SceneLoadError(error);
  }
  if (h.vertices > file_bytes || h.triangles > file_bytes || h.materials > file_bytes ||
      sizeof h + h.payload_bytes() != file_bytes)
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer returned inconsistent data", path));
  s.mesh.vertices.resize(h.vertices);
  s.mesh.triangles.resize(h.triangles);
  s.material_ids.resize(h.triangles);
  s.materials.resize(h.materials);
  uint64_t at = sizeof h;
  auto read_part = [&](void* dst, uint64_t n) {
    const bool ok = pread_all(fd, dst, n, at);
    at += n;
    return ok;
  };
  if (!read_part(s.mesh.vertices.data(), h.vertices * sizeof(Vec3f)) ||
      !read_part(s.mesh.triangles.data(), h.triangles * sizeof(std::array<uint32_t, 3>)) ||
      !read_part(s.material_ids.data(), h.triangles * sizeof(uint32_t)) ||
      !read_part(s.materials.data(), h.materials * sizeof(Material)))
    throw SceneLoadError(fmt::format("{}: cannot load mesh: the importer's data is truncated", path));
  if (h.has_camera == 1) {
    View v;
    v.from = Vec3f(h.camera_from[0], h.camera_from[1], h.camera_from[2]);
    v.at = Vec3f(h.camera_at[0], h.camera_at[1], h.camera_at[2]);
    v.up = Vec3f(h.camera_up[0], h.camera_up[1], h.camera_up[2]);
    v.fov_deg = h.camera_fov_deg;
    if (view_problem(v).empty()) file_camera = v;
  }
}

Vec3f json_vec3(const nlohmann::json& j, const char* key, const std::string& file) {
  if (!j.contains(key)) throw SceneLoadError(fmt::format("{}: view file has no '{}'", file, key));
  const auto& a = j.at(key);
  if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
    throw SceneLoadError(fmt::format("{}: '{}' must be an array of 3 numbers", file, key));
  return Vec3f(a[0].get<float>(), a[1].get<float>(), a[2].get<float>());
}

}  // namespace

void apply_sibling_view_file(const std::string& mesh_path, View& v) {
  const fs::path file = fs::path(mesh_path).replace_extension(".json");
  std::error_code ec;
  if (file == fs::path(mesh_path) || !fs::exists(file, ec)) return;
  std::ifstream in(file);
  if (!in) throw SceneLoadError(fmt::format("{}: cannot open the view file", file.string()));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw SceneLoadError(fmt::format("{}: invalid view file: {}", file.string(), e.what()));
  }
  if (!j.is_object()) throw SceneLoadError(fmt::format("{}: a view file must hold a JSON object", file.string()));
  if (j.contains("meshes") && !j.contains("from")) return;  // a scene file that happens to share the name
  View out = v;
  out.from = json_vec3(j, "from", file.string());
  out.at = json_vec3(j, "at", file.string());
  out.up = json_vec3(j, "up", file.string());
  auto number = [&](const char* key, auto fallback) {
    using T = decltype(fallback);
    if (!j.contains(key)) return fallback;
    if (!j[key].is_number() || (std::is_integral_v<T> && !j[key].is_number_integer()))
      throw SceneLoadError(fmt::format("{}: '{}' must be {}", file.string(), key, std::is_integral_v<T> ? "an integer" : "a number"));
    return j[key].template get<T>();
  };
  if (!j.contains("fov_deg")) throw SceneLoadError(fmt::format("{}: view file has no 'fov_deg'", file.string()));
  out.fov_deg = number("fov_deg", out.fov_deg);
  out.width = number("width", out.width);
  out.height = number("height", out.height);
  if (const std::string why = view_problem(out); !why.empty())
    throw SceneLoadError(fmt::format("{}: {}", file.string(), why));
  v = out;
}

Scene load_mesh_file(const std::string& path) {
  std::error_code ec;
  // symlink_status: a dangling symlink or a symlink loop exists but cannot
  // be opened; open() below says why.
  if (!fs::exists(fs::symlink_status(path, ec))) throw SceneLoadError(fmt::format("{}: no such file", path));
  if (fs::is_directory(path, ec)) throw SceneLoadError(fmt::format("{}: is a directory, not a mesh file", path));
  {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw SceneLoadError(fmt::format("{}: cannot open for reading: {}", path, std::strerror(errno)));
    char byte;
    const ssize_t n = ::read(fd, &byte, 1);
    const int err = errno;
    ::close(fd);
    if (n < 0) throw SceneLoadError(fmt::format("{}: cannot read: {}", path, std::strerror(err)));
    if (n == 0) throw SceneLoadError(fmt::format("{}: file is empty", path));
  }

  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::optional<View> nff_view, file_camera;
  Scene s;
  s.name = path;
  // The prechecks run while the child imports; their precise messages take
  // precedence over whatever Assimp makes of a bad file.
  import_isolated(path, s, [&] {
    precheck_mesh_file(path);
    if (ext == ".nff") nff_view = read_nff_view(path);
  }, file_camera);
  if (s.mesh.num_triangles() == 0) throw SceneLoadError(fmt::format("{}: contains no triangles", path));
  if (s.materials.empty()) s.materials.push_back(Material{});
  try {
    s.validate();
  } catch (const MeshError& e) {
    throw SceneLoadError(fmt::format("{}: {}", path, e.what()));
  }

  // The file's own camera when it has one (NFF's viewpoint, a glTF camera), else a framing of the bounds.
  s.view = nff_view ? *nff_view : file_camera ? *file_camera : frame_bounds(s.bounds());
  apply_sibling_view_file(path, s.view);
  if (s.has_emitters()) {
    s.background = Vec3f::Constant(0.05f);
  } else {
    // A dim sky plus a key light (irradiance pi: a white Lambertian surface
    // facing it reflects radiance 1) gives shading and shadows; a white sky
    // alone made grey objects flat silhouettes.
    s.background = Vec3f::Constant(0.3f);
    s.key_light = Vec3f::Constant(3.14159265f);
    aim_key_light(s);
  }
  return s;
}

}  // namespace raylab

#pragma once
// Writers for the small mesh files the scene tests create themselves: text
// formats as strings, binary PLY and STL, glTF 2.0 with an embedded base64
// buffer (or as .glb).
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scenes/mesh_import.h"

namespace raylab::test {

inline std::string write_file(const std::filesystem::path& dir, const std::string& name, const std::string& bytes) {
  const auto p = dir / name;
  std::ofstream(p, std::ios::binary) << bytes;
  return p.string();
}

// Message of the SceneLoadError `load` throws (empty if none).
template <class Load>
std::string load_error_of(Load load) {
  try {
    load();
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "";
}

// Message of the SceneLoadError thrown by load_mesh_file (empty if none).
inline std::string load_error(const std::string& path) {
  return load_error_of([&] { load_mesh_file(path); });
}

template <class T>
void append_raw(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

inline std::string base64(const std::string& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8) | uint8_t(bytes[i + 2]);
    for (int k = 3; k >= 0; --k) out += alphabet[(v >> (6 * k)) & 63];
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint8_t(bytes[i]) << 16;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

// Binary little-endian PLY: float xyz vertices, uchar-count int32 faces.
inline std::string binary_ply(const std::vector<float>& xyz, const std::vector<std::vector<int32_t>>& faces) {
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(xyz.size() / 3) +
                  "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces.size()) +
                  "\nproperty list uchar int vertex_indices\nend_header\n";
  for (float f : xyz) append_raw(s, f);
  for (const auto& f : faces) {
    s.push_back(static_cast<char>(f.size()));
    for (int32_t i : f) append_raw(s, i);
  }
  return s;
}

// Binary STL: 80-byte header, count, 50 bytes per triangle (9 floats per triangle in `xyz`).
inline std::string binary_stl(const std::vector<float>& xyz) {
  std::string s(80, ' ');
  append_raw(s, static_cast<uint32_t>(xyz.size() / 9));
  for (size_t t = 0; t + 8 < xyz.size(); t += 9) {
    for (int k = 0; k < 3; ++k) append_raw(s, 0.0f);  // normal (ignored)
    for (int k = 0; k < 9; ++k) append_raw(s, xyz[t + k]);
    s.append(2, '\0');
  }
  return s;
}

// One glTF primitive: positions, indices (uint32 or uint16), material colours.
struct GltfPrimitive {
  std::vector<float> xyz;
  std::vector<uint32_t> indices;
  bool short_indices = false;
  std::vector<float> base_color = {0.8f, 0.8f, 0.8f, 1.0f};
  std::vector<float> emissive = {0.0f, 0.0f, 0.0f};
};

// A glTF 2.0 document with one mesh per primitive, each on its own node
// (node i translated by translations[i] if given), all data in buffer 0.
// Returns the JSON and the binary buffer; `embed` puts the buffer in a data URI.
inline nlohmann::json gltf_document(const std::vector<GltfPrimitive>& prims, std::string& buffer,
                                    const std::vector<std::vector<float>>& translations = {}) {
  using nlohmann::json;
  json doc = {{"asset", {{"version", "2.0"}}}, {"scene", 0}};
  json nodes = json::array(), meshes = json::array(), materials = json::array(), views = json::array(),
       accessors = json::array(), scene_nodes = json::array();
  buffer.clear();
  for (size_t i = 0; i < prims.size(); ++i) {
    const GltfPrimitive& p = prims[i];
    while (buffer.size() % 4) buffer.push_back('\0');
    const size_t pos_offset = buffer.size();
    for (float f : p.xyz) append_raw(buffer, f);
    views.push_back({{"buffer", 0}, {"byteOffset", pos_offset}, {"byteLength", p.xyz.size() * 4}});
    json lo = json::array(), hi = json::array();
    for (int k = 0; k < 3; ++k) {
      float mn = 1e30f, mx = -1e30f;
      for (size_t v = k; v < p.xyz.size(); v += 3) mn = std::min(mn, p.xyz[v]), mx = std::max(mx, p.xyz[v]);
      lo.push_back(mn);
      hi.push_back(mx);
    }
    accessors.push_back({{"bufferView", views.size() - 1}, {"componentType", 5126}, {"count", p.xyz.size() / 3},
                         {"type", "VEC3"}, {"min", lo}, {"max", hi}});
    const size_t position_accessor = accessors.size() - 1;
    while (buffer.size() % 4) buffer.push_back('\0');
    const size_t idx_offset = buffer.size();
    for (uint32_t v : p.indices) {
      if (p.short_indices) append_raw(buffer, static_cast<uint16_t>(v));
      else append_raw(buffer, v);
    }
    views.push_back({{"buffer", 0}, {"byteOffset", idx_offset}, {"byteLength", buffer.size() - idx_offset}});
    accessors.push_back({{"bufferView", views.size() - 1}, {"componentType", p.short_indices ? 5123 : 5125},
                         {"count", p.indices.size()}, {"type", "SCALAR"}});
    materials.push_back({{"pbrMetallicRoughness", {{"baseColorFactor", p.base_color}}}, {"emissiveFactor", p.emissive}});
    meshes.push_back({{"primitives", json::array({{{"attributes", {{"POSITION", position_accessor}}},
                                                   {"indices", accessors.size() - 1},
                                                   {"material", materials.size() - 1}}})}});
    json node = {{"mesh", meshes.size() - 1}};
    if (i < translations.size()) node["translation"] = translations[i];
    nodes.push_back(node);
    scene_nodes.push_back(nodes.size() - 1);
  }
  doc["nodes"] = nodes;
  doc["meshes"] = meshes;
  doc["materials"] = materials;
  doc["bufferViews"] = views;
  doc["accessors"] = accessors;
  doc["scenes"] = json::array({{{"nodes", scene_nodes}}});
  doc["buffers"] = json::array({{{"byteLength", buffer.size()}}});
  return doc;
}

inline std::string gltf_embedded(const std::vector<GltfPrimitive>& prims, const std::vector<std::vector<float>>& translations = {}) {
  std::string buffer;
  nlohmann::json doc = gltf_document(prims, buffer, translations);
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
  return doc.dump();
}

// Binary glTF container: header, JSON chunk, BIN chunk (both 4-byte aligned).
inline std::string glb(const std::vector<GltfPrimitive>& prims) {
  std::string buffer;
  std::string text = gltf_document(prims, buffer).dump();
  while (text.size() % 4) text.push_back(' ');
  while (buffer.size() % 4) buffer.push_back('\0');
  std::string out = "glTF";
  append_raw(out, uint32_t{2});
  append_raw(out, static_cast<uint32_t>(12 + 8 + text.size() + 8 + buffer.size()));
  append_raw(out, static_cast<uint32_t>(text.size()));
  append_raw(out, uint32_t{0x4E4F534A});
  out += text;
  append_raw(out, static_cast<uint32_t>(buffer.size()));
  append_raw(out, uint32_t{0x004E4942});
  out += buffer;
  return out;
}

}  // namespace raylab::test

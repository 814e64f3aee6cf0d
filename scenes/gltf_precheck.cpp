// Structural checks of glTF 2.0 files before Assimp reads them (see
// precheck_gltf in mesh_precheck.h). Only what decides whether the triangles
// can be read is checked: buffers, views, accessors, index ranges.
#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "scenes/mesh_import.h"
#include "scenes/mesh_precheck.h"

namespace raylab {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// RFC 4648 base64 (no line breaks in data URIs); false on a bad character.
bool decode_base64(const std::string& text, size_t begin, std::string& out) {
  static const std::array<int8_t, 256> table = [] {
    std::array<int8_t, 256> t{};
    t.fill(-1);
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) t[static_cast<unsigned char>(alphabet[i])] = static_cast<int8_t>(i);
    return t;
  }();
  out.clear();
  out.reserve((text.size() - begin) / 4 * 3);
  uint32_t acc = 0;
  int bits = 0;
  for (size_t i = begin; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '=') break;
    const int v = table[static_cast<unsigned char>(c)];
    if (v < 0) return false;
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((acc >> bits) & 0xFF));
    }
  }
  return true;
}

// Where a buffer's bytes are: decoded in memory (data URI) or a byte range of
// a file (external .bin, or the BIN chunk of a .glb).
struct BufferData {
  std::string memory;
  std::string file;
  uint64_t file_offset = 0;
  uint64_t size = 0;        // bytes actually available
  uint64_t byte_length = 0; // bytes declared
  mutable std::shared_ptr<std::ifstream> stream;

  bool read(uint64_t offset, uint64_t n, char* dst) const {
    if (offset + n > size) return false;
    if (file.empty()) {
      std::copy_n(memory.data() + offset, n, dst);
      return true;
    }
    if (!stream) stream = std::make_shared<std::ifstream>(file, std::ios::binary);
    std::ifstream& in = *stream;
    in.clear();
    in.seekg(static_cast<std::streamoff>(file_offset + offset));
    in.read(dst, static_cast<std::streamsize>(n));
    return static_cast<uint64_t>(in.gcount()) == n;
  }
};

class GltfChecker {
 public:
  GltfChecker(const std::string& path, uint64_t file_size) : path_(path), file_size_(file_size) {}

  void run() {
    std::string text = read_json_text();
    try {
      doc_ = json::parse(text);
    } catch (const json::parse_error& e) {
      std::string what = e.what();
      const auto bracket = what.find("] ");
      if (bracket != std::string::npos) what = what.substr(bracket + 2);
      if (what.size() > 200) what = what.substr(0, 200) + "...";  // "last read" may quote a long string
      fail(fmt::format("malformed JSON ({})", what));
    }
    text.clear();
    if (!doc_.is_object()) fail("not a glTF file (the JSON is not an object)");
    if (!doc_.contains("asset") || !doc_["asset"].is_object()) fail("not a glTF file (no 'asset' object)");
    const json& version = doc_["asset"]["version"];
    if (!version.is_string() || version.get<std::string>().rfind("2", 0) != 0)
      fail(fmt::format("not a glTF 2.0 file (asset.version is {})", version.dump()));
    check_buffers();
    check_meshes();
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw SceneLoadError(fmt::format("{}: {}", path_, what)); }

  const json& array(const json& parent, const char* key) const {
    static const json empty = json::array();
    if (!parent.contains(key)) return empty;
    if (!parent[key].is_array()) fail(fmt::format("'{}' must be an array", key));
    return parent[key];
  }

  uint64_t uint_field(const json& obj, const char* key, const std::string& where, uint64_t fallback, bool required = false) const {
    if (!obj.contains(key)) {
      if (required) fail(fmt::format("{} has no '{}'", where, key));
      return fallback;
    }
    if (!obj[key].is_number_unsigned()) fail(fmt::format("{}.{} must be a non-negative integer", where, key));
    return obj[key].get<uint64_t>();
  }

  std::string read_json_text() {
    std::ifstream in(path_, std::ios::binary);
    std::string head(12, '\0');
    in.read(head.data(), 12);
    if (in.gcount() == 12 && head.compare(0, 4, "glTF") == 0) {
      // GLB: 12-byte header (magic, version, length), then chunks of
      // (length, type, data): JSON first, then an optional BIN chunk.
      uint32_t version = 0, length = 0;
      std::memcpy(&version, head.data() + 4, 4);
      std::memcpy(&length, head.data() + 8, 4);
      if (version != 2) fail(fmt::format("GLB container version {} (only glTF 2.0 is read)", version));
      if (length > file_size_) fail(fmt::format("truncated GLB: the header declares {} bytes, the file has {}", length, file_size_));
      uint64_t at = 12;
      std::string json_text;
      while (at + 8 <= length) {
        uint32_t chunk_length = 0, type = 0;
        in.seekg(static_cast<std::streamoff>(at));
        in.read(reinterpret_cast<char*>(&chunk_length), 4);
        in.read(reinterpret_cast<char*>(&type), 4);
        if (at + 8 + chunk_length > length) fail("truncated GLB: a chunk runs past the end of the file");
        if (type == 0x4E4F534Au) {  // "JSON"
          json_text.resize(chunk_length);
          in.read(json_text.data(), chunk_length);
        } else if (type == 0x004E4942u && !glb_bin_) {  // "BIN\0"
          glb_bin_ = true;
          glb_bin_offset_ = at + 8;
          glb_bin_size_ = chunk_length;
        }
        at += 8 + chunk_length;
      }
      if (json_text.empty()) fail("GLB file without a JSON chunk");
      return json_text;
    }
    in.clear();
    in.seekg(0);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  void check_buffers() {
    const json& buffers = array(doc_, "buffers");
    for (size_t i = 0; i < buffers.size(); ++i) {
      const json& b = buffers[i];
      const std::string where = fmt::format("buffers[{}]", i);
      if (!b.is_object()) fail(where + " must be an object");
      BufferData data;
      data.byte_length = uint_field(b, "byteLength", where, 0, true);
      if (b.contains("uri")) {
        if (!b["uri"].is_string()) fail(where + ".uri must be a string");
        const std::string uri = b["uri"];
        if (uri.rfind("data:", 0) == 0) {
          const auto comma = uri.find(',');
          if (comma == std::string::npos || uri.rfind(";base64", comma) == std::string::npos)
            fail(where + ": only base64 data URIs are supported");
          if (!decode_base64(uri, comma + 1, data.memory)) fail(where + ": the data URI is not valid base64");
          data.size = data.memory.size();
        } else {
          const fs::path file = fs::path(path_).parent_path() / uri;
          std::error_code ec;
          const auto size = fs::file_size(file, ec);
          if (ec) fail(fmt::format("{}: cannot read the buffer file '{}'", where, file.string()));
          data.file = file.string();
          data.size = size;
        }
      } else {
        if (i != 0 || !glb_bin_) fail(where + " has no uri (and is not the binary chunk of a .glb)");
        data.file = path_;
        data.file_offset = glb_bin_offset_;
        data.size = glb_bin_size_;
      }
      if (data.size < data.byte_length)
        fail(fmt::format("{} declares {} bytes, but its data has only {} (truncated?)", where, data.byte_length, data.size));
      buffers_.push_back(std::move(data));
    }
  }

  // Byte range [offset, offset + size) of accessor `a` inside its buffer,
  // checked against the view and the buffer. Returns the buffer index.
  size_t accessor_range(uint64_t a, const std::string& where, uint64_t& offset, uint64_t& stride, uint64_t& elem,
                        uint64_t& count, uint64_t& component_type) const {
    const json& accessors = array(doc_, "accessors");
    if (a >= accessors.size()) fail(fmt::format("{} refers to accessor {}, but there are {}", where, a, accessors.size()));
    const json& acc = accessors[a];
    const std::string aw = fmt::format("accessors[{}]", a);
    if (!acc.is_object()) fail(aw + " must be an object");
    count = uint_field(acc, "count", aw, 0, true);
    component_type = uint_field(acc, "componentType", aw, 0, true);
    const uint64_t comp = component_type == 5120 || component_type == 5121 ? 1
                          : component_type == 5122 || component_type == 5123 ? 2
                          : component_type == 5125 || component_type == 5126 ? 4 : 0;
    if (comp == 0) fail(fmt::format("{}.componentType {} is not a glTF component type", aw, component_type));
    if (!acc.contains("type") || !acc["type"].is_string()) fail(aw + " has no 'type'");
    const std::string type = acc["type"];
    const uint64_t n = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : type == "VEC4" ? 4
                       : type == "MAT2" ? 4 : type == "MAT3" ? 9 : type == "MAT4" ? 16 : 0;
    if (n == 0) fail(fmt::format("{}.type '{}' is not a glTF accessor type", aw, type));
    elem = n * comp;
    if (!acc.contains("bufferView")) return SIZE_MAX;  // all zeros (or sparse): nothing to read
    const json& views = array(doc_, "bufferViews");
    const uint64_t v = uint_field(acc, "bufferView", aw, 0);
    if (v >= views.size()) fail(fmt::format("{} refers to bufferView {}, but there are {}", aw, v, views.size()));
    const json& view = views[v];
    const std::string vw = fmt::format("bufferViews[{}]", v);
    const uint64_t buffer = uint_field(view, "buffer", vw, 0, true);
    if (buffer >= buffers_.size()) fail(fmt::format("{} refers to buffer {}, but there are {}", vw, buffer, buffers_.size()));
    const uint64_t view_offset = uint_field(view, "byteOffset", vw, 0);
    const uint64_t view_length = uint_field(view, "byteLength", vw, 0, true);
    if (view_offset + view_length > buffers_[buffer].byte_length)
      fail(fmt::format("{} (bytes {}..{}) lies outside buffer {} ({} bytes)", vw, view_offset, view_offset + view_length, buffer,
                       buffers_[buffer].byte_length));
    stride = uint_field(view, "byteStride", vw, 0);
    if (stride == 0) stride = elem;
    const uint64_t acc_offset = uint_field(acc, "byteOffset", aw, 0);
    const uint64_t need = count == 0 ? 0 : acc_offset + stride * (count - 1) + elem;
    if (need > view_length)
      fail(fmt::format("{} needs {} bytes of {}, which has {} (truncated or wrong count?)", aw, need, vw, view_length));
    offset = view_offset + acc_offset;
    return buffer;
  }

  void check_meshes() {
    const json& meshes = array(doc_, "meshes");
    size_t triangle_primitives = 0;
    for (size_t m = 0; m < meshes.size(); ++m) {
      const json& prims = array(meshes[m], "primitives");
      for (size_t p = 0; p < prims.size(); ++p) {
        const json& prim = prims[p];
        const std::string where = fmt::format("meshes[{}].primitives[{}]", m, p);
        const uint64_t mode = uint_field(prim, "mode", where, 4);
        if (mode < 4) continue;  // points and lines: no surface, dropped by the importer
        ++triangle_primitives;
        if (!prim.contains("attributes") || !prim["attributes"].is_object() || !prim["attributes"].contains("POSITION"))
          fail(where + " has no POSITION attribute");
        uint64_t offset = 0, stride = 0, elem = 0, vertices = 0, type = 0;
        accessor_range(uint_field(prim["attributes"], "POSITION", where + ".attributes", 0), where + ".attributes.POSITION",
                       offset, stride, elem, vertices, type);
        if (!prim.contains("indices")) {
          if (mode == 4 && vertices % 3 != 0)
            fail(fmt::format("{}: {} vertices without indices, not a multiple of 3 (truncated?)", where, vertices));
          continue;
        }
        uint64_t count = 0;
        const size_t buffer = accessor_range(uint_field(prim, "indices", where, 0), where + ".indices", offset, stride, elem,
                                             count, type);
        if (type != 5121 && type != 5123 && type != 5125)
          fail(fmt::format("{}: index componentType {} is not an unsigned integer type", where, type));
        if (mode == 4 && count % 3 != 0)
          fail(fmt::format("{}: {} indices, not a multiple of 3 (truncated?)", where, count));
        if (buffer == SIZE_MAX || count == 0) continue;
        check_indices(buffers_[buffer], offset, stride, elem, count, vertices, where);
      }
    }
    if (triangle_primitives == 0) fail("contains no triangles (no mesh primitive of triangles)");
  }

  void check_indices(const BufferData& data, uint64_t offset, uint64_t stride, uint64_t elem, uint64_t count,
                     uint64_t vertices, const std::string& where) const {
    // In chunks, so a large index buffer needs no large temporary.
    constexpr uint64_t kChunk = 1 << 16;
    std::string bytes;
    for (uint64_t first = 0; first < count; first += kChunk) {
      const uint64_t n = std::min(kChunk, count - first);
      bytes.resize(stride * (n - 1) + elem);
      if (!data.read(offset + first * stride, bytes.size(), bytes.data())) fail(where + ": cannot read the index data");
      for (uint64_t i = 0; i < n; ++i) {
        const char* p = bytes.data() + i * stride;
        uint32_t v = 0;
        if (elem == 1) {
          v = static_cast<uint8_t>(*p);
        } else if (elem == 2) {
          uint16_t s;
          std::memcpy(&s, p, 2);
          v = s;
        } else {
          std::memcpy(&v, p, 4);
        }
        if (v >= vertices)
          fail(fmt::format("{}: index {} is {}, but POSITION has {} vertices (index out of range)", where, first + i, v, vertices));
      }
    }
  }

  const std::string& path_;
  uint64_t file_size_;
  json doc_;
  std::vector<BufferData> buffers_;
  bool glb_bin_ = false;
  uint64_t glb_bin_offset_ = 0, glb_bin_size_ = 0;
};

}  // namespace

void precheck_gltf(const std::string& path, uint64_t file_size) { GltfChecker(path, file_size).run(); }

}  // namespace raylab

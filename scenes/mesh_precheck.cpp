#include "scenes/mesh_precheck.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "scenes/mesh_import.h"

namespace raylab {

namespace {

std::string lower_extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

int ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// Counts non-empty lines from the current position (stops early at `enough`).
uint64_t count_data_lines(std::istream& in, uint64_t enough) {
  uint64_t lines = 0;
  std::string line;
  while (lines < enough && std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos && line[line.find_first_not_of(" \t\r")] != '#') ++lines;
  }
  return lines;
}

void precheck_ply(const std::string& path, uint64_t file_size) {
  std::ifstream in(path, std::ios::binary);
  std::string line, format;
  struct Element {
    std::string name;
    uint64_t count = 0;
    uint64_t min_bytes = 0;  // per element, binary formats
  };
  std::vector<Element> elements;
  bool ended = false;
  size_t header_bytes = 0;
  while (std::getline(in, line)) {
    header_bytes += line.size() + 1;
    if (header_bytes > (1u << 20)) break;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> format;
    } else if (word == "element") {
      Element e;
      std::string count;
      ls >> e.name >> count;
      try {
        size_t used = 0;
        e.count = std::stoull(count, &used);
        if (used != count.size()) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw SceneLoadError(fmt::format("{}: PLY element '{}' has an invalid count '{}'", path, e.name, count));
      }
      elements.push_back(e);
    } else if (word == "property" && !elements.empty()) {
      std::string type;
      ls >> type;
      if (type == "list") {
        std::string count_type, item_type;
        ls >> count_type >> item_type;
        elements.back().min_bytes += static_cast<uint64_t>(ply_type_size(count_type));
        // A face's index list needs three entries to make a triangle.
        if (elements.back().name == "face") elements.back().min_bytes += 3u * static_cast<uint64_t>(ply_type_size(item_type));
      } else {
        elements.back().min_bytes += static_cast<uint64_t>(ply_type_size(type));
      }
    } else if (word == "end_header") {
      ended = true;
      break;
    }
  }
  if (!ended) throw SceneLoadError(fmt::format("{}: PLY header has no end_header (truncated or not a PLY file)", path));
  const uint64_t body = file_size > header_bytes ? file_size - header_bytes : 0;
  uint64_t total = 0;
  for (const auto& e : elements) {
    // Every element takes at least one byte in any encoding.
    if (e.count > body)
      throw SceneLoadError(fmt::format("{}: PLY header declares {} {} elements, but only {} bytes follow it", path,
                                       e.count, e.name, body));
    total += e.count;
  }
  if (format.rfind("binary", 0) == 0) {
    uint64_t need = 0;
    for (const auto& e : elements) need += e.count * e.min_bytes;
    if (need > body)
      throw SceneLoadError(fmt::format("{}: truncated binary PLY: the header declares at least {} bytes of data, the file has {}",
                                       path, need, body));
  } else if (format == "ascii") {
    const uint64_t lines = count_data_lines(in, total);
    if (lines < total)
      throw SceneLoadError(fmt::format("{}: truncated ASCII PLY: the header declares {} element lines, the file has {}", path,
                                       total, lines));
  }
}

// Reads the next data line (not blank, not a comment); false at the end.
bool next_data_line(std::istream& in, std::string& line, uint64_t& line_no) {
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
  }
  return false;
}

// OFF files declare their counts; Assimp 5.2 clamps out-of-range indices and
// reads past short face records silently, so the whole file is checked here
// (line by line, as Assimp reads it): counts, vertex coordinates, face sizes
// and indices.
void precheck_off(const std::string& path, uint64_t file_size) {
  std::ifstream in(path);
  std::string line;
  uint64_t line_no = 0;
  std::vector<uint64_t> counts;
  bool keyword = false;
  while (counts.size() < 2 && next_data_line(in, line, line_no)) {
    std::istringstream ls(line);
    std::string word;
    while (ls >> word) {
      if (!keyword && word.find("OFF") != std::string::npos) {
        keyword = true;
        continue;
      }
      uint64_t v = 0;
      const auto [p, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
      if (!keyword || ec != std::errc() || p != word.data() + word.size())
        throw SceneLoadError(fmt::format("{}: line {}: OFF header has an invalid count '{}'", path, line_no, word));
      counts.push_back(v);
    }
  }
  if (!keyword || counts.size() < 2) throw SceneLoadError(fmt::format("{}: not an OFF file (no OFF header with counts)", path));
  const uint64_t nv = counts[0], nf = counts[1];
  if (nv + nf > file_size)
    throw SceneLoadError(fmt::format("{}: OFF header declares {} vertices and {} faces, but the file has only {} bytes", path,
                                     nv, nf, file_size));
  auto truncated = [&](const char* what, uint64_t have, uint64_t want) {
    return SceneLoadError(fmt::format("{}: truncated OFF file: {} {} declared, {} present", path, want, what, have));
  };
  for (uint64_t i = 0; i < nv; ++i) {
    if (!next_data_line(in, line, line_no)) throw truncated("vertices", i, nv);
    const char* p = line.data();
    const char* end = line.data() + line.size();
    for (int k = 0; k < 3; ++k) {
      while (p < end && (*p == ' ' || *p == '\t')) ++p;
      if (p < end && *p == '+') ++p;  // from_chars takes no plus sign
      float x = 0;
      const auto [q, ec] = std::from_chars(p, end, x);
      if (ec != std::errc() || (q < end && *q != ' ' && *q != '\t' && *q != '\r'))
        throw SceneLoadError(fmt::format("{}: line {}: vertex {} needs 3 numbers: '{}'", path, line_no, i, line));
      if (!std::isfinite(x))
        throw SceneLoadError(fmt::format("{}: line {}: vertex {} has a non-finite coordinate", path, line_no, i));
      p = q;
    }
  }
  for (uint64_t f = 0; f < nf; ++f) {
    if (!next_data_line(in, line, line_no)) throw truncated("faces", f, nf);
    std::istringstream ls(line);
    std::string word;
    auto next_index = [&](uint64_t& v) {
      if (!(ls >> word)) return false;
      const auto [p, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
      if (ec != std::errc() || p != word.data() + word.size())
        throw SceneLoadError(fmt::format("{}: line {}: face {}: '{}' is not a vertex index", path, line_no, f, word));
      return true;
    };
    uint64_t n = 0;
    next_index(n);
    for (uint64_t k = 0; k < n; ++k) {
      uint64_t v = 0;
      if (!next_index(v))
        throw SceneLoadError(fmt::format("{}: line {}: face {} declares {} vertices but lists {}", path, line_no, f, n, k));
      if (v >= nv)
        throw SceneLoadError(fmt::format("{}: line {}: face {} refers to vertex {}, but the file declares {} vertices (index out of range)",
                                         path, line_no, f, v, nv));
    }
  }
}

// A binary STL is an 80-byte header, a triangle count and 50 bytes per
// triangle; an ASCII STL starts with "solid" and ends with "endsolid". Some
// binary headers start with "solid" too, so the size decides first.
void precheck_stl(const std::string& path, uint64_t file_size) {
  std::ifstream in(path, std::ios::binary);
  char head[84] = {};
  in.read(head, sizeof head);
  const auto got = static_cast<uint64_t>(in.gcount());
  if (got == 84) {
    uint32_t count = 0;
    std::memcpy(&count, head + 80, 4);
    if (84 + 50ull * count == file_size) return;  // a complete binary STL
  }
  std::string start(head, got);
  const auto first = start.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && start.compare(first, 5, "solid") == 0) {
    // ASCII: the last word of the file must close the solid.
    const uint64_t tail_bytes = std::min<uint64_t>(file_size, 4096);
    std::string tail(tail_bytes, '\0');
    in.clear();
    in.seekg(static_cast<std::streamoff>(file_size - tail_bytes));
    in.read(tail.data(), static_cast<std::streamsize>(tail_bytes));
    tail.resize(static_cast<size_t>(in.gcount()));
    const auto last = tail.find_last_not_of(" \t\r\n");
    const auto line_start = last == std::string::npos ? std::string::npos : tail.find_last_of("\n", last);
    const std::string last_line = last == std::string::npos ? "" : tail.substr(line_start == std::string::npos ? 0 : line_start + 1);
    if (last_line.find("endsolid") == std::string::npos)
      throw SceneLoadError(fmt::format("{}: truncated ASCII STL: the file does not end with 'endsolid'", path));
    return;
  }
  if (got < 84)
    throw SceneLoadError(fmt::format("{}: not an STL file: {} bytes, neither 'solid' text nor an 84-byte binary header", path, got));
  uint32_t count = 0;
  std::memcpy(&count, head + 80, 4);
  throw SceneLoadError(fmt::format("{}: truncated or malformed binary STL: the header declares {} triangles ({} bytes), the file has {} bytes",
                                   path, count, 84 + 50ull * count, file_size));
}

}  // namespace

void precheck_mesh_file(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return;
  const std::string ext = lower_extension(path);
  if (ext == ".ply") precheck_ply(path, size);
  else if (ext == ".off") precheck_off(path, size);
  else if (ext == ".stl") precheck_stl(path, size);
  else if (ext == ".gltf" || ext == ".glb") precheck_gltf(path, size);
}

}  // namespace raylab

#include "scenes/mesh_precheck.h"

#include <algorithm>
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

void precheck_off(const std::string& path, uint64_t file_size) {
  std::ifstream in(path);
  std::string line;
  // Skip the OFF keyword line (it may also carry the counts) and comments.
  std::vector<uint64_t> counts;
  bool keyword = false;
  while (counts.size() < 2 && std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string word;
    while (ls >> word) {
      if (!keyword && word.find("OFF") != std::string::npos) {
        keyword = true;
        continue;
      }
      try {
        counts.push_back(std::stoull(word));
      } catch (const std::exception&) {
        throw SceneLoadError(fmt::format("{}: OFF header has an invalid count '{}'", path, word));
      }
    }
  }
  if (!keyword || counts.size() < 2) throw SceneLoadError(fmt::format("{}: not an OFF file (no OFF header with counts)", path));
  const uint64_t total = counts[0] + counts[1];
  if (total > file_size)
    throw SceneLoadError(fmt::format("{}: OFF header declares {} vertices and {} faces, but the file has only {} bytes", path,
                                     counts[0], counts[1], file_size));
  const uint64_t lines = count_data_lines(in, total);
  if (lines < total)
    throw SceneLoadError(fmt::format("{}: truncated OFF file: {} vertex and face lines declared, {} present", path, total, lines));
}

}  // namespace

void precheck_mesh_file(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return;
  const std::string ext = lower_extension(path);
  if (ext == ".ply") precheck_ply(path, size);
  else if (ext == ".off") precheck_off(path, size);
}

}  // namespace raylab

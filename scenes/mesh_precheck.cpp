#include "scenes/mesh_precheck.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
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
      auto known = [&](const std::string& t) {
        if (ply_type_size(t) == 0)
          throw SceneLoadError(fmt::format("{}: PLY header: a property of element '{}' has unknown type '{}'", path,
                                           elements.back().name, t));
        return static_cast<uint64_t>(ply_type_size(t));
      };
      if (type == "list") {
        std::string count_type, item_type;
        ls >> count_type >> item_type;
        elements.back().min_bytes += known(count_type);
        const uint64_t item = known(item_type);
        // A face's index list needs three entries to make a triangle.
        if (elements.back().name == "face") elements.back().min_bytes += 3u * item;
      } else {
        elements.back().min_bytes += known(type);
      }
    } else if (word == "end_header") {
      ended = true;
      break;
    }
  }
  if (!ended) throw SceneLoadError(fmt::format("{}: PLY header has no end_header (truncated or not a PLY file)", path));
  const auto face = std::find_if(elements.begin(), elements.end(), [](const Element& e) { return e.name == "face"; });
  if (face == elements.end()) throw SceneLoadError(fmt::format("{}: contains no triangles (no face element: a point cloud?)", path));
  if (face->count == 0) throw SceneLoadError(fmt::format("{}: contains no triangles (the header declares 0 faces)", path));
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
      if (!keyword) throw SceneLoadError(fmt::format("{}: not an OFF file (line {} comes before any OFF keyword)", path, line_no));
      uint64_t v = 0;
      const auto [p, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
      if (ec != std::errc() || p != word.data() + word.size())
        throw SceneLoadError(fmt::format("{}: line {}: OFF header has an invalid count '{}'", path, line_no, word));
      counts.push_back(v);
    }
  }
  if (!keyword || counts.size() < 2) throw SceneLoadError(fmt::format("{}: not an OFF file (no OFF header with counts)", path));
  const uint64_t nv = counts[0], nf = counts[1];
  if (nf == 0) throw SceneLoadError(fmt::format("{}: contains no triangles (the header declares 0 faces)", path));
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
    if (84 + 50ull * count == file_size) {  // a complete binary STL
      if (count == 0) throw SceneLoadError(fmt::format("{}: contains no triangles (the header declares 0)", path));
      return;
    }
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
    // At least one facet (looked for at the start; an ASCII facet is < 300 bytes).
    std::string body(std::min<uint64_t>(file_size, 4096), '\0');
    in.clear();
    in.seekg(0);
    in.read(body.data(), static_cast<std::streamsize>(body.size()));
    body.resize(static_cast<size_t>(in.gcount()));
    if (body.find("facet") == std::string::npos && body.find("FACET") == std::string::npos)
      throw SceneLoadError(fmt::format("{}: contains no triangles (no facet in the solid)", path));
    return;
  }
  if (got < 84)
    throw SceneLoadError(fmt::format("{}: not an STL file: {} bytes, neither 'solid' text nor an 84-byte binary header", path, got));
  uint32_t count = 0;
  std::memcpy(&count, head + 80, 4);
  throw SceneLoadError(fmt::format("{}: truncated or malformed binary STL: the header declares {} triangles ({} bytes), the file has {} bytes",
                                   path, count, 84 + 50ull * count, file_size));
}

// OBJ files declare nothing, so the check reads the file once (mapped, no
// copy) and looks at what Assimp 5.2 would get wrong or report obscurely:
// vertex records with fewer than 3 numbers or non-finite ones, numbers
// Assimp cannot read (a leading decimal point: it then drops the vertex and
// reports an index error), face records with fewer than 3 vertices, index 0,
// indices beyond the vertex list, and files without any face.
class ObjChecker {
 public:
  ObjChecker(const std::string& path, const char* data, size_t size) : path_(path), p_(data), end_(data + size) {}

  void run() {
    uint64_t max_index = 0, max_index_line = 0, faces = 0;
    while (p_ < end_) {
      ++line_no_;
      const char* line_end = static_cast<const char*>(std::memchr(p_, '\n', static_cast<size_t>(end_ - p_)));
      if (!line_end) line_end = end_;
      const char* q = skip_blanks(p_, line_end);
      // Line continuations ('\' at the end) are rare; leave such files to Assimp.
      if (line_end > p_ && (line_end[-1] == '\\' || (line_end[-1] == '\r' && line_end - 1 > p_ && line_end[-2] == '\\'))) return;
      if (q + 1 < line_end && q[0] == 'v' && (q[1] == ' ' || q[1] == '\t')) {
        check_vertex(q + 2, line_end);
        ++vertices_;
      } else if (q + 1 < line_end && q[0] == 'f' && (q[1] == ' ' || q[1] == '\t')) {
        check_face(q + 2, line_end, max_index, max_index_line);
        ++faces;
      }
      p_ = line_end + 1;
    }
    if (faces == 0) fail_file("contains no triangles (no 'f' face records)");
    if (max_index > vertices_)
      fail(max_index_line, fmt::format("a face refers to vertex {}, but the file has {} vertices (index out of range)", max_index, vertices_));
  }

 private:
  static const char* skip_blanks(const char* p, const char* end) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    return p;
  }
  static const char* token_end(const char* p, const char* end) {
    while (p < end && *p != ' ' && *p != '\t' && *p != '\r') ++p;
    return p;
  }
  [[noreturn]] void fail(uint64_t line, const std::string& what) const {
    throw SceneLoadError(fmt::format("{}: line {}: {}", path_, line, what));
  }
  [[noreturn]] void fail_file(const std::string& what) const { throw SceneLoadError(fmt::format("{}: {}", path_, what)); }

  void check_vertex(const char* p, const char* end) {
    int numbers = 0;
    double w = 1.0;
    for (p = skip_blanks(p, end); p < end; p = skip_blanks(p, end)) {
      const char* t = token_end(p, end);
      const std::string_view token(p, static_cast<size_t>(t - p));
      if (token[0] == '#') break;
      if (token[0] == '.')
        fail(line_no_, fmt::format("number '{}' starts with a decimal point, which the importer (Assimp 5.2) cannot read; write 0{}",
                                   token, token));
      const char* num = token[0] == '+' ? p + 1 : p;  // from_chars takes no plus sign
      double x = 0;
      const auto [after, ec] = std::from_chars(num, t, x);
      // Assimp reads the longest numeric prefix ("3.1+e2" is 3.1); so do we.
      if (after == num) {
        if (numbers >= 3) break;  // trailing words after the coordinates
        fail(line_no_, fmt::format("vertex {} needs 3 numbers, '{}' is not a number", vertices_ + 1, token));
      }
      if (ec == std::errc::result_out_of_range ? std::abs(std::strtod(std::string(num, t).c_str(), nullptr)) > 1.0
                                               : !std::isfinite(static_cast<float>(x)))
        fail(line_no_, fmt::format("vertex {} has a non-finite coordinate '{}'", vertices_ + 1, token));
      if (numbers == 3) w = x;
      ++numbers;
      p = t;
    }
    if (numbers < 3) fail(line_no_, fmt::format("vertex {} needs 3 numbers, has {}", vertices_ + 1, numbers));
    // "v x y z w": the OBJ format makes w a weight of rational curves, but
    // Assimp 5.2 divides x, y and z by it; rather than a silently distorted
    // mesh, say so. (Six numbers are x y z and a colour: fine.)
    if (numbers == 4 && w != 1.0)
      fail(line_no_, fmt::format("vertex {} has a 4th (w) component {}, by which the importer (Assimp 5.2) would divide "
                                 "its coordinates (in OBJ, w only weights rational curves); remove it",
                                 vertices_ + 1, w));
  }

  void check_face(const char* p, const char* end, uint64_t& max_index, uint64_t& max_index_line) {
    int corners = 0;
    for (p = skip_blanks(p, end); p < end; p = skip_blanks(p, end)) {
      const char* t = token_end(p, end);
      if (*p == '#') break;
      int64_t index = 0;
      const char* num = *p == '+' ? p + 1 : p;
      const auto [after, ec] = std::from_chars(num, t, index);
      if (ec != std::errc() || (after != t && *after != '/'))
        fail(line_no_, fmt::format("'{}' is not a vertex index", std::string_view(p, static_cast<size_t>(t - p))));
      if (index == 0) fail(line_no_, "face index 0 (OBJ indices start at 1)");
      if (index < 0) {
        if (static_cast<uint64_t>(-index) > vertices_)
          fail(line_no_, fmt::format("relative index {} reaches before the first vertex ({} vertices so far)", index, vertices_));
      } else if (static_cast<uint64_t>(index) > max_index) {
        max_index = static_cast<uint64_t>(index);
        max_index_line = line_no_;
      }
      ++corners;
      p = t;
    }
    if (corners < 3) fail(line_no_, fmt::format("face with {} {} (a face needs at least 3; truncated?)", corners, corners == 1 ? "vertex" : "vertices"));
  }

  const std::string& path_;
  const char* p_;
  const char* end_;
  uint64_t line_no_ = 0, vertices_ = 0;
};

void precheck_obj(const std::string& path, uint64_t file_size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;  // the loader reports unreadable files
  void* map = ::mmap(nullptr, file_size, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) return;
  struct Unmap {
    void* p;
    size_t n;
    ~Unmap() { ::munmap(p, n); }
  } unmap{map, file_size};
  const auto* bytes = static_cast<const unsigned char*>(map);
  if (file_size >= 2 && ((bytes[0] == 0xFE && bytes[1] == 0xFF) || (bytes[0] == 0xFF && bytes[1] == 0xFE)))
    throw SceneLoadError(fmt::format("{}: UTF-16 text, from which the importer (Assimp 5.2) reads no geometry; "
                                     "convert it to UTF-8 (iconv -f UTF-16 -t UTF-8)", path));
  size_t skip = file_size >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF ? 3 : 0;  // UTF-8 mark
  ObjChecker(path, static_cast<const char*>(map) + skip, file_size - skip).run();
}

}  // namespace

void precheck_mesh_file(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return;
  const std::string ext = lower_extension(path);
  // A UTF-16 byte order mark: Assimp 5.2's text readers (OBJ, DAE, AC, NFF,
  // X, ...) read no geometry from it and report "malformed XML" or nothing.
  // Binary STL is skipped: its 80-byte header may start with any bytes.
  if (ext != ".stl" && size >= 2) {
    unsigned char mark[2] = {0, 0};
    if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
      const size_t got = std::fread(mark, 1, 2, f);
      std::fclose(f);
      if (got == 2 && ((mark[0] == 0xFE && mark[1] == 0xFF) || (mark[0] == 0xFF && mark[1] == 0xFE)))
        throw SceneLoadError(fmt::format("{}: UTF-16 text, from which the importer (Assimp 5.2) reads no geometry; "
                                         "convert it to UTF-8 (iconv -f UTF-16 -t UTF-8)", path));
    }
  }
  if (ext == ".ply") precheck_ply(path, size);
  else if (ext == ".off") precheck_off(path, size);
  else if (ext == ".stl") precheck_stl(path, size);
  else if (ext == ".obj") precheck_obj(path, size);
  else if (ext == ".gltf" || ext == ".glb") precheck_gltf(path, size);
}

}  // namespace raylab

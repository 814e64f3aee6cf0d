// A structure includes another structure only when it is built from it; every tool two
// structures use lives in accel/core/. This test holds the allow-list of "built from"
// includes and scans accel/ for any other include that crosses from one structure's folder
// into another's (accel/core/ includes no structure at all). accel/registry.cpp, which names
// every structure, and the headers at the top of accel/ are not structures.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;

// (structure, structure it is built from).
const std::set<std::pair<std::string, std::string>> kBuiltFrom = {
    {"bsp", "kdtree"},           // a BSP tree generalises the k-d tree: its walk, leaf blocks, build options
    {"hybrid", "bvh"},           // grid cells holding BVHs (inner=bvh)
    {"hybrid", "kdtree"},        // grid cells holding k-d trees (inner=kdtree, entry)
    {"loose_octree", "octree"},  // the octree's nodes, temporary tree, parameters and leaf blocks
};

struct CrossInclude {
  std::string file;      // relative to the source root, e.g. accel/hgrid/hgrid.h
  std::string from, to;  // the including and the included folder under accel/
  std::string included;  // the include's path
};

// The folder under accel/ of a path relative to the source root ("accel/grid/dda.h" -> "grid"),
// empty for a file at the top of accel/.
std::string structure_of(const std::string& path) {
  const auto first = path.find('/');
  const auto second = path.find('/', first + 1);
  return second == std::string::npos ? std::string() : path.substr(first + 1, second - first - 1);
}

// Every include in a folder under root/accel/ of a file in another folder under accel/ (core
// included on the including side only: core may include nothing from a structure).
std::vector<CrossInclude> cross_includes(const fs::path& root) {
  static const std::regex include_re(R"re(^\s*#\s*include\s*"(accel/[^"]+)")re");
  std::vector<CrossInclude> out;
  for (const auto& entry : fs::recursive_directory_iterator(root / "accel")) {
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".h" && ext != ".cpp")) continue;
    const std::string file = fs::relative(entry.path(), root).generic_string();
    const std::string from = structure_of(file);
    if (from.empty()) continue;  // accel/registry.cpp and the interface headers
    std::ifstream in(entry.path());
    std::string line;
    std::smatch m;
    while (std::getline(in, line)) {
      if (!std::regex_search(line, m, include_re)) continue;
      const std::string included = m[1];
      const std::string to = structure_of(included);
      if (!to.empty() && to != from && to != "core") out.push_back({file, from, to, included});
    }
  }
  std::sort(out.begin(), out.end(), [](const CrossInclude& a, const CrossInclude& b) {
    return std::tie(a.file, a.included) < std::tie(b.file, b.included);
  });
  return out;
}

bool allowed(const CrossInclude& c) { return kBuiltFrom.count({c.from, c.to}) != 0; }

TEST(StructureIncludes, OnlyStructuresBuiltFromAnotherIncludeIt) {
  const auto includes = cross_includes(RAYLAB_SOURCE_DIR);
  for (const CrossInclude& c : includes)
    EXPECT_TRUE(allowed(c)) << c.file << " includes " << c.included << ": " << c.from
                            << " is not built from " << c.to
                            << " (move the shared tool to accel/core/, or add the pair to kBuiltFrom"
                               " if one structure really is built from the other)";
}

// The allow-list states only what is true: every pair is used.
TEST(StructureIncludes, EveryAllowedPairIsUsed) {
  std::set<std::pair<std::string, std::string>> used;
  for (const CrossInclude& c : cross_includes(RAYLAB_SOURCE_DIR)) used.insert({c.from, c.to});
  for (const auto& pair : kBuiltFrom) EXPECT_TRUE(used.count(pair)) << pair.first << " -> " << pair.second;
}

// The scan on a made-up tree: an include into another structure is found, one into core, one
// inside a structure and the registry's are not.
TEST(StructureIncludes, ScanFindsAnIncludeIntoAnotherStructure) {
  const fs::path root = test::temp_dir("structure_includes");
  const auto write = [&](const std::string& path, const std::string& text) {
    fs::create_directories((root / path).parent_path());
    std::ofstream(root / path) << text;
  };
  write("accel/registry.cpp", "#include \"accel/octree/octree_accel.h\"\n");
  write("accel/octree/octree_accel.h", "#include \"accel/core/hit_recorder.h\"\n#include \"accel/octree/octree_node.h\"\n");
  write("accel/octree/build_octree.cpp", "// text\n  #include \"accel/grid/cell_lists.h\"  // a comment\n");
  write("accel/core/dda.h", "#include \"accel/grid/dda_grid.h\"\n");
  const auto found = cross_includes(root);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].file, "accel/core/dda.h");
  EXPECT_EQ(found[0].to, "grid");
  EXPECT_EQ(found[1].file, "accel/octree/build_octree.cpp");
  EXPECT_EQ(found[1].included, "accel/grid/cell_lists.h");
  EXPECT_FALSE(allowed(found[1]));
  fs::remove_all(root);
}

}  // namespace
}  // namespace raylab

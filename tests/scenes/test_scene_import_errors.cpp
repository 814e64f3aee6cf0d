// Every importer error case, format by format, with files the tests write
// themselves: unreadable, malformed, truncated, empty, NaN coordinates,
// indices out of range. Each must give one clear message naming the file and
// the problem, through the API (SceneLoadError) and the CLI (exit code 2,
// one line on stderr).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scenes/mesh_import.h"
#include "tests/scene_test_files.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

struct BadFile {
  std::string name;     // file name (the extension picks the format)
  std::string content;
  std::string expect;   // substring of the message, besides the file name
};

const std::string kPlyHead =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kStlFacet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";

std::vector<BadFile> bad_files() {
  std::vector<BadFile> c;
  // OBJ
  c.push_back({"empty.obj", "", "file is empty"});
  c.push_back({"comments_only.obj", "# nothing here\n", "no triangles"});
  c.push_back({"malformed.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", "line 2"});
  c.push_back({"short_vertex.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "needs 3 numbers"});
  c.push_back({"truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 3 2", "face with 2 vertices"});
  c.push_back({"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"});
  c.push_back({"inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n", "non-finite"});
  c.push_back({"overflow.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"});
  c.push_back({"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "index out of range"});
  c.push_back({"negative_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -7\n", "before the first vertex"});
  c.push_back({"zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "index 0"});
  c.push_back({"bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 b 3\n", "not a vertex index"});
  c.push_back({"lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n", "no triangles"});
  c.push_back({"leading_dot.obj", "v .5 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "decimal point"});
  c.push_back({"w_component.obj", "v 0 0 0\nv 1 0 0 0.5\nv 0 1 0\nf 1 2 3\n", "4th (w) component 0.5"});
  c.push_back({"utf16.obj", std::string("\xFF\xFEv\0 \0", 6), "UTF-16"});
  // PLY, ASCII
  c.push_back({"empty.ply", "", "file is empty"});
  c.push_back({"malformed.ply", kPlyHead + "0 0 0\nab 0 0\n0 1 0\n3 0 1 2\n", "malformed number 'ab'"});
  c.push_back({"truncated.ply", kPlyHead + "0 0 0\n1 0 0\n", "truncated ASCII PLY"});
  c.push_back({"no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "end_header"});
  c.push_back({"unknown_type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flot x\nend_header\n0\n", "unknown type 'flot'"});
  c.push_back({"nan.ply", kPlyHead + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "non-finite"});
  c.push_back({"range.ply", kPlyHead + "0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", "out of range"});
  c.push_back({"points.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n",
               "no triangles"});
  c.push_back({"absurd.ply",
               "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
               "4000000000"});
  // Absurd declared counts in the other formats with counts in a header.
  c.push_back({"absurd_vertices.off", "OFF\n4000000000 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "declares 4000000000 vertices"});
  c.push_back({"absurd_faces.off", "OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "4000000000 faces"});
  c.push_back({"absurd_bin.stl", std::string(80, '\0') + std::string(4, '\xFF') + std::string(50, '\0'),
               "declares 4294967295 triangles"});
  // PLY, binary
  const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::string good_bin = test::binary_ply(tri, {{0, 1, 2}});
  c.push_back({"truncated_bin.ply", good_bin.substr(0, good_bin.size() - 6), "truncated binary PLY"});
  c.push_back({"nan_bin.ply", test::binary_ply({0, 0, 0, std::nanf(""), 0, 0, 0, 1, 0}, {{0, 1, 2}}), "non-finite"});
  c.push_back({"range_bin.ply", test::binary_ply(tri, {{0, 1, 3}}), "out of range"});
  c.push_back({"negative_bin.ply", test::binary_ply(tri, {{0, 1, -1}}), "out of range"});
  // STL, ASCII and binary
  c.push_back({"empty.stl", "", "file is empty"});
  c.push_back({"truncated.stl", "solid t\n" + kStlFacet + "facet normal 0 0 1\nouter loop\nvertex 1 0", "endsolid"});
  c.push_back({"malformed.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 zz 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
               "malformed number 'zz'"});
  c.push_back({"nan.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
               "non-finite"});
  c.push_back({"no_facets.stl", "solid t\nendsolid t\n", "no triangles"});
  const std::string good_stl = test::binary_stl({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
  c.push_back({"truncated_bin.stl", good_stl.substr(0, good_stl.size() - 20), "truncated or malformed binary STL"});
  c.push_back({"nan_bin.stl", test::binary_stl({0, 0, 0, std::nanf(""), 0, 0, 0, 1, 0}), "non-finite"});
  c.push_back({"short.stl", "\x01\x02\x03", "not an STL file"});
  c.push_back({"zero_bin.stl", test::binary_stl({}), "no triangles"});
  // OFF
  c.push_back({"empty.off", "", "file is empty"});
  c.push_back({"no_header.off", "3 1\n0 0 0\n", "not an OFF file"});
  c.push_back({"malformed.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "line 4"});
  c.push_back({"truncated.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n", "truncated OFF"});
  c.push_back({"nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "non-finite"});
  c.push_back({"range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", "index out of range"});
  c.push_back({"short_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "declares 4 vertices but lists 3"});
  c.push_back({"no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no triangles"});
  // glTF 2.0
  test::GltfPrimitive quad;
  quad.xyz = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.indices = {0, 1, 2, 0, 2, 3};
  const std::string good_gltf = test::gltf_embedded({quad});
  c.push_back({"empty.gltf", "", "file is empty"});
  c.push_back({"malformed.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [", "malformed JSON"});
  c.push_back({"truncated.gltf", good_gltf.substr(0, good_gltf.size() / 2), "malformed JSON"});
  c.push_back({"version1.gltf", R"({"asset":{"version":"1.0"}})", "not a glTF 2.0 file"});
  c.push_back({"no_meshes.gltf", R"({"asset":{"version":"2.0"}})", "no triangles"});
  {
    nlohmann::json j = nlohmann::json::parse(good_gltf);
    j["buffers"][0]["byteLength"] = j["buffers"][0]["byteLength"].get<int>() + 100;
    c.push_back({"short_buffer.gltf", j.dump(), "truncated"});
    j = nlohmann::json::parse(good_gltf);
    j["accessors"][1]["count"] = 600;
    c.push_back({"accessor_overflow.gltf", j.dump(), "needs"});
  }
  test::GltfPrimitive bad_index = quad;
  bad_index.indices = {0, 1, 2, 0, 2, 9};
  c.push_back({"range.gltf", test::gltf_embedded({bad_index}), "index out of range"});
  test::GltfPrimitive nan_vertex = quad;
  nan_vertex.xyz[4] = std::nanf("");
  c.push_back({"nan.gltf", test::gltf_embedded({nan_vertex}), "non-finite"});
  const std::string good_glb = test::glb({quad});
  c.push_back({"truncated.glb", good_glb.substr(0, good_glb.size() - 10), "truncated GLB"});
  // Anything else
  c.push_back({"unsupported.xyz123", "hello", "unsupported file format"});
  return c;
}

TEST(SceneImportErrors, EveryFormatAndErrorGivesOneClearMessage) {
  const auto dir = test::temp_dir("import_errors");
  for (const auto& c : bad_files()) {
    const std::string path = test::write_file(dir, c.name, c.content);
    const std::string err = test::load_error(path);
    EXPECT_FALSE(err.empty()) << c.name << " loaded without error";
    EXPECT_THAT(err, HasSubstr(c.name)) << c.name;
    EXPECT_THAT(err, HasSubstr(c.expect)) << c.name;
    EXPECT_EQ(err.find('\n'), std::string::npos) << c.name << ": " << err;
  }
}

TEST(SceneImportErrors, CliExitsWithCode2AndOneLine) {
  const auto dir = test::temp_dir("import_errors_cli");
  for (const auto& c : bad_files()) {
    const std::string path = test::write_file(dir, c.name, c.content);
    const auto r = test::run_raylab("info --scene " + path);
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.output;
    EXPECT_THAT(r.output, ::testing::StartsWith("raylab info: error: " + path + ": ")) << c.name;
    EXPECT_THAT(r.output, HasSubstr(c.expect)) << c.name;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.name << ": " << r.output;
  }
}

TEST(SceneImportErrors, UnreadablePaths) {
  const auto dir = test::temp_dir("import_unreadable");
  EXPECT_THAT(test::load_error((dir / "missing.obj").string()), HasSubstr("missing.obj: no such file"));
  EXPECT_THAT(test::load_error(dir.string()), HasSubstr("is a directory"));
  // A symlink loop and a dangling link exist as names but cannot be opened (also as root).
  std::filesystem::create_symlink(dir / "loop_b.obj", dir / "loop_a.obj");
  std::filesystem::create_symlink(dir / "loop_a.obj", dir / "loop_b.obj");
  EXPECT_THAT(test::load_error((dir / "loop_a.obj").string()), HasSubstr("loop_a.obj: cannot open for reading"));
  std::filesystem::create_symlink(dir / "nowhere.obj", dir / "dangling.obj");
  EXPECT_THAT(test::load_error((dir / "dangling.obj").string()), HasSubstr("dangling.obj: cannot open for reading"));
  // Without read permission (root reads anyway, so only checked for other users).
  const std::string locked = test::write_file(dir, "locked.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ::chmod(locked.c_str(), 0);
  if (::geteuid() != 0) {
    EXPECT_THAT(test::load_error(locked), HasSubstr("locked.obj: cannot open for reading"));
  }
  const auto r = test::run_raylab("info --scene " + (dir / "loop_a.obj").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace raylab

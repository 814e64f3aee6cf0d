// Mesh validation and import through Assimp: each format, each error case,
// with files the tests write themselves.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "scenes/mesh_import.h"
#include "scenes/scene_registry.h"
#include "tests/scene_test_files.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
using test::load_error;
using test::write_file;

const char* kCubeObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

TEST(MeshValidation, NamesTheFirstOffendingElement) {
  TriangleMesh m;
  m.vertices = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 9}};
  try {
    m.validate();
    FAIL();
  } catch (const MeshError& e) {
    EXPECT_THAT(e.what(), HasSubstr("triangle 1"));
    EXPECT_THAT(e.what(), HasSubstr("vertex 9"));
  }
  m.triangles = {{0, 1, 2}};
  m.vertices[2].z() = std::numeric_limits<float>::infinity();
  try {
    m.validate();
    FAIL();
  } catch (const MeshError& e) {
    EXPECT_THAT(e.what(), HasSubstr("vertex 2"));
  }
}

TEST(MeshImport, ObjQuadsAreTriangulated) {
  const auto dir = test::temp_dir("obj");
  const Scene s = load_mesh_file(write_file(dir, "cube.obj", kCubeObj));
  EXPECT_EQ(s.num_triangles(), 12u);
  EXPECT_EQ(s.bounds().lo, Vec3f(0, 0, 0));
  EXPECT_EQ(s.bounds().hi, Vec3f(1, 1, 1));
  EXPECT_EQ(s.material_ids.size(), 12u);
  EXPECT_GT(s.background.maxCoeff(), 0.0f);  // default sky light when the file has no emitters
}

TEST(MeshImport, AsciiAndBinaryPlyStlAndOff) {
  const auto dir = test::temp_dir("formats");
  const std::string ply_ascii =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
  std::string ply_bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float verts[9] = {0, 0, 0, 2, 0, 0, 0, 2, 0};
  ply_bin.append(reinterpret_cast<const char*>(verts), sizeof verts);
  ply_bin.push_back(3);
  const int32_t idx[3] = {0, 1, 2};
  ply_bin.append(reinterpret_cast<const char*>(idx), sizeof idx);
  const std::string stl =
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
      "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
  const std::string off = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
  EXPECT_EQ(load_mesh_file(write_file(dir, "a.ply", ply_ascii)).num_triangles(), 2u);
  const Scene b = load_mesh_file(write_file(dir, "b.ply", ply_bin));
  EXPECT_EQ(b.num_triangles(), 1u);
  EXPECT_EQ(b.bounds().hi, Vec3f(2, 2, 0));
  EXPECT_EQ(load_mesh_file(write_file(dir, "c.stl", stl)).num_triangles(), 2u);
  EXPECT_EQ(load_mesh_file(write_file(dir, "d.off", off)).num_triangles(), 2u);
}

TEST(MeshImport, ViewFileNextToTheMeshSetsTheCamera) {
  const auto dir = test::temp_dir("view");
  const std::string mesh = write_file(dir, "scene.obj", kCubeObj);
  write_file(dir, "scene.json", R"({"from":[5,6,7],"at":[0.5,0.5,0.5],"up":[0,0,1],"fov_deg":30,"width":320,"height":200})");
  const Scene s = load_mesh_file(mesh);
  EXPECT_EQ(s.view.from, Vec3f(5, 6, 7));
  EXPECT_EQ(s.view.up, Vec3f(0, 0, 1));
  EXPECT_EQ(s.view.fov_deg, 30.0f);
  EXPECT_EQ(s.view.width, 320);
  EXPECT_EQ(s.view.height, 200);
  write_file(dir, "scene.json", R"({"from":[5,6],"at":[0,0,0]})");
  EXPECT_THAT(load_error(mesh), HasSubstr("scene.json"));
}

TEST(MeshImport, ErrorsNameTheFileAndTheProblem) {
  const auto dir = test::temp_dir("errors");
  struct Case {
    std::string name, content, expect;
  };
  const std::vector<Case> cases = {
      {"empty.obj", "", "empty.obj"},
      {"garbage.ply", "this is not a mesh\n\x01\x02", "garbage.ply"},
      {"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\np 2\n", "no triangles"},
      {"lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n", "no triangles"},
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
      {"inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "non-finite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "range.obj"},
      {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "zero.obj"},
      {"truncated.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 300\nproperty float x\nproperty float y\n"
       "property float z\nelement face 100\nproperty list uchar int vertex_indices\nend_header\n\x01\x02\x03",
       "truncated.ply"},
      {"absurd.ply",
       "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
       "absurd.ply"},
      {"range.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n",
       "range.ply"},
      {"unsupported.xyz123", "hello", "unsupported.xyz123"},
  };
  for (const auto& c : cases) {
    const std::string path = write_file(dir, c.name, c.content);
    const std::string err = load_error(path);
    EXPECT_FALSE(err.empty()) << c.name << " loaded without error";
    EXPECT_THAT(err, HasSubstr(c.name)) << c.name;
    EXPECT_THAT(err, HasSubstr(c.expect)) << c.name;
  }
  EXPECT_THAT(load_error((dir / "does_not_exist.obj").string()), HasSubstr("no such file"));
  EXPECT_THAT(load_error(dir.string()), HasSubstr("directory"));
}

TEST(MeshImport, SharedScenesLoadWithManifestTriangleCounts) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  std::ifstream manifest(test::shared_dir() + "/scenes/MANIFEST.tsv");
  std::string line;
  std::getline(manifest, line);  // header
  int checked = 0;
  while (std::getline(manifest, line)) {
    std::stringstream ss(line);
    std::string name, file, tris;
    std::getline(ss, name, '\t');
    std::getline(ss, file, '\t');
    std::getline(ss, tris, '\t');
    if (std::stoul(tris) > 100000) continue;  // keep the test quick
    const Scene s = load_mesh_file(test::shared_dir() + "/scenes/" + file);
    // Assimp drops zero-area faces of OBJ files only when asked; counts must match.
    EXPECT_EQ(s.num_triangles(), std::stoul(tris)) << file;
    ++checked;
  }
  EXPECT_GE(checked, 5);
}

TEST(MeshImport, SharedInvalidFilesGiveErrorsNotCrashes) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  for (const auto& entry : std::filesystem::directory_iterator(test::shared_dir() + "/scenes/invalid/tinyobjloader")) {
    if (entry.path().extension() != ".obj") continue;
    try {
      const Scene s = load_mesh_file(entry.path().string());
      s.validate();  // whatever loads must be a valid mesh
    } catch (const SceneLoadError& e) {
      EXPECT_THAT(e.what(), HasSubstr(entry.path().filename().string()));
    }
  }
}

}  // namespace
}  // namespace raylab

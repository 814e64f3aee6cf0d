// The real meshes of ../shared/scenes (skipped when it is absent): every
// Standard Procedural Databases scene loads with its manifest's triangle
// count and its own viewpoint, and that viewpoint sees the scene; the
// awkward-but-valid files load, the invalid ones fail with a message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "accel/registry.h"
#include "scenes/mesh_import.h"
#include "scenes/scene_registry.h"
#include "tests/test_util.h"
#include "tracer/camera.h"

namespace raylab {
namespace {

std::vector<std::vector<std::string>> read_tsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, '\t');) cells.push_back(cell);
    if (!cells.empty()) rows.push_back(cells);
  }
  return rows;
}

Vec3f vec3(const nlohmann::json& j) { return Vec3f(j[0].get<float>(), j[1].get<float>(), j[2].get<float>()); }

// Primary rays through a 16x16 image of the scene's view (built with the
// default BVH) that hit something.
long hits_in_view(const Scene& s) {
  auto accel = make_accelerator("bvh");
  accel->build(s.mesh);
  View v = s.view;
  v.width = v.height = 16;
  const PinholeCamera cam(v);
  std::vector<Ray> rays;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) rays.push_back(cam.generate(x + 0.5f, y + 0.5f));
  std::vector<Hit> hits(rays.size());
  accel->intersect(rays, hits);
  return std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.valid(); });
}

TEST(SharedScenes, SpdScenesLoadWithTheirOwnViewpoints) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const std::string spd = test::shared_dir() + "/scenes/spd/";
  int checked = 0;
  for (const auto& row : read_tsv(spd + "MANIFEST.tsv")) {
    const std::string stem = row[0] + "_s" + row[1];
    SCOPED_TRACE(stem);
    const unsigned long triangles = std::stoul(row[4]);
    const Scene s = load_mesh_file(spd + stem + ".obj");
    EXPECT_EQ(s.num_triangles(), triangles);
    const nlohmann::json view = nlohmann::json::parse(std::ifstream(spd + stem + ".json"));
    EXPECT_EQ(s.view.from, vec3(view["from"]));
    EXPECT_EQ(s.view.at, vec3(view["at"]));
    EXPECT_EQ(s.view.up, vec3(view["up"]));
    EXPECT_EQ(s.view.fov_deg, view["fov_deg"].get<float>());
    EXPECT_EQ(s.view.width, view["width"].get<int>());
    if (triangles > 60000) {  // keep the test quick: the viewpoint check below builds a BVH
      ++checked;
      continue;
    }
    EXPECT_GT(hits_in_view(s), 10) << "the view misses the scene";
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(SharedScenes, SceneFilesForSharedMeshesLoadAndSeeTheirMeshes) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const std::filesystem::path dir = std::filesystem::path(RAYLAB_SOURCE_DIR) / "scenes" / "shared";
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    const Scene s = load_scene(entry.path().string());
    EXPECT_EQ(view_problem(s.view), "");
    EXPECT_TRUE(s.has_emitters() || s.background.maxCoeff() > 0.0f);
    if (s.num_triangles() < 100000) {  // the viewpoint check builds a BVH: small ones only
      EXPECT_GT(hits_in_view(s), 128);
    }
    ++checked;
  }
  EXPECT_GE(checked, 4);
}

TEST(SharedScenes, AwkwardButValidFilesLoadAndPointCloudsAreRefused) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const std::string dir = test::shared_dir() + "/scenes/edgecases/";
  const std::vector<std::pair<std::string, size_t>> valid = {
      {"box_longline.obj", 944}, {"box_without_lineending.obj", 12}, {"concave_polygon.obj", 64}, {"cube_binary.ply", 12},
      {"float-color.ply", 1},    {"multiple_spaces.obj", 1},          {"number_formats.obj", 1}};
  for (const auto& [file, tris] : valid) EXPECT_EQ(load_mesh_file(dir + file).num_triangles(), tris) << file;
  for (const std::string file : {"point_cloud.obj", "points.ply", "testline.obj", "testpoints.obj", "issue623.ply"}) {
    try {
      load_mesh_file(dir + file);
      ADD_FAILURE() << file << " has no triangles but loaded";
    } catch (const SceneLoadError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("no triangles")) << file;
    }
  }
  // Assimp 5.2 reads no geometry from UTF-16 text: a clear refusal, not an obscure one.
  try {
    load_mesh_file(dir + "box_UTF16BE.obj");
    ADD_FAILURE() << "UTF-16 file loaded";
  } catch (const SceneLoadError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("UTF-16"));
  }
  // The original Cornell box OBJ with its MTL: materials arrive, the light emits.
  const Scene cornell = load_mesh_file(test::shared_dir() + "/scenes/extras/CornellBox-Original.obj");
  EXPECT_TRUE(cornell.has_emitters());
  EXPECT_GT(cornell.materials.size(), 3u);
}

TEST(SharedScenes, InvalidFilesNameTheLineOfTheProblem) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const std::string dir = test::shared_dir() + "/scenes/invalid/tinyobjloader/";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"invalid-face-definition.obj", "line 15: face with 1 vertex"},
      {"invalid-relative-vertex-index.obj", "line 1: relative index -4"},
      {"invalid-relative-texture-index.obj", "index out of range"},
      {"issue-140-zero-face-idx.obj", "face index 0"},
      {"test-nan.obj", "non-finite"},
      {"line-prim.obj", "no triangles"},
      {"points-prim.obj", "no triangles"},
  };
  for (const auto& [file, expect] : cases) {
    try {
      load_mesh_file(dir + file);
      ADD_FAILURE() << file << " loaded";
    } catch (const SceneLoadError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr(file)) << file;
      EXPECT_THAT(e.what(), ::testing::HasSubstr(expect)) << file;
    }
  }
}

}  // namespace
}  // namespace raylab

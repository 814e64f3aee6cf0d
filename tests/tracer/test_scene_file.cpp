// JSON scene files: meshes from files and generators, transforms (order,
// Euler convention, mirroring), materials, camera and background; every
// error names the file and the JSON pointer; the shipped examples load and
// their cameras see their geometry.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "scenes/mesh_import.h"
#include "scenes/scene_file.h"
#include "scenes/scene_registry.h"
#include "tests/scene_test_files.h"
#include "tests/test_util.h"
#include "tests/tracer_test_util.h"
#include "tracer/camera.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

std::string scene_error(const std::string& path) {
  return test::load_error_of([&] { load_scene_file(path); });
}

bool near(const Vec3f& a, const Vec3f& b, float tol = 1e-5f) { return (a - b).cwiseAbs().maxCoeff() <= tol; }

Vec3f triangle_normal(const Scene& s, size_t t) {
  return (s.mesh.vertex(t, 1) - s.mesh.vertex(t, 0)).cross(s.mesh.vertex(t, 2) - s.mesh.vertex(t, 0)).normalized();
}

double hit_fraction(const Scene& s) {
  auto accel = make_accelerator("bvh");
  accel->build(s.mesh);
  return test::camera_hit_fraction(s, *accel);
}

TEST(SceneFile, TransformsApplyScaleThenRotateThenTranslate) {
  const auto dir = test::temp_dir("scenefile_xf");
  const std::string path = test::write_file(dir, "s.json", R"({
    "meshes": [{"generator": "box",
                "transform": {"scale": [2, 1, 1], "rotate": {"axis": [0, 1, 0], "degrees": 90}, "translate": [10, 0, 0]}}]})");
  const Scene s = load_scene_file(path);
  ASSERT_EQ(s.num_triangles(), 12u);
  // x in [-1, 1] after scaling; a right-handed quarter turn about y sends x to -z.
  EXPECT_TRUE(near(s.bounds().lo, Vec3f(9.5f, -0.5f, -1.0f)));
  EXPECT_TRUE(near(s.bounds().hi, Vec3f(10.5f, 0.5f, 1.0f)));
}

TEST(SceneFile, EulerAnglesRotateAboutXThenYThenZAndMirrorsKeepFrontFaces) {
  const auto dir = test::temp_dir("scenefile_euler");
  // The plane faces +y. Rx(90) turns +y into +z; then Ry(90) turns +z into +x.
  const Scene a = load_scene_file(test::write_file(dir, "a.json", R"({"meshes": [{"generator": "plane", "transform": {"rotate": [90, 0, 0]}}]})"));
  EXPECT_TRUE(near(triangle_normal(a, 0), Vec3f(0, 0, 1)));
  const Scene b = load_scene_file(test::write_file(dir, "b.json", R"({"meshes": [{"generator": "plane", "transform": {"rotate": [90, 90, 0]}}]})"));
  EXPECT_TRUE(near(triangle_normal(b, 0), Vec3f(1, 0, 0)));
  // A mirroring scale flips the winding back: the plane still faces +y.
  const Scene m = load_scene_file(test::write_file(dir, "m.json", R"({"meshes": [{"generator": "plane", "transform": {"scale": [-1, 1, 1]}}]})"));
  EXPECT_TRUE(near(triangle_normal(m, 0), Vec3f(0, 1, 0)));
  // Uniform scale by a number.
  const Scene u = load_scene_file(test::write_file(dir, "u.json", R"({"meshes": [{"generator": "box", "transform": {"scale": 4}}]})"));
  EXPECT_TRUE(near(u.bounds().hi, Vec3f(2, 2, 2)));
}

TEST(SceneFile, MaterialsCameraBackgroundAndRelativeFiles) {
  const auto dir = test::temp_dir("scenefile_mat");
  std::filesystem::create_directories(dir / "models");
  test::write_file(dir / "models", "tri.obj", "v 0 0 5\nv 1 0 5\nv 0 1 5\nf 1 2 3\n");
  const std::string path = test::write_file(dir, "s.json", R"({
    "camera": {"from": [0, 0, 20], "at": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 30, "width": 64, "height": 48},
    "background": [0.1, 0.2, 0.3],
    "materials": {"lamp": {"diffuse": 0.5, "emission": [4, 3, 2]}, "red": {"diffuse": [0.9, 0.1, 0.1]}},
    "meshes": [
      {"generator": "box", "material": "red"},
      {"file": "models/tri.obj", "material": "lamp"},
      {"generator": "plane", "material": {"diffuse": [0.2, 0.4, 0.6]}, "transform": {"translate": [0, -3, 0]}}
    ]})");
  const Scene s = load_scene_file(path);
  ASSERT_EQ(s.num_triangles(), 12u + 1u + 2u);
  EXPECT_TRUE(near(s.material_of(0).albedo, Vec3f(0.9f, 0.1f, 0.1f)));
  EXPECT_TRUE(near(s.material_of(12).emission, Vec3f(4, 3, 2)));
  EXPECT_TRUE(near(s.material_of(12).albedo, Vec3f::Constant(0.5f)));
  EXPECT_EQ(s.mesh.vertex(12, 0), Vec3f(0, 0, 5));  // the file, relative to the scene file's folder
  EXPECT_TRUE(near(s.material_of(13).albedo, Vec3f(0.2f, 0.4f, 0.6f)));
  EXPECT_EQ(s.view.from, Vec3f(0, 0, 20));
  EXPECT_EQ(s.view.fov_deg, 30.0f);
  EXPECT_EQ(s.view.width, 64);
  EXPECT_EQ(s.view.height, 48);
  EXPECT_TRUE(near(s.background, Vec3f(0.1f, 0.2f, 0.3f)));
  // load_scene dispatches .json paths here.
  EXPECT_EQ(load_scene(path).num_triangles(), 15u);
  // A scene file named like its mesh (tri.json beside tri.obj) is not taken for the mesh's view file.
  const std::string same = test::write_file(dir / "models", "tri.json", R"({"meshes": [{"file": "tri.obj"}]})");
  EXPECT_EQ(load_scene(same).num_triangles(), 1u);
}

TEST(SceneFile, DefaultsFrameTheSceneAndLightItWithASkyUnlessItEmits) {
  const auto dir = test::temp_dir("scenefile_defaults");
  const Scene sky = load_scene_file(test::write_file(dir, "a.json", R"({"meshes": [{"generator": "sphere:segments=8,rings=4"}]})"));
  EXPECT_EQ(sky.background, Vec3f::Constant(1.0f));
  EXPECT_EQ(sky.view.at, sky.bounds().center());
  EXPECT_GT(hit_fraction(sky), 0.05);
  const Scene lit = load_scene_file(test::write_file(dir, "b.json", R"({"meshes": [{"generator": "cornell"}]})"));
  EXPECT_EQ(lit.background, Vec3f::Zero());
  EXPECT_TRUE(lit.has_emitters());  // the generator's own materials are kept
  // Generator parameters from "params" and from the spec string combine.
  const Scene p = load_scene_file(test::write_file(dir, "c.json",
      R"({"meshes": [{"generator": "sphere:segments=8", "params": {"rings": 4}}]})"));
  EXPECT_EQ(p.num_triangles(), 2u * 8u * 3u);
}

TEST(SceneFile, ErrorsNameTheFileAndTheJsonPointer) {
  const auto dir = test::temp_dir("scenefile_errors");
  const std::string box = R"({"generator": "box"})";
  struct Case {
    std::string json, expect;
  };
  const std::vector<Case> cases = {
      {R"({"meshes": [)" + box + R"(, {"generator": "box", "transform": {"scale": "big"}}]})",
       "/meshes/1/transform/scale: expected a number or an array of 3 numbers"},
      {R"({"meshes": [)" + box + R"(], "lights": []})", "/lights: unknown key"},
      {R"({"meshes": [{"generator": "box", "colour": [1, 0, 0]}]})", "/meshes/0/colour: unknown key"},
      {R"({"meshes": [{"generator": "box", "transform": {"shear": 1}}]})", "/meshes/0/transform/shear: unknown key"},
      {R"({"meshes": [{"generator": "box", "transform": {"rotate": {"axis": [0, 1, 0], "deg": 3}}}]})", "/meshes/0/transform/rotate/deg: unknown key"},
      {R"({"meshes": [{"generator": "box", "transform": {"rotate": {"axis": [0, 0, 0], "degrees": 3}}}]})", "/meshes/0/transform/rotate/axis: the axis must not be the zero vector"},
      {R"({"meshes": [{"generator": "box", "transform": {"rotate": 30}}]})", "/meshes/0/transform/rotate: expected"},
      {R"({"meshes": [{"generator": "box", "transform": {"scale": [1, 0, 1]}}]})", "/meshes/0/transform/scale: scale factors must be non-zero"},
      {R"({"meshes": [{"generator": "box", "transform": {"translate": [1, 2]}}]})", "/meshes/0/transform/translate: expected an array of 3 numbers"},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5]}})", "/camera: missing \"at\""},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5], "at": [0, 0, 0], "fov": 40}})", "/camera/fov: unknown key"},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5], "at": [0, 0, 0], "fov_deg": "wide"}})", "/camera/fov_deg: expected a number"},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5], "at": [0, 0, 0], "width": 10.5}})", "/camera/width: expected an integer"},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5], "at": [0, 0, 5]}})", "/camera: camera 'from' and 'at' are the same point"},
      {R"({"meshes": [)" + box + R"(], "camera": {"from": [0, 0, 5], "at": [0, 0, 0], "up": [0, 0, 1]}})", "/camera: camera 'up' is parallel"},
      {R"({"meshes": [)" + box + R"(], "background": "blue"})", "/background: expected a number or an array of 3 numbers"},
      {R"({"meshes": [)" + box + R"(], "materials": {"m": {"diffuse": 1.5}}})", "/materials/m/diffuse: a diffuse albedo must be below 1"},
      {R"({"meshes": [)" + box + R"(], "materials": {"m": {"emission": [-1, 0, 0]}}})", "/materials/m/emission: values must be >= 0"},
      {R"({"meshes": [)" + box + R"(], "materials": {"m": {"glossy": 1}}})", "/materials/m/glossy: unknown key"},
      {R"({"meshes": [{"generator": "box", "material": "nope"}]})", "/meshes/0/material: no material named 'nope'"},
      {R"({"meshes": [{"generator": "box", "file": "x.obj"}]})", "/meshes/0: give either \"file\" or \"generator\", not both"},
      {R"({"meshes": [{"material": {"diffuse": 0.5}}]})", "/meshes/0: missing \"file\" or \"generator\""},
      {R"({"meshes": [{"file": "x.obj", "params": {}}]})", "/meshes/0/params: \"params\" belongs to a \"generator\""},
      {R"({"meshes": [{"generator": "sphere:rings=4", "params": {"rings": 5}}]})", "/meshes/0/params/rings: given both"},
      {R"({"meshes": [{"generator": "teapot"}]})", "/meshes/0/generator: unknown scene 'teapot'"},
      {R"({"meshes": [{"generator": "sphere", "params": {"segments": 1}}]})", "/meshes/0/params: sphere: segments must be >= 3, got 1"},
      {R"({"meshes": [{"generator": "sphere", "params": {"bogus": 1}}]})", "/meshes/0/params:"},
      {R"({"meshes": [{"file": "missing.obj"}]})", "/meshes/0/file: "},
      {R"({"meshes": [{"file": "other.json"}]})", "/meshes/0/file: scene files cannot include other scene files"},
      {R"({"meshes": [{"file": 42}]})", "/meshes/0/file: expected a file path"},
      {R"({"meshes": []})", "/meshes: expected a non-empty array"},
      {R"({"meshes": [7]})", "/meshes/0: expected a mesh object"},
      {R"({"camera": {"from": [0, 0, 5], "at": [0, 0, 0]}})", "missing \"meshes\""},
      {R"([1, 2])", "expected an object with \"meshes\""},
      {"{\"meshes\": [\n  {\"generator\": \"box\"},\n", "malformed JSON (parse error at line 3"},
      {R"({"from": [1, 2, 3], "at": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 45})", "this is a view file"},
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    const std::string path = test::write_file(dir, "case" + std::to_string(i) + ".json", cases[i].json);
    const std::string err = scene_error(path);
    EXPECT_THAT(err, ::testing::StartsWith(path + ": ")) << cases[i].json;
    EXPECT_THAT(err, HasSubstr(cases[i].expect)) << cases[i].json;
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
  // The mesh-file error keeps the mesh file's own message.
  EXPECT_THAT(scene_error(test::write_file(dir, "m.json", R"({"meshes": [{"file": "missing.obj"}]})")),
              HasSubstr("missing.obj: no such file"));
  // Through the command line: exit code 2, one line.
  const auto r = test::run_raylab("render " + (dir / "case0.json").string() + " --size 8x8 --spp 1 --out " +
                                  (dir / "x.png").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_THAT(r.output, HasSubstr("case0.json: /meshes/1/transform/scale: expected a number or an array of 3 numbers"));
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(SceneFile, RenderTakesTheSceneFileAsAPositionalArgument) {
  const auto dir = test::temp_dir("scenefile_cli");
  const std::string path = test::write_file(dir, "s.json", R"({"meshes": [{"generator": "box"}]})");
  const std::string out = (dir / "s.png").string();
  const auto r = test::run_raylab("render " + path + " --size 16x16 --spp 1 --quiet --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out));
  EXPECT_THAT(r.output, HasSubstr("12 triangles"));
  const auto both = test::run_raylab("render " + path + " --scene cornell --size 16x16 --spp 1 --out " + out);
  EXPECT_EQ(both.exit_code, 2) << both.output;
  const auto info = test::run_raylab("info " + path);
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_THAT(info.output, HasSubstr("triangles  12"));
}

TEST(SceneFile, ShippedExamplesLoadAndTheirCamerasSeeThem) {
  const std::filesystem::path examples = std::filesystem::path(RAYLAB_SOURCE_DIR) / "scenes" / "examples";
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(examples)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".json" && ext != ".nff") continue;
    SCOPED_TRACE(entry.path().string());
    const Scene s = load_scene(entry.path().string());
    EXPECT_NO_THROW(s.validate());
    EXPECT_EQ(view_problem(s.view), "");
    EXPECT_TRUE(s.has_emitters() || s.background.maxCoeff() > 0.0f) << "no light";
    EXPECT_GT(hit_fraction(s), 0.3) << "the camera should look at the scene";
    ++checked;
  }
  EXPECT_GE(checked, 3);  // two scene files and the NFF example
}

}  // namespace
}  // namespace raylab

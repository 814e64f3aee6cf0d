// Mesh import through Assimp, format by format, with files the tests write
// themselves: triangle counts, exact coordinates, per-triangle materials
// (OBJ/MTL Kd and Ke, glTF baseColorFactor and emissiveFactor, NFF fill
// colours), merged meshes with node transforms, the NFF view record.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "scenes/mesh_import.h"
#include "scenes/scene_registry.h"
#include "tests/scene_test_files.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

bool near(const Vec3f& a, const Vec3f& b, float tol = 1e-6f) { return (a - b).cwiseAbs().maxCoeff() <= tol; }

// The material of a triangle with a vertex at p.
const Material& material_at(const Scene& s, const Vec3f& p) {
  for (size_t t = 0; t < s.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k)
      if (near(s.mesh.vertex(t, k), p)) return s.material_of(static_cast<uint32_t>(t));
  throw std::runtime_error("no triangle at that vertex");
}

TEST(SceneImport, ObjMtlGivesDiffuseAndEmissionPerTriangle) {
  const auto dir = test::temp_dir("import_mtl");
  test::write_file(dir, "m.mtl", "newmtl red\nKd 0.8 0.1 0.1\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 5 4 3\n");
  const std::string obj = test::write_file(
      dir, "m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 0\nv 6 5 0\nv 5 6 0\nusemtl red\nf 1 2 3\nusemtl lamp\nf 4 5 6\n");
  const Scene s = load_mesh_file(obj);
  ASSERT_EQ(s.num_triangles(), 2u);
  const Material& red = material_at(s, Vec3f(1, 0, 0));
  const Material& lamp = material_at(s, Vec3f(6, 5, 0));
  EXPECT_TRUE(near(red.albedo, Vec3f(0.8f, 0.1f, 0.1f)));
  EXPECT_FALSE(red.is_emissive());
  EXPECT_TRUE(near(lamp.albedo, Vec3f(0.5f, 0.5f, 0.5f)));
  EXPECT_TRUE(near(lamp.emission, Vec3f(5, 4, 3)));
  // A file with emitters is lit by them: the sky is dimmed.
  EXPECT_LT(s.background.maxCoeff(), 0.1f);
}

TEST(SceneImport, ObjVertexExtrasWithoutEffectOnPositions) {
  // "v x y z 1" (w = 1) and "v x y z r g b" (a colour) keep the positions as written.
  const auto dir = test::temp_dir("import_obj_extras");
  const Scene s = load_mesh_file(test::write_file(dir, "x.obj", "v 0 0 0 1\nv 2 0 0 0.5 0.5 0.5\nv 0 3 0 1.0\nf 1 2 3\n"));
  EXPECT_EQ(s.bounds().hi, Vec3f(2, 3, 0));
}

TEST(SceneImport, FilesWithoutMaterialsGetDefaultGreyAndASky) {
  const auto dir = test::temp_dir("import_grey");
  const Scene s = load_mesh_file(test::write_file(dir, "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  ASSERT_EQ(s.num_triangles(), 1u);
  const Material& m = s.material_of(0);
  EXPECT_GT(m.albedo.x(), 0.3f);
  EXPECT_LT(m.albedo.x(), 0.9f);
  EXPECT_EQ(m.albedo.x(), m.albedo.y());
  EXPECT_EQ(m.albedo.y(), m.albedo.z());
  EXPECT_FALSE(m.is_emissive());
  // Lit by a dim sky and a key light (a white sky alone washes grey objects out).
  EXPECT_EQ(s.background, Vec3f::Constant(0.3f));
  EXPECT_GT(s.key_light.minCoeff(), 0.0f);
}

TEST(SceneImport, PlyAsciiBinaryLittleAndBigEndianKeepExactCoordinates) {
  const auto dir = test::temp_dir("import_ply");
  const std::vector<float> xyz = {0.125f, -2.5f, 3.0f, 1e-3f, 7.0f, -0.25f, 1e4f, 0.5f, 0.75f, -1, -1, -1};
  const Scene le = load_mesh_file(test::write_file(dir, "le.ply", test::binary_ply(xyz, {{0, 1, 2}, {0, 2, 3}})));
  ASSERT_EQ(le.num_triangles(), 2u);
  ASSERT_EQ(le.mesh.num_vertices(), 4u);
  for (size_t v = 0; v < 4; ++v) EXPECT_EQ(le.mesh.vertices[v], Vec3f(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2])) << v;
  EXPECT_EQ(le.mesh.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
  // PLY gives no colour (Assimp reports white): the default grey, visible against the sky.
  EXPECT_LT(le.material_of(0).albedo.maxCoeff(), 0.9f);

  std::string be = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  auto put_be = [&](const void* p) {
    const char* c = static_cast<const char*>(p);
    for (int k = 3; k >= 0; --k) be.push_back(c[k]);
  };
  for (float f : {0.0f, 0.0f, 0.0f, 3.0f, 0.0f, 0.0f, 0.0f, 4.0f, 0.0f}) put_be(&f);
  be.push_back(3);
  for (int32_t i : {0, 1, 2}) put_be(&i);
  const Scene b = load_mesh_file(test::write_file(dir, "be.ply", be));
  ASSERT_EQ(b.num_triangles(), 1u);
  EXPECT_EQ(b.bounds().hi, Vec3f(3, 4, 0));

  const Scene a = load_mesh_file(test::write_file(
      dir, "a.ply",
      "ply\nformat ascii 1.0\ncomment quads are triangulated\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n2 0 0\n2 2 0\n0 2 0\n4 0 1 2 3\n"));
  EXPECT_EQ(a.num_triangles(), 2u);
  EXPECT_EQ(a.bounds().hi, Vec3f(2, 2, 0));
}

TEST(SceneImport, StlAsciiAndBinary) {
  const auto dir = test::temp_dir("import_stl");
  const Scene ascii = load_mesh_file(test::write_file(
      dir, "a.stl",
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
      "facet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n"));
  EXPECT_EQ(ascii.num_triangles(), 2u);
  // A binary header may itself start with "solid": the size decides.
  std::string bin = test::binary_stl({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 5, 1, 0, 5, 0, 1, 5, 0, 0, -2, 0, 1, -2, 1, 0, -2});
  bin.replace(0, 5, "solid");
  const Scene b = load_mesh_file(test::write_file(dir, "b.stl", bin));
  EXPECT_EQ(b.num_triangles(), 3u);
  EXPECT_EQ(b.bounds().lo, Vec3f(0, 0, -2));
  EXPECT_EQ(b.bounds().hi, Vec3f(1, 1, 5));
  EXPECT_LT(b.material_of(0).albedo.maxCoeff(), 0.9f);  // no colour in STL: default grey
}

TEST(SceneImport, OffPolygonsAreTriangulated) {
  const auto dir = test::temp_dir("import_off");
  const Scene s = load_mesh_file(test::write_file(
      dir, "p.off", "OFF\n# a pentagon and a triangle\n6 2 0\n0 0 0\n2 0 0\n3 1 0\n1 2 0\n-1 1 0\n0 0 4\n5 0 1 2 3 4\n3 0 1 5\n"));
  EXPECT_EQ(s.num_triangles(), 4u);
  EXPECT_EQ(s.bounds().lo, Vec3f(-1, 0, 0));
  EXPECT_EQ(s.bounds().hi, Vec3f(3, 2, 4));
}

TEST(SceneImport, GltfMergesMeshesWithNodeTransformsAndMaterials) {
  const auto dir = test::temp_dir("import_gltf");
  test::GltfPrimitive quad;
  quad.xyz = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.indices = {0, 1, 2, 0, 2, 3};
  quad.base_color = {0.8f, 0.2f, 0.1f, 1.0f};
  test::GltfPrimitive light;
  light.xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  light.indices = {0, 1, 2};
  light.short_indices = true;
  light.base_color = {0.5f, 0.5f, 0.5f, 1.0f};
  light.emissive = {2.0f, 1.0f, 0.5f};
  const Scene s = load_mesh_file(test::write_file(dir, "m.gltf", test::gltf_embedded({quad, light}, {{}, {0, 0, 10}})));
  ASSERT_EQ(s.num_triangles(), 3u);
  EXPECT_EQ(s.bounds().lo, Vec3f(0, 0, 0));
  EXPECT_EQ(s.bounds().hi, Vec3f(1, 1, 10));  // the second node is translated by 10 in z
  const Material& q = material_at(s, Vec3f(1, 1, 0));
  const Material& l = material_at(s, Vec3f(1, 0, 10));
  EXPECT_TRUE(near(q.albedo, Vec3f(0.8f, 0.2f, 0.1f)));
  EXPECT_FALSE(q.is_emissive());
  EXPECT_TRUE(near(l.emission, Vec3f(2.0f, 1.0f, 0.5f)));

  const Scene b = load_mesh_file(test::write_file(dir, "m.glb", test::glb({quad})));
  EXPECT_EQ(b.num_triangles(), 2u);
  EXPECT_EQ(b.bounds().hi, Vec3f(1, 1, 0));

  // An external .bin buffer beside the .gltf; the index check reads it there.
  std::string buffer;
  nlohmann::json doc = test::gltf_document({quad, light}, buffer);
  doc["buffers"][0]["uri"] = "ext.bin";
  test::write_file(dir, "ext.bin", buffer);
  EXPECT_EQ(load_mesh_file(test::write_file(dir, "ext.gltf", doc.dump())).num_triangles(), 3u);
  test::write_file(dir, "ext.bin", buffer.substr(0, buffer.size() - 4));
  EXPECT_THAT(test::load_error(dir / "ext.gltf"), HasSubstr("truncated"));
  std::filesystem::remove(dir / "ext.bin");
  EXPECT_THAT(test::load_error(dir / "ext.gltf"), HasSubstr("cannot read the buffer file"));
}

const char* kNff =
    "v\nfrom 2.1 1.3 1.7\nat 0 0 0.5\nup 0 0 1\nangle 30\nhither 0.01\nresolution 320 240\n"
    "b 0.078 0.361 0.753\nl 4 3 2\nf 0.9 0.2 0.1 0.8 0 0 0 0\n"
    "p 4\n-2 -2 -0.5\n2 -2 -0.5\n2 2 -0.5\n-2 2 -0.5\n"
    "f 0.1 0.2 0.9 0.8 0 0 0 0\ntess 1\ns 0 0 0 0.5\n";

TEST(SceneImport, NffViewRecordBecomesTheCamera) {
  const auto dir = test::temp_dir("import_nff");
  const std::string path = test::write_file(dir, "t.nff", kNff);
  const Scene s = load_mesh_file(path);
  EXPECT_EQ(s.view.from, Vec3f(2.1f, 1.3f, 1.7f));
  EXPECT_EQ(s.view.at, Vec3f(0, 0, 0.5f));
  EXPECT_EQ(s.view.up, Vec3f(0, 0, 1));
  EXPECT_EQ(s.view.fov_deg, 30.0f);
  EXPECT_EQ(s.view.width, 320);
  EXPECT_EQ(s.view.height, 240);
  EXPECT_GT(s.num_triangles(), 2u);  // the polygon and the tessellated sphere
  // NFF's fill colour times its diffuse coefficient Kd (0.8).
  EXPECT_TRUE(near(material_at(s, Vec3f(2, 2, -0.5f)).albedo, Vec3f(0.72f, 0.16f, 0.08f)));

  // Without a view record: a camera framing the bounds.
  const Scene f = load_mesh_file(test::write_file(dir, "noview.nff", std::string(kNff).substr(std::string(kNff).find("b "))));
  EXPECT_EQ(f.view.at, f.bounds().center());
  // A view file beside the mesh takes precedence over the record.
  test::write_file(dir, "t.json", R"({"from":[9,9,9],"at":[0,0,0],"up":[0,0,1],"fov_deg":50})");
  EXPECT_EQ(load_mesh_file(path).view.from, Vec3f(9, 9, 9));
  // A broken record names the file and the line.
  const std::string bad = test::write_file(dir, "bad.nff", "v\nfrom 1 2 3\nat 0 0 0\nup 0 0 1\nangle wide\nresolution 8 8\ns 0 0 0 1\n");
  EXPECT_THAT(test::load_error(bad), HasSubstr("bad.nff: line 5"));
  const std::string partial = test::write_file(dir, "partial.nff", "v\nfrom 1 2 3\nat 0 0 0\nangle 40\nresolution 8 8\ns 0 0 0 1\n");
  EXPECT_THAT(test::load_error(partial), HasSubstr("no 'up'"));
}

TEST(SceneImport, LargeBinaryPlyArrivesIntact) {
  // 2^18 triangles through the child process and the memory file: every
  // coordinate and index must arrive unchanged.
  const auto dir = test::temp_dir("import_large");
  const int n = 1 << 18;
  std::vector<float> xyz;
  std::vector<std::vector<int32_t>> faces;
  xyz.reserve(3 * (n + 2));
  for (int i = 0; i < n + 2; ++i) {
    xyz.push_back(static_cast<float>(i) * 0.5f);
    xyz.push_back(static_cast<float>(i % 7));
    xyz.push_back(-static_cast<float>(i % 13));
  }
  faces.reserve(n);
  for (int i = 0; i < n; ++i) faces.push_back({i, i + 1, i + 2});
  const Scene s = load_mesh_file(test::write_file(dir, "big.ply", test::binary_ply(xyz, faces)));
  ASSERT_EQ(s.num_triangles(), static_cast<size_t>(n));
  ASSERT_EQ(s.mesh.num_vertices(), static_cast<size_t>(n + 2));
  size_t wrong = 0;
  for (int i = 0; i < n + 2; ++i) wrong += s.mesh.vertices[i] != Vec3f(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
  for (int i = 0; i < n; ++i)
    wrong += s.mesh.triangles[i] != std::array<uint32_t, 3>{uint32_t(i), uint32_t(i + 1), uint32_t(i + 2)};
  EXPECT_EQ(wrong, 0u);
}

TEST(SceneImport, InfoReportsTheLoadTime) {
  const auto dir = test::temp_dir("import_info");
  const std::string path = test::write_file(dir, "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto r = test::run_raylab("info " + path);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("triangles  1"));
  EXPECT_THAT(r.output, ::testing::ContainsRegex("load +[0-9.]+ ms"));
}

}  // namespace
}  // namespace raylab

// The benchmark workflow (workflow/): the per-cell reports merged by
// merge_records.py equal one `raylab bench` run over the same matrix (same
// cells in the same order, same hits, same CSV columns); compare_records.py
// finds a changed hit; the Snakefile parses and plans the quick preset; and
// scripts/random_views.py, the view-robustness helper.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/report_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;
using test::read_json;

using Shell = test::CommandResult;

// A shell command's exit code and output (stdout and stderr).
Shell sh(const std::string& command) { return test::run_shell(command + " 2>&1"); }

const std::string kSource = RAYLAB_SOURCE_DIR;
const std::string kCommon =
    " --scene 'soup:n=400;terrain:n=8' --ray-sets primary,random --size 16x16 --rays 300 --repeats 1 --min-time 0 --quiet";

TEST(Workflow, MergedCellsEqualOneRunOverTheMatrix) {
  const auto dir = test::temp_dir("workflow_merge");
  const std::string bin = RAYLAB_BINARY;
  ASSERT_EQ(sh(bin + " bench --accel embree,bvh,grid --threads 1" + kCommon + " -o " + (dir / "one.json").string()).exit_code, 0);
  std::string cells;
  for (const char* accel : {"embree", "bvh", "grid"}) {
    const auto cell = dir / (std::string(accel) + ".json");
    ASSERT_EQ(sh(bin + " bench --accel " + accel + " --threads 1" + kCommon + " -o " + cell.string()).exit_code, 0);
    cells += " " + cell.string();
  }
  const auto merged = dir / "merged.json";
  const Shell m = sh("/usr/bin/python3 " + kSource + "/workflow/scripts/merge_records.py --out " + merged.string() + cells);
  ASSERT_EQ(m.exit_code, 0) << m.output;

  const auto one = read_json(dir / "one.json"), all = read_json(merged);
  ASSERT_EQ(all["records"].size(), one["records"].size());
  ASSERT_EQ(all["records"].size(), 2u * 3u * 2u);  // scenes x accels x ray sets
  for (size_t i = 0; i < one["records"].size(); ++i) {
    const auto& a = one["records"][i];
    const auto& b = all["records"][i];
    for (const char* key : {"scene", "accel", "ray_set", "threads", "rays", "triangles", "embree_agreement",
                            "nodes_per_ray", "tris_per_ray", "bytes", "nodes", "leaves"})
      EXPECT_EQ(a[key], b[key]) << "record " << i << " " << key;
  }
  EXPECT_EQ(all["options"]["accels"], one["options"]["accels"]);
  EXPECT_EQ(all["options"]["scenes"], one["options"]["scenes"]);
  EXPECT_TRUE(all["complete"].get<bool>());
  EXPECT_EQ(all["cells"], 3);
  EXPECT_EQ(all["revision"], one["revision"]);

  // CSV: the same header, one row per record, rows in the JSON's order.
  const auto csv_one = test::read_lines(dir / "one.csv"), csv_all = test::read_lines(dir / "merged.csv");
  ASSERT_EQ(csv_all.size(), csv_one.size());
  EXPECT_EQ(csv_all[0], csv_one[0]);
  for (size_t i = 1; i < csv_all.size(); ++i) {
    const auto& r = all["records"][i - 1];
    EXPECT_THAT(csv_all[i], HasSubstr("," + r["accel"].get<std::string>() + "," + r["ray_set"].get<std::string>() + ","))
        << "row " << i;
  }

  // compare_records: a run agrees with itself, and a changed hit is found.
  const auto a_dir = dir / "a", b_dir = dir / "b";
  fs::create_directories(a_dir);
  fs::create_directories(b_dir);
  fs::copy_file(merged, a_dir / "bench.json");
  auto changed = all;
  changed["records"][3]["embree_agreement"] = 0.5;
  std::ofstream(b_dir / "bench.json") << changed.dump();
  const std::string compare = "/usr/bin/python3 " + kSource + "/workflow/scripts/compare_records.py ";
  const Shell same = sh(compare + a_dir.string() + " " + a_dir.string());
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_THAT(same.output, HasSubstr("same cells and hits (bench.json 12)"));
  const Shell diff = sh(compare + a_dir.string() + " " + b_dir.string());
  EXPECT_EQ(diff.exit_code, 1) << diff.output;
  EXPECT_THAT(diff.output, HasSubstr("embree_agreement"));
  fs::remove_all(dir);
}

// Embree's bytes on a multi-threaded build vary with scheduling (per-thread allocator blocks);
// compare_records accepts 10 % there and nowhere else: one thread, or any raylab structure,
// must agree exactly.
TEST(Workflow, CompareRecordsToleratesOnlyEmbreeMultithreadBytes) {
  const auto dir = test::temp_dir("workflow_bytes");
  const auto write = [&](const fs::path& d, int threads, const char* accel, long bytes) {
    fs::create_directories(d);
    nlohmann::json r = {{"scene", "terrain:n=96"}, {"accel", accel}, {"ray_set", "primary"},
                        {"threads", threads}, {"triangles", 18050}, {"rays", 1000},
                        {"embree_agreement", 1.0}, {"bytes", bytes}};
    std::ofstream(d / "bench.json") << nlohmann::json{{"records", {r}}}.dump();
  };
  const std::string compare = "/usr/bin/python3 " + kSource + "/workflow/scripts/compare_records.py ";
  const auto run = [&](int threads, const char* accel, long bytes_b) {
    write(dir / "a", threads, accel, 1223440);
    write(dir / "b", threads, accel, bytes_b);
    return sh(compare + (dir / "a").string() + " " + (dir / "b").string());
  };
  EXPECT_EQ(run(2, "embree", 1285136).exit_code, 0);  // the pair seen in a real local-vs-Slurm run
  EXPECT_EQ(run(2, "embree", 1500000).exit_code, 1);  // 18 %: beyond scheduling
  EXPECT_EQ(run(1, "embree", 1285136).exit_code, 1);  // one build thread is deterministic
  const Shell bvh = run(2, "bvh", 1285136);
  EXPECT_EQ(bvh.exit_code, 1);
  EXPECT_THAT(bvh.output, HasSubstr("bytes"));
  fs::remove_all(dir);
}

// The merge refuses inputs that are not bench reports rather than writing a half-merged file.
TEST(Workflow, MergeRejectsAForeignReport) {
  const auto dir = test::temp_dir("workflow_bad");
  std::ofstream(dir / "x.json") << R"({"command": "verify", "records": []})";
  std::ofstream(dir / "x.csv") << "scene\n";
  const Shell m = sh("/usr/bin/python3 " + kSource + "/workflow/scripts/merge_records.py --out " +
                     (dir / "m.json").string() + " " + (dir / "x.json").string());
  EXPECT_NE(m.exit_code, 0);
  EXPECT_THAT(m.output, HasSubstr("not a `raylab bench` report"));
  EXPECT_FALSE(fs::exists(dir / "m.json"));
  fs::remove_all(dir);
}

// The output files of a dry run's plan (`snakemake -n`), each checked to lie under `dir`:
// the workflow writes nothing outside its output directory, so the checkout stays clean.
size_t outputs_under(const std::string& plan, const fs::path& dir) {
  std::istringstream lines(plan);
  size_t outputs = 0;
  for (std::string line; std::getline(lines, line);) {
    const auto at = line.find("output: ");
    if (at == std::string::npos) continue;
    std::istringstream files(line.substr(at + 8));
    for (std::string f; std::getline(files, f, ',');) {
      f.erase(0, f.find_first_not_of(' '));
      ++outputs;
      EXPECT_EQ(f.rfind(dir.string(), 0), 0u) << "written outside " << dir << ": " << f;
    }
  }
  return outputs;
}

// The Snakefile parses and plans the quick preset: every cell of the matrix is a job
// (without the optional ../shared meshes, so the count does not depend on them).
TEST(Workflow, SnakefilePlansTheQuickPreset) {
  ASSERT_EQ(sh("command -v snakemake").exit_code, 0) << "snakemake not installed (bash scripts/install-deps.sh)";
  const auto dir = test::temp_dir("workflow_plan");
  const Shell r = sh("cd " + kSource + " && snakemake -s workflow/Snakefile -n --nolock --cores 2 --config raylab=" +
                     std::string(RAYLAB_BINARY) + " out=" + dir.string() + " node_cores=2 shared_scenes_marker=/nonexistent > " + (dir / "plan.txt").string() + " 2>&1; rc=$?; tr -s ' ' < " + (dir / "plan.txt").string() + "; exit $rc");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // 3 scenes x 14 accelerator specs x threads {1, 2}; 4 soups x 11 structures.
  EXPECT_THAT(r.output, HasSubstr("bench_cell 84 2 2"));
  EXPECT_THAT(r.output, HasSubstr("scaling_cell 44 2 2"));
  EXPECT_THAT(r.output, HasSubstr("merge_bench 1 1 1"));
  // The pictures and the page are part of the study...
  for (const char* rule : {"heatmaps 1 ", "structures 1 ", "report 1 ", "charts 1 "})
    EXPECT_THAT(r.output, HasSubstr(rule)) << rule;
  // ...and every file the workflow writes is under its output directory: `make bench`
  // leaves the checkout clean.
  EXPECT_GT(outputs_under(r.output, dir), 50u);
  fs::remove_all(dir);
}

// Every other preset plans too: the scalar preset's specs ("grid:simd=0") are not file
// names, so its equal-time jobs are keyed by the spec's slug (the planner refused it before).
TEST(Workflow, SnakefilePlansTheScalarAndFullPresets) {
  ASSERT_EQ(sh("command -v snakemake").exit_code, 0) << "snakemake not installed (bash scripts/install-deps.sh)";
  const auto dir = test::temp_dir("workflow_presets");
  for (const std::string preset : {"scalar", "full"}) {
    const Shell r = sh("cd " + kSource + " && snakemake -s workflow/Snakefile -n -p --nolock --cores 2 --config preset=" +
                       preset + " raylab=" + std::string(RAYLAB_BINARY) + " out=" + (dir / preset).string() +
                       " node_cores=2 shared_scenes_marker=/nonexistent > " + (dir / "plan.txt").string() +
                       " 2>&1; rc=$?; tr -s ' ' < " + (dir / "plan.txt").string() + "; exit $rc");
    ASSERT_EQ(r.exit_code, 0) << preset << ": " << r.output;
    EXPECT_THAT(r.output, HasSubstr("equal_time_renders ")) << preset;
    if (preset == "scalar") {
      // One render job per scalar spec, the spec passed whole to raylab.
      EXPECT_THAT(r.output, HasSubstr("equal_time_renders 13 "));
      EXPECT_THAT(r.output, HasSubstr("--accel 'kdtree:simd=0,ct=15'"));
    }
  }
  fs::remove_all(dir);
}

// The study (workflow/study.smk) plans one timing job per scene of the suite (the procedural
// ones always, the ../shared ones when present), verify, stress, the analysis and the page,
// all under its output directory; the timing jobs run every structure and variant.
TEST(Workflow, SnakefilePlansTheStudy) {
  ASSERT_EQ(sh("command -v snakemake").exit_code, 0) << "snakemake not installed (bash scripts/install-deps.sh)";
  const auto dir = test::temp_dir("workflow_study");
  const Shell r = sh("cd " + kSource + " && snakemake -s workflow/Snakefile study -n -p --nolock --cores 2 --config raylab=" +
                     std::string(RAYLAB_BINARY) + " study_root=" + dir.string() + " node_cores=2 > " +
                     (dir / "plan.txt").string() + " 2>&1; rc=$?; tr -s ' ' < " + (dir / "plan.txt").string() +
                     "; exit $rc");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const int scenes = test::have_shared_scenes() ? 23 : 4;
  EXPECT_THAT(r.output, HasSubstr("study_bench " + std::to_string(scenes) + " "));
  for (const char* rule : {"study_merge 1 ", "study_stress 1 ", "study_analysis 1 ", "study_page 1 ", "study_suite 1 "})
    EXPECT_THAT(r.output, HasSubstr(rule)) << rule;
  for (const char* scene : {"--scene 'stadium'", "--scene 'terrain'", "--scene 'city'", "--scene 'grass'"})
    EXPECT_THAT(r.output, HasSubstr(scene)) << scene;
  EXPECT_THAT(r.output, HasSubstr("--accel 'embree,bvh,kdtree,bsp,octree,loose_octree,grid,hashgrid,grid2,hgrid,irgrid,"
                                  "hybrid,embree:robust=1,bvh:tri=mt' --threads 1"));
  if (!test::have_shared_scenes()) {
    EXPECT_THAT(r.output, HasSubstr("study: scene balls skipped"));
  }
  EXPECT_GT(outputs_under(r.output, dir), 8u);
  fs::remove_all(dir);
}

// scripts/random_views.py: seeded cameras inside the box (the same seed, the
// same files), mesh paths made absolute so the copies load from elsewhere,
// and bad arguments refused without writing anything.
TEST(Scripts, RandomViewsWritesSeededCamerasInsideTheBox) {
  const auto dir = test::temp_dir("random_views");
  fs::create_directories(dir / "src");
  std::ofstream(dir / "src" / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "src" / "room.json")
      << R"({"camera": {"from": [0, 0, 5], "at": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 50, "width": 32, "height": 24},
             "meshes": [{"file": "tri.obj"}, {"generator": "plane"}]})";
  const std::string script = "/usr/bin/python3 " + kSource + "/scripts/random_views.py " + (dir / "src" / "room.json").string();
  for (const char* out : {"a/view", "b/view"})
    ASSERT_EQ(sh(script + " " + (dir / out).string() + " --box=-1,2,-3,1,4,3 --count 3 --seed 5").exit_code, 0);
  for (int i = 0; i < 3; ++i) {
    const std::string name = "view_v" + std::to_string(i) + ".json";
    const nlohmann::json a = read_json(dir / "a" / name), b = read_json(dir / "b" / name);
    EXPECT_EQ(a, b) << "same seed, same views";
    const auto& from = a["camera"]["from"];
    ASSERT_EQ(from.size(), 3u);
    EXPECT_GE(from[0].get<double>(), -1.0);
    EXPECT_LE(from[0].get<double>(), 1.0);
    EXPECT_GE(from[1].get<double>(), 2.0);
    EXPECT_LE(from[1].get<double>(), 4.0);
    EXPECT_GE(from[2].get<double>(), -3.0);
    EXPECT_LE(from[2].get<double>(), 3.0);
    EXPECT_EQ(a["meshes"][0]["file"], (dir / "src" / "tri.obj").string());
  }
  EXPECT_NE(read_json(dir / "a" / "view_v0.json")["camera"], read_json(dir / "a" / "view_v1.json")["camera"]);
  EXPECT_FALSE(fs::exists(dir / "a" / "view_v3.json"));
  // The copies load where they are (the mesh path is absolute).
  const auto info = test::run_raylab("info " + (dir / "a" / "view_v2.json").string());
  EXPECT_EQ(info.exit_code, 0) << info.output;
  // Bad arguments: a non-zero exit and no file.
  for (const char* bad : {" --box=1,2", " --box=1,1,1,0,0,0", "", " --around=0,0,0 --distance 0,1"}) {
    const Shell r = sh(script + " " + (dir / "c" / "view").string() + bad);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_FALSE(fs::exists(dir / "c" / "view_v0.json")) << bad;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace raylab

// The command line: exit codes, one-line errors, no partial output files,
// and the outputs of render, verify and bench.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include <nlohmann/json.hpp>

#include "accel/registry.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

TEST(Cli, BadArgumentsExitWithCode2AndAMessage) {
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"render --scene nosuch --out X", "unknown scene 'nosuch'"},
      {std::string("render --accel ") + kReservedUnknownAccelerator + " --out X",
       std::string("unknown accelerator '") + kReservedUnknownAccelerator + "'"},
      {"render --accel bvh:leaf=zero --out X", "not an integer"},
      {"render --frobnicate --out X", "frobnicate"},
      {"render --size 12xq --out X", "invalid size"},
      {"render --spp 0 --out X", "spp"},
      {"render --scene /no/such/file.ply --out X", "no such file"},
      {"verify --accel bvh,nope", "unknown accelerator 'nope'"},
      {"verify --ray-sets primary,weird", "unknown ray set 'weird'"},
      {"bench --threads -1", "thread count"},
      {"bench --sweep nothing=1,2", "no accelerator in the list has a parameter 'nothing'"},
      {"info --scene soup:n=abc", "not an integer"},
      {"nosuchcommand", "nosuchcommand"},
      {"", "subcommand"},
  };
  const auto dir = test::temp_dir("cli_bad");
  for (const auto& c : cases) {
    std::string args = c.args;
    const auto x = args.find("--out X");
    if (x != std::string::npos) args.replace(x, 7, "--out " + (dir / "img.png").string());
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.message)) << args;
    EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << "one-line error expected for: " << args << "\n"
                                                                     << r.output;
  }
  // No output file and no temporary file left behind.
  EXPECT_TRUE(fs::is_empty(dir)) << "files left in " << dir;
}

TEST(Cli, RenderWritesAPngOfTheRequestedSize) {
  const auto dir = test::temp_dir("cli_render");
  const auto png = dir / "sub" / "c.png";
  fs::create_directories(dir / "sub");  // an output's directory must exist (tests/app/test_output_paths.cpp)
  const auto r = test::run_raylab("render --scene cornell --spp 2 --size 40x30 --quiet --out " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(png, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  auto be32 = [&](size_t at) {
    return (static_cast<uint8_t>(bytes[at]) << 24) | (static_cast<uint8_t>(bytes[at + 1]) << 16) |
           (static_cast<uint8_t>(bytes[at + 2]) << 8) | static_cast<uint8_t>(bytes[at + 3]);
  };
  EXPECT_EQ(be32(16), 40u);  // IHDR width
  EXPECT_EQ(be32(20), 30u);  // IHDR height
  // Only the final file: the temporary was renamed.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "sub"), fs::directory_iterator()), 1);
}

TEST(Cli, RenderIsDeterministicAcrossThreadCounts) {
  const auto dir = test::temp_dir("cli_det");
  const auto a = dir / "a.pfm", b = dir / "b.pfm";
  ASSERT_EQ(test::run_raylab("render --scene cornell --spp 3 --size 32x32 --threads 1 --quiet --out " + a.string()).exit_code, 0);
  ASSERT_EQ(test::run_raylab("render --scene cornell --spp 3 --size 32x32 --threads 2 --quiet --out " + b.string()).exit_code, 0);
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  const std::string sa((std::istreambuf_iterator<char>(fa)), {}), sb((std::istreambuf_iterator<char>(fb)), {});
  EXPECT_GT(sa.size(), 32u * 32 * 12);
  EXPECT_EQ(sa, sb);
}

TEST(Cli, VerifyReportsZeroDisagreementsAndWritesJson) {
  const auto dir = test::temp_dir("cli_verify");
  const auto json = dir / "v.json";
  const auto r = test::run_raylab("verify --scene cornell --accel bvh,brute --rays 5000 -o " + json.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("records"));
  ASSERT_EQ(j["records"].size(), 4u);  // 2 accelerators x (primary, random)
  for (const auto& rec : j["records"]) {
    for (const char* key : {"scene", "accel", "ray_set", "rays", "hit_miss_disagree", "prim_disagree", "max_rel_t_err",
                            "raylab_wrong", "embree_wrong", "ties"})
      EXPECT_TRUE(rec.contains(key)) << key;
    EXPECT_EQ(rec["rays"], 5000);
    EXPECT_EQ(rec["hit_miss_disagree"], 0);
    EXPECT_EQ(rec["prim_disagree"], 0);
    EXPECT_EQ(rec["raylab_wrong"], 0);
  }
  for (const char* key : {"cpu", "revision", "date", "embree", "compiler"}) EXPECT_TRUE(j.contains(key)) << key;
}

TEST(Cli, BenchWritesRecordsWithRatiosToEmbreeFromTheSameRun) {
  const auto dir = test::temp_dir("cli_bench");
  const auto json = dir / "b.json";
  const auto r = test::run_raylab("bench --scene soup:n=2000 --accel embree,bvh --ray-sets primary,random,shadow,diffuse "
                                  "--size 64x64 --rays 4000 --repeats 2 --min-time 0 --threads 1,2 --quiet -o " +
                                  json.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j["records"].size(), 2u * 4 * 2);
  for (const auto& rec : j["records"]) {
    for (const char* key : {"scene", "triangles", "accel", "ray_set", "threads", "rays", "build_ms", "bytes",
                            "mrays_per_s", "embree_mrays_per_s", "ratio_to_embree"})
      EXPECT_TRUE(rec.contains(key)) << key;
    EXPECT_EQ(rec["triangles"], 2000);
    EXPECT_GT(rec["mrays_per_s"].get<double>(), 0.0);
    EXPECT_NEAR(rec["ratio_to_embree"].get<double>(),
                rec["mrays_per_s"].get<double>() / rec["embree_mrays_per_s"].get<double>(), 1e-9);
    if (rec["accel"] == "embree") {
      EXPECT_EQ(rec["ratio_to_embree"].get<double>(), 1.0);
    }
    EXPECT_EQ(rec["embree_agreement"].get<double>(), 1.0) << rec.dump();
  }
}

TEST(Cli, InfoAndListings) {
  const auto info = test::run_raylab("info --scene cornell");
  EXPECT_EQ(info.exit_code, 0);
  EXPECT_THAT(info.output, HasSubstr("triangles  32"));
  const auto scenes = test::run_raylab("scenes");
  EXPECT_EQ(scenes.exit_code, 0);
  EXPECT_THAT(scenes.output, HasSubstr("cornell"));
  const auto accels = test::run_raylab("accels");
  EXPECT_EQ(accels.exit_code, 0);
  EXPECT_THAT(accels.output, HasSubstr("embree"));
  EXPECT_THAT(accels.output, HasSubstr("leaf="));
  EXPECT_EQ(test::run_raylab("--help").exit_code, 0);
}

TEST(Cli, AccelsJsonIsTheRegistry) {
  const auto r = test::run_raylab("accels --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j.size(), accelerator_registry().size());
  for (size_t i = 0; i < j.size(); ++i) {
    const AcceleratorInfo& info = accelerator_registry()[i];
    EXPECT_EQ(j[i]["name"], info.name);
    EXPECT_EQ(j[i]["params"].size(), info.params.size()) << info.name;
    EXPECT_EQ(j[i]["stats"].size(), info.stats.size()) << info.name;
    EXPECT_EQ(j[i]["cover"].size(), info.cover.size()) << info.name;
    EXPECT_EQ(j[i]["capabilities"]["reference"].get<bool>(), info.caps.reference) << info.name;
    EXPECT_EQ(j[i]["capabilities"]["quadratic"].get<bool>(), info.caps.quadratic) << info.name;
    EXPECT_EQ(j[i]["description"].is_null(), !info.describe) << info.name;
    for (size_t k = 0; k < info.params.size() && k < j[i]["params"].size(); ++k)
      EXPECT_EQ(j[i]["params"][k]["valid"], info.params[k].check.describe()) << info.name << ":" << info.params[k].name;
  }
  // A declared range as numbers: bsp's tplanes in 0..64.
  const auto& bsp = *std::find_if(j.begin(), j.end(), [](const auto& a) { return a["name"] == "bsp"; });
  const auto& tplanes = *std::find_if(bsp["params"].begin(), bsp["params"].end(),
                                      [](const auto& p) { return p["name"] == "tplanes"; });
  EXPECT_EQ(tplanes["kind"], "integer");
  EXPECT_EQ(tplanes["range"]["min"].get<double>(), 0.0);
  EXPECT_EQ(tplanes["range"]["max"].get<double>(), 64.0);
}

TEST(Cli, OutputInUnwritablePlaceFailsCleanly) {
  const auto dir = test::temp_dir("cli_unwritable");
  const auto blocker = dir / "file";
  std::ofstream(blocker) << "x";
  // A path whose parent is a regular file cannot be created.
  const auto r = test::run_raylab("render --scene cornell --spp 1 --size 8x8 --quiet --out " + (blocker / "x.png").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_THAT(r.output, HasSubstr("x.png"));
  const auto bad_ext = test::run_raylab("render --scene cornell --spp 1 --size 8x8 --quiet --out " + (dir / "x.jpg").string());
  EXPECT_EQ(bad_ext.exit_code, 2);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

// `raylab verify` on the structures: a bad parameter is a usage error naming
// it (exit 2); good specs report no wrong hit.
TEST(Cli, VerifyRejectsBadStructureParameters) {
  for (const auto& [spec, word] : {std::pair{"grid:density=0", "density"}, std::pair{"kdtree:ct=-1", "ct"}}) {
    const auto r = test::run_raylab(std::string("verify --scene cornell --accel ") + spec + " --rays 10");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(word));
  }
}

TEST(Cli, VerifyReportsNoWrongHitsForKdTrees) {
  const auto r = test::run_raylab("verify --scene copies:n=1000 --accel kdtree,kdtree:builder=median,kdtree:clip=0 --rays 4096");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("FAIL"), std::string::npos) << r.output;
  EXPECT_THAT(r.output, HasSubstr("kdtree:builder=median"));
}

TEST(Cli, VerifyPassesForGridsOnDragonInSponza) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const auto r = test::run_raylab("verify --scene " + test::shared_dir() +
                                  "/scenes/dragon_in_sponza.ply --accel grid,hashgrid,grid2 --rays 20000 --threads 2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("FAIL"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace raylab

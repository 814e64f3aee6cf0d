// One command-line vocabulary across subcommands, accurate error
// messages, image outputs, and interruption with kept records. Each test
// pins one rule that the command line broke before.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tests/scene_test_files.h"
#include "tests/report_test_util.h"
#include "tests/test_util.h"
#include "tracer/image.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;
using test::read_json;
using test::read_lines;

std::string q(const fs::path& p) { return fmt::format("'{}'", p.string()); }

TEST(CliVocabulary, RaySetsNamesSetsAndRaysCountsRaysInVerifyAndBench) {
  const auto dir = test::temp_dir("voc_rays");
  const auto v = test::run_raylab("verify --scene soup:n=200 --accel bvh --ray-sets random --rays 700 -q -o " +
                                  q(dir / "v.json"));
  ASSERT_EQ(v.exit_code, 0) << v.output;
  const auto b = test::run_raylab("bench --scene soup:n=200 --accel embree,bvh --ray-sets random --rays 700 --repeats 1 --min-time 0 "
                                  "--threads 1 -q -o " + q(dir / "b.json"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  for (const char* file : {"v.json", "b.json"}) {
    const auto j = read_json(dir / file);
    ASSERT_FALSE(j["records"].empty()) << file;
    for (const auto& rec : j["records"]) {
      EXPECT_EQ(rec["ray_set"], "random") << file;
      EXPECT_EQ(rec["rays"], 700) << file;
    }
  }
  // A set name given to --rays (the old bench meaning) is answered with the right option.
  for (const char* cmd : {"verify", "bench"}) {
    const auto r = test::run_raylab(std::string(cmd) + " --rays primary");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("--ray-sets")) << cmd;
    EXPECT_THAT(r.output, Not(HasSubstr("not in range"))) << cmd;
  }
}

TEST(CliVocabulary, EveryScenedCommandTakesAPositionalScene) {
  const auto dir = test::temp_dir("voc_positional");
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"info soup:n=123", "triangles  123"},
      {"render soup:n=123 --spp 1 --size 8x8 -q -o " + q(dir / "r.png"), "123 triangles"},
      {"verify soup:n=123 --accel bvh --ray-sets random --rays 100 -q", "soup:n=123 (123 triangles)"},
      {"bench soup:n=123 --accel embree --ray-sets random --rays 100 --repeats 1 --min-time 0 --threads 1 -q", "soup:n=123 (123 triangles)"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_raylab(c.args);
    EXPECT_EQ(r.exit_code, 0) << c.args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.expect)) << c.args;
  }
  // stress runs scenarios, not scenes: they take the positional place.
  const auto st = test::run_raylab("stress single --accel bvh -q --ray-scale 0.01");
  EXPECT_EQ(st.exit_code, 0) << st.output;
  EXPECT_THAT(st.output, HasSubstr("stress: 1 scenario x 1 accelerator,"));
  // Both forms at once: one message naming the two scenes, not CLI11's "--scene excludes scene".
  for (const char* cmd : {"render", "verify", "info"}) {
    const auto r = test::run_raylab(std::string(cmd) + " soup:n=5 --scene cornell");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("not both")) << cmd;
    EXPECT_THAT(r.output, HasSubstr("soup:n=5")) << cmd;
    EXPECT_THAT(r.output, Not(HasSubstr("excludes"))) << cmd;
  }
}

TEST(CliVocabulary, ThreadsZeroMeansAllCoresInEveryCommand) {
  const auto dir = test::temp_dir("voc_threads");
  const auto b = test::run_raylab("bench --scene soup:n=100 --accel embree --ray-sets random --rays 200 --repeats 1 --min-time 0 "
                                  "--threads 0 -q -o " + q(dir / "b.json"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const auto j = read_json(dir / "b.json");
  ASSERT_EQ(j["records"].size(), 1u);
  EXPECT_EQ(j["records"][0]["threads"].get<int>(), static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  for (const std::string& args : {"render --spp 1 --size 8x8 -q --threads 0 -o " + q(dir / "r.png"),
                                 std::string("verify --accel bvh --rays 100 --threads 0 -q"),
                                 std::string("stress --scenario single --accel bvh --threads 0 -q --ray-scale 0.01")}) {
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
  }
  for (const char* cmd : {"render", "verify", "stress", "bench"}) {
    const auto r = test::run_raylab(std::string(cmd) + " --threads -2");
    EXPECT_EQ(r.exit_code, 2) << cmd << r.output;
    EXPECT_THAT(r.output, HasSubstr("thread count")) << cmd;
  }
}

TEST(CliVocabulary, ShortOptionsWhereUsersExpectThem) {
  const auto dir = test::temp_dir("voc_short");
  // pbrt/Mitsuba habits: -o output, -s samples, -t threads, -q quiet.
  const auto r = test::run_raylab("render cornell -s 2 -t 1 -q --size 12x10 -o " + q(dir / "c.pfm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image img = read_pfm((dir / "c.pfm").string());
  EXPECT_EQ(img.width, 12);
  EXPECT_EQ(img.height, 10);
  const auto v = test::run_raylab("verify cornell --accel bvh --rays 50 -t 1 -q -o " + q(dir / "v.json"));
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_EQ(read_json(dir / "v.json")["records"].size(), 2u);
  const auto b = test::run_raylab("bench cornell --accel embree --ray-sets random --rays 50 --repeats 1 --min-time 0 -t 1 -q -o " +
                                  q(dir / "b.json"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(read_json(dir / "b.json")["records"].size(), 1u);
}

TEST(CliVocabulary, MinusOIsTheOutputEverywhereAndOldSpellingsSayTheNewOne) {
  const auto dir = test::temp_dir("voc_out");
  for (const auto& [cmd, file] : std::vector<std::pair<std::string, std::string>>{
           {"verify soup:n=30 --accel bvh --rays 50 -q", "v.json"},
           {"stress single --accel bvh --ray-scale 0.01 -q", "s.json"},
           {"bench soup:n=30 --accel embree --ray-sets random --rays 50 --repeats 1 --min-time 0 -t 1 -q", "b.json"},
           {"render soup:n=30 -s 1 --size 8x8 -q", "r.png"},
           {"rays soup:n=30 --ray-sets random --rays 10", "r.rays"},
           {"show soup:n=30 --size 16x16", "s.ply"}}) {
    for (const char* flag : {"-o", "--out"}) {
      const fs::path out = dir / (std::string(flag == std::string("-o") ? "short_" : "long_") + file);
      const auto r = test::run_raylab(cmd + " " + flag + " " + q(out));
      EXPECT_EQ(r.exit_code, 0) << cmd << " " << flag << "\n" << r.output;
      EXPECT_TRUE(fs::exists(out)) << cmd << " " << flag;
    }
  }
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"verify --json x.json", "--json was renamed: use -o/--out FILE"},
           {"stress --json x.json", "--json was renamed: use -o/--out FILE"},
           {"bench --json x.json", "--json was renamed: use -o/--out FILE"},
           {"bench --random-rays 5", "--random-rays was renamed: use --rays N"},
           {"compare a b --json -", "--json was renamed: use -o/--out FILE"},
           {"compare a b --min-change 3", "--min-change was renamed: use --min-effect PCT"},
           {"render --json t.json", "--json was renamed: use --timings FILE"},
           {"rays cornell --set random -o x.rays", "--set was renamed: use --ray-sets NAME"},
           {"rays cornell --count 5 -o x.rays", "--count was renamed: use --rays N"}}) {
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(message)) << args;
  }
}

TEST(CliVocabulary, HelpAndMessagesSayWhatIsAccepted) {
  // --accel lists are separated by ';' (the README's form), as the help says.
  for (const char* cmd : {"verify", "stress", "bench"}) {
    const auto h = test::run_raylab(std::string(cmd) + " --help");
    EXPECT_THAT(h.output, HasSubstr("accelerator specs separated by ';'")) << cmd;
    EXPECT_THAT(h.output, Not(HasSubstr("accelerator specs, comma separated"))) << cmd;
  }
  const auto v = test::run_raylab("verify soup:n=30 --accel 'bvh:leaf=2;kdtree' --rays 30 -q");
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_THAT(v.output, HasSubstr("kdtree"));
  // EXR is written as 32-bit float, and the help says so.
  const auto render = test::run_raylab("render --help");
  EXPECT_THAT(render.output, HasSubstr(".exr (linear 32-bit float)"));
  EXPECT_THAT(render.output, Not(HasSubstr("half")));
  // show's default depth is the one the README's pictures use.
  EXPECT_THAT(test::run_raylab("show --help").output, ::testing::ContainsRegex("--depth INT[^\n]*=4\n"));
  // Limits are named; rays takes one set and says why.
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"render --size 100000x100000", "at most 65536"},
           {"rays cornell --ray-sets primary,random -o x.rays", "a ray file holds one ray set"}}) {
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_THAT(r.output, HasSubstr(message)) << args;
  }
}

TEST(CliVocabulary, ErrorsPointToTheSubcommandsOwnHelp) {
  for (const char* cmd : {"render", "verify", "stress", "bench", "info"}) {
    const auto r = test::run_raylab(std::string(cmd) + " --frobnicate");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(std::string("raylab ") + cmd + ": error:")) << cmd;
    EXPECT_THAT(r.output, HasSubstr(std::string("see raylab ") + cmd + " --help")) << cmd;
  }
  // Value errors found after parsing point there too.
  const auto r = test::run_raylab("render --size 3by4");
  EXPECT_THAT(r.output, HasSubstr("see raylab render --help")) << r.output;
}

TEST(CliVocabulary, MessagesSayWhatIsWrong) {
  const auto dir = test::temp_dir("voc_messages");
  // `-o` is an option now, so the image name is not taken for a second scene.
  const auto o = test::run_raylab("render --scene cornell -s 1 --size 8x8 -q -o " + q(dir / "x.png"));
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_TRUE(fs::exists(dir / "x.png"));
  // render takes one accelerator: 'all' and lists are refused as such, not as unknown names.
  for (const char* accel : {"all", "bvh,kdtree"}) {
    const auto r = test::run_raylab(std::string("render --accel ") + accel + " -o " + q(dir / "y.png"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr("render uses one accelerator")) << accel;
    EXPECT_THAT(r.output, Not(HasSubstr("unknown accelerator"))) << accel;
  }
  EXPECT_FALSE(fs::exists(dir / "y.png"));
}

TEST(CliOutput, ExrIsLinearFloatAndExtensionsIgnoreCase) {
  const auto dir = test::temp_dir("out_exr");
  const std::string common = "render cornell -s 2 --size 20x16 -t 1 -q ";
  ASSERT_EQ(test::run_raylab(common + "-o " + q(dir / "a.pfm")).exit_code, 0);
  const auto e = test::run_raylab(common + "-o " + q(dir / "a.EXR"));
  ASSERT_EQ(e.exit_code, 0) << e.output;
  const Image pfm = read_pfm((dir / "a.pfm").string());
  const Image exr = read_exr((dir / "a.EXR").string());
  ASSERT_EQ(exr.width, 20);
  ASSERT_EQ(exr.height, 16);
  EXPECT_EQ(exr.rgb, pfm.rgb);  // same deterministic render, stored as 32-bit floats
  EXPECT_GT(exr.mean().sum(), 0.0f);
  const auto p = test::run_raylab(common + "-o " + q(dir / "b.PNG"));
  EXPECT_EQ(p.exit_code, 0) << p.output;
  std::ifstream png(dir / "b.PNG", std::ios::binary);
  std::string magic(4, '\0');
  png.read(magic.data(), 4);
  EXPECT_EQ(magic.substr(1, 3), "PNG");
  const auto bad = test::run_raylab(common + "-o " + q(dir / "c.tiff"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.output, HasSubstr(".exr"));
}

TEST(CliOutput, DefaultOutputNameIsTheScenesShortName) {
  const auto dir = test::temp_dir("out_default");
  const std::string mesh = test::write_file(dir, "little_tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto r = test::run_raylab_in(dir, "render " + q(mesh) + " -s 1 --size 8x8 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "little_tri.png")) << r.output;
  EXPECT_THAT(r.output, HasSubstr("1 triangle ")) << r.output;  // not "1 triangles"
  const auto s = test::run_raylab_in(dir, "render sphereflake:level=1 -s 1 --size 8x8 -q");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "sphereflake_level_1.png")) << s.output;
}

// Starts raylab with stdout and stderr on a pipe; returns its pid and the read end.
std::pair<pid_t, int> spawn_raylab(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe(fds) != 0) return {-1, -1};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> argv;
    std::string bin = RAYLAB_BINARY;
    argv.push_back(bin.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(RAYLAB_BINARY, argv.data());
    _exit(127);
  }
  close(fds[1]);
  return {pid, fds[0]};
}

// Reads the child's stdout until `marker` appears (or EOF); returns what was read.
std::string read_until(int fd, const std::string& marker) {
  std::string got;
  char buf[4096];
  while (got.find(marker) == std::string::npos) {
    const ssize_t n = read(fd, buf, sizeof buf);
    if (n <= 0) break;
    got.append(buf, static_cast<size_t>(n));
  }
  return got;
}

// Sends SIGINT, drains the output, waits; the exit code, and in `seconds`
// how long the process took to end after the signal.
int interrupt_and_wait(pid_t pid, int fd, double* seconds = nullptr) {
  const auto sent = std::chrono::steady_clock::now();
  kill(pid, SIGINT);
  char buf[4096];
  while (read(fd, buf, sizeof buf) > 0) {
  }
  close(fd);
  int status = 0;
  waitpid(pid, &status, 0);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Generous for a loaded 2-core CI machine; a cell interrupted only at its
// end takes minutes (brute force over 20000 triangles x 200000 rays).
constexpr double kStopWithinSeconds = 5.0;

TEST(CliInterrupt, CtrlCInVerifyKeepsFinishedRecordsAndExits130) {
  const auto dir = test::temp_dir("int_verify");
  const auto json = dir / "v.json";
  // Many slow brute-force records: far from done when the signal comes.
  std::vector<std::string> args = {"verify", "soup:n=5000", "--ray-sets", "primary,random", "--rays", "2048",
                                   "--accel", "bvh,brute,brute,brute,brute,brute,brute,brute", "-t", "1", "-o", json.string()};
  auto [pid, fd] = spawn_raylab(args);
  ASSERT_GT(pid, 0);
  const std::string head = read_until(fd, "result");  // the table header: the handler is installed
  ASSERT_THAT(head, HasSubstr("result"));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(interrupt_and_wait(pid, fd), 130);
  const auto j = read_json(json);
  EXPECT_EQ(j["complete"], false);
  EXPECT_LT(j["records"].size(), 16u);
  for (const auto& rec : j["records"]) EXPECT_EQ(rec["raylab_wrong"], 0);
}

TEST(CliInterrupt, CtrlCInStressKeepsFinishedRecordsAndExits130) {
  const auto dir = test::temp_dir("int_stress");
  const auto json = dir / "s.json";
  auto [pid, fd] = spawn_raylab({"stress", "--accel", "bvh", "--ray-scale", "0.1", "-t", "1", "-o", json.string()});
  ASSERT_GT(pid, 0);
  // The first finished row (the header ends with "leaks/M").
  const std::string head = read_until(fd, "leaks/M\n");
  std::string rows = read_until(fd, "\n");
  ASSERT_FALSE(rows.empty()) << head;
  EXPECT_EQ(interrupt_and_wait(pid, fd), 130);
  const auto j = read_json(json);
  EXPECT_EQ(j["complete"], false);
  EXPECT_GE(j["records"].size(), 1u);
  const auto full = test::run_raylab("stress --list");
  EXPECT_LT(j["records"].size(), 2 * static_cast<size_t>(std::count(full.output.begin(), full.output.end(), '\n')));
}

// A long command interrupted in the middle of its work: started with
// `args` (its output file last), signalled `delay_ms` after `marker` appears
// in its output (at once when empty); the exit code, the seconds it took to
// end after the signal, and its JSON report (null when none was written).
struct Interrupted {
  int exit_code = -1;
  double seconds = 0;
  std::string output;
  nlohmann::json report;
};
Interrupted interrupt_mid_run(const std::vector<std::string>& args, const std::string& marker, int delay_ms) {
  Interrupted r;
  auto [pid, fd] = spawn_raylab(args);
  if (pid <= 0) return r;
  if (!marker.empty()) r.output = read_until(fd, marker);
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  r.exit_code = interrupt_and_wait(pid, fd, &r.seconds);
  if (fs::exists(args.back()) && args.back().size() > 5 && args.back().substr(args.back().size() - 5) == ".json")
    r.report = read_json(args.back());
  return r;
}

TEST(CliInterrupt, CtrlCStopsVerifyInsideABruteForceRecord) {
  // verify's brute force over 20000 triangles x 200000 rays takes minutes; Ctrl-C
  // in the middle of it stops within seconds, keeping the finished bvh records
  // (printed as they finish; brute is running after them).
  const auto json = test::temp_dir("int_verify_cell") / "v.json";
  const auto r = interrupt_mid_run({"verify", "soup:n=20000", "--accel", "bvh;brute", "--rays", "200000", "-t", "1",
                                    "-q", "-o", json.string()},
                                   "random", 500);
  ASSERT_THAT(r.output, ::testing::ContainsRegex("bvh +random")) << r.output;
  EXPECT_EQ(r.exit_code, 130);
  EXPECT_LT(r.seconds, kStopWithinSeconds);
  EXPECT_EQ(r.report["complete"], false);
  ASSERT_EQ(r.report["records"].size(), 2u) << r.report.dump();
  for (const auto& rec : r.report["records"]) EXPECT_EQ(rec["accel"], "bvh");
}

TEST(CliInterrupt, CtrlCStopsBenchInsideACell) {
  // One brute-force cell timed 30 times: far longer than the bound. Embree's
  // cell is done when its line appears (stderr, not a terminal).
  const auto json = test::temp_dir("int_bench_cell") / "b.json";
  const auto r = interrupt_mid_run({"bench", "soup:n=4000", "--accel", "embree;brute", "--ray-sets", "random", "--rays",
                                    "50000", "--repeats", "30", "--min-time", "0", "-t", "1", "-o", json.string()},
                                   "embree random t=1", 1000);
  ASSERT_THAT(r.output, HasSubstr("embree random t=1")) << r.output;
  EXPECT_EQ(r.exit_code, 130);
  EXPECT_LT(r.seconds, kStopWithinSeconds);
  EXPECT_EQ(r.report["complete"], false);
  ASSERT_EQ(r.report["records"].size(), 1u) << r.report.dump();
  EXPECT_EQ(r.report["records"][0]["accel"], "embree");
}

TEST(CliInterrupt, CtrlCStopsStressInsideARecord) {
  // Brute force on the stadium with a 120 s budget: interrupted within seconds.
  const auto json = test::temp_dir("int_stress_cell") / "s.json";
  const auto r = interrupt_mid_run(
      {"stress", "stadium", "--accel", "brute", "--budget", "120", "-t", "1", "-q", "-o", json.string()}, "leaks/M\n",
      1500);
  ASSERT_THAT(r.output, HasSubstr("leaks/M"));
  EXPECT_EQ(r.exit_code, 130);
  EXPECT_LT(r.seconds, kStopWithinSeconds);
  EXPECT_EQ(r.report["complete"], false);
  EXPECT_EQ(r.report["records"].size(), 0u) << "the interrupted record is dropped, not kept half-done";
}

TEST(CliInterrupt, CtrlCStopsARenderAndWritesNoImage) {
  const auto dir = test::temp_dir("int_render");
  const auto png = dir / "r.png";
  const auto r = interrupt_mid_run({"render", "cornell", "-s", "20000", "--size", "64x64", "-t", "1", "-q", "--timings",
                                    (dir / "r.json").string(), "-o", png.string()},
                                   "", 1500);
  EXPECT_EQ(r.exit_code, 130);
  EXPECT_LT(r.seconds, kStopWithinSeconds);
  EXPECT_FALSE(fs::exists(png)) << "a partial image would pass for a finished one";
  EXPECT_FALSE(fs::exists(dir / "r.json"));
}

TEST(CliNotes, SecondarySetsThatHoldFewerRaysSaySo) {
  // Half the primary rays of this view miss the single quad, so diffuse and shadow sets are smaller.
  const auto r = test::run_raylab("verify soup:n=50 --accel bvh --ray-sets primary,diffuse,shadow --rays 2000 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("note: ray set 'diffuse' holds"));
  EXPECT_THAT(r.output, HasSubstr("primary hits"));
  EXPECT_THAT(r.output, Not(HasSubstr("note: ray set 'primary'")));
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

// Bounding box (x0, y0, x1, y1) of the pixels that differ from the sky colour.
std::array<int, 4> object_extent(const Image& img, float sky) {
  std::array<int, 4> e = {img.width, img.height, -1, -1};
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (std::fabs(img.pixel(x, y).x() - sky) > 1e-4f) {
        e[0] = std::min(e[0], x);
        e[1] = std::min(e[1], y);
        e[2] = std::max(e[2], x);
        e[3] = std::max(e[3], y);
      }
  return e;
}

TEST(CliCamera, UpAxisStandsAZUpMeshUpright) {
  const auto dir = test::temp_dir("cam_up");
  // A post 8 units tall along +z (as Blender, STL and DXF files store "up").
  std::string obj;
  for (int i = 0; i < 8; ++i) {
    const float x = (i & 1) ? 0.5f : -0.5f, y = (i & 2) ? 0.5f : -0.5f, z = (i & 4) ? 8.0f : 0.0f;
    obj += "v " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
  }
  obj += "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n";
  const std::string mesh = test::write_file(dir, "post.obj", obj);
  const std::string common = "render " + q(mesh) + " -s 1 --size 64x64 -t 1 -q --background 1 ";
  ASSERT_EQ(test::run_raylab(common + "-o " + q(dir / "y.pfm")).exit_code, 0);
  const auto r = test::run_raylab(common + "--up z -o " + q(dir / "z.pfm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto ey = object_extent(read_pfm((dir / "y.pfm").string()), 1.0f);
  const auto ez = object_extent(read_pfm((dir / "z.pfm").string()), 1.0f);
  const int wy = ey[2] - ey[0], hy = ey[3] - ey[1], wz = ez[2] - ez[0], hz = ez[3] - ez[1];
  ASSERT_GT(wz, 0);
  EXPECT_GT(hz, 3 * wz) << "--up z: the post should stand upright";
  EXPECT_LT(hy, 3 * wy) << "y up: the post lies on its side";
  EXPECT_EQ(test::run_raylab(common + "--up w -o " + q(dir / "w.pfm")).exit_code, 2);
}

TEST(CliCamera, CameraAndBackgroundOverrideTheScene) {
  const auto dir = test::temp_dir("cam_override");
  const std::string common = "render soup:n=20 -s 1 --size 32x32 -t 1 -q ";
  ASSERT_EQ(test::run_raylab(common + "--background 0.25,0.5,1 -o " + q(dir / "bg.pfm")).exit_code, 0);
  const Image bg = read_pfm((dir / "bg.pfm").string());
  // A camera looking away from everything sees only the background.
  const auto away = test::run_raylab(common + "--background 0.25,0.5,1 --camera from=0,0,100,at=0,0,200,fov=10 -o " +
                                     q(dir / "away.pfm"));
  ASSERT_EQ(away.exit_code, 0) << away.output;
  const Image img = read_pfm((dir / "away.pfm").string());
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) ASSERT_TRUE(img.pixel(x, y).isApprox(Vec3f(0.25f, 0.5f, 1.0f), 1e-5f)) << x << "," << y;
  EXPECT_NE(bg.rgb, img.rgb);
  for (const auto& [arg, message] : std::vector<std::pair<std::string, std::string>>{
           {"--camera from=1,2", "three numbers"},
           {"--camera eye=0,0,1", "unknown key 'eye'"},
           {"--camera from=0,0,0,at=0,0,0", "--camera"},
           {"--background -1", "non-negative"}}) {
    const auto r = test::run_raylab(common + arg + " -o " + q(dir / "bad.png"));
    EXPECT_EQ(r.exit_code, 2) << arg << r.output;
    EXPECT_THAT(r.output, HasSubstr(message)) << arg;
  }
  EXPECT_FALSE(fs::exists(dir / "bad.png"));
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

TEST(CliNumbers, NotApplicableFiguresShowNaAndListingsAlign) {
  // Embree reports no tree: n/a, not "nodes 0" or "sah nan".
  const auto info = test::run_raylab("info soup:n=100 --accel embree,bvh");
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_THAT(info.output, Not(HasSubstr("nan")));
  EXPECT_THAT(info.output, HasSubstr("sah_cost   n/a"));
  EXPECT_THAT(info.output, HasSubstr("nodes      n/a"));
  const auto bench = test::run_raylab("bench soup:n=100 --accel embree,bvh --ray-sets random --rays 100 --repeats 1 --min-time 0 -t 1 -q");
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  EXPECT_THAT(bench.output, Not(HasSubstr("sah nan")));
  EXPECT_THAT(bench.output, HasSubstr("sah n/a, nodes n/a"));
  EXPECT_THAT(bench.output, ::testing::ContainsRegex("embree +random +1 .* n/a +n/a\n"));
  // No other Embree mode ran: no "x best" and "best embree" columns repeating "x embree".
  EXPECT_THAT(bench.output, Not(HasSubstr("best embree")));
  EXPECT_THAT(bench.output, HasSubstr("x embree"));
  // raylab accels: every parameter's help text starts in the same column.
  const auto accels = test::run_raylab("accels");
  std::istringstream lines(accels.output);
  std::set<size_t> columns;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("    ", 0) != 0) continue;
    const auto gap = line.find("  ", 4);
    ASSERT_NE(gap, std::string::npos) << line;
    columns.insert(line.find_first_not_of(' ', gap));
  }
  EXPECT_EQ(columns.size(), 1u) << accels.output;
}

TEST(CliNumbers, DepthCappedKdTreeWarnsAndOneTriangleIsSingular) {
  const auto capped = test::run_raylab("info soup:n=3000 --accel kdtree:max_depth=4");
  ASSERT_EQ(capped.exit_code, 0) << capped.output;
  EXPECT_THAT(capped.output, HasSubstr("warning: kdtree:max_depth=4: the tree reached its depth cap (4 levels)"));
  const auto free = test::run_raylab("info cornell --accel kdtree");  // depth 14 of 15
  EXPECT_THAT(free.output, Not(HasSubstr("depth cap")));
  const auto bench = test::run_raylab("bench soup:n=3000 --accel kdtree:max_depth=4 --ray-sets random --rays 100 --repeats 1 --min-time 0 -t 1 -q");
  EXPECT_THAT(bench.output, HasSubstr("warning: kdtree:max_depth=4: the tree reached its depth cap"));
  const auto one = test::run_raylab("verify soup:n=1 --accel bvh --rays 10 -q");
  ASSERT_EQ(one.exit_code, 0) << one.output;
  EXPECT_THAT(one.output, HasSubstr("(1 triangle)"));
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

TEST(CliMessages, MalformedNumberNamesItsLine) {
  const auto dir = test::temp_dir("msg_nff");
  // An NFF cone record whose numbers are followed by a texture name (as in Assimp's NFF/cone.nff).
  const std::string nff = test::write_file(dir, "cone.nff", "c 0 0 0 1 1 0 0 2\ncantfindme.png 2\n");
  const auto r = test::run_raylab("info " + q(nff));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_THAT(r.output, HasSubstr("malformed number 'cantfindme.png' at line 2"));
}

TEST(CliMessages, Utf16TextFilesOfEveryFormatAreNamedAsSuch) {
  const auto dir = test::temp_dir("msg_utf16");
  auto utf16le = [](const std::string& ascii) {
    std::string out = "\xFF\xFE";
    for (char c : ascii) out += std::string(1, c) + std::string(1, '\0');
    return out;
  };
  const std::string dae = "<?xml version=\"1.0\" encoding=\"utf-16\"?>\n<COLLADA version=\"1.4.1\"></COLLADA>\n";
  const std::string ac = "AC3Db\nMATERIAL \"\" rgb 1 1 1 amb 0.2 0.2 0.2 emis 0 0 0 spec 0 0 0 shi 0 trans 0\nOBJECT world\nkids 0\n";
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{{"box.dae", dae}, {"box.ac", ac}}) {
    const std::string path = test::write_file(dir, name, utf16le(text));
    const auto r = test::run_raylab("info " + q(path));
    EXPECT_EQ(r.exit_code, 2) << name << r.output;
    EXPECT_THAT(r.output, HasSubstr("UTF-16 text")) << name;
    EXPECT_THAT(r.output, Not(HasSubstr("XML"))) << name;
  }
}

}  // namespace
}  // namespace raylab

#include "scenes/mesh_import.h"

namespace raylab {
namespace {

TEST(CliCamera, GltfCameraIsHonoured) {
  const auto dir = test::temp_dir("cam_gltf");
  test::GltfPrimitive tri;
  tri.xyz = {-1, 0, 0, 1, 0, 0, 0, 1, 0};
  tri.indices = {0, 1, 2};
  std::string buffer;
  nlohmann::json doc = test::gltf_document({tri}, buffer);
  doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + test::base64(buffer);
  doc["cameras"] = nlohmann::json::array({{{"type", "perspective"},
                                           {"perspective", {{"yfov", 0.6}, {"aspectRatio", 1.0}, {"znear", 0.01}}}}});
  // Placed at (4, 0.5, 0), turned 90 degrees about +y: it looks along -x, at the triangle.
  doc["nodes"].push_back({{"camera", 0}, {"translation", {4, 0.5, 0}}, {"rotation", {0, 0.70710678, 0, 0.70710678}}});
  doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
  const std::string path = test::write_file(dir, "cam.gltf", doc.dump());
  const Scene s = load_mesh_file(path);
  EXPECT_TRUE(s.view.from.isApprox(Vec3f(4, 0.5f, 0), 1e-4f)) << s.view.from.transpose();
  const Vec3f dir_seen = (s.view.at - s.view.from).normalized();
  EXPECT_TRUE(dir_seen.isApprox(Vec3f(-1, 0, 0), 1e-4f)) << dir_seen.transpose();
  EXPECT_NEAR(s.view.fov_deg, 0.6 * 180 / 3.14159265, 0.01);
  // Without a camera: the default framing, unchanged.
  const std::string plain = test::write_file(dir, "plain.gltf", test::gltf_embedded({tri}));
  EXPECT_FALSE(load_mesh_file(plain).view.from.isApprox(Vec3f(4, 0.5f, 0), 1e-2f));
}

TEST(CliCamera, ColladaCameraKeepsItsVerticalFieldOfView) {
  // Assimp stores Collada's camera as the full horizontal angle (54.4 degrees
  // for yfov 37.8 at aspect 1.5): read as a half angle it became 86 degrees and
  // the model a speck (assimp-testmodels' duck.dae).
  const auto dir = test::temp_dir("cam_dae");
  const std::string dae = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="1" name="meter"/><up_axis>Y_UP</up_axis></asset>
  <library_cameras><camera id="cam" name="cam"><optics><technique_common><perspective>
    <yfov>37.8492</yfov><aspect_ratio>1.5</aspect_ratio><znear>0.1</znear><zfar>100</zfar>
  </perspective></technique_common></optics></camera></library_cameras>
  <library_geometries><geometry id="tri" name="tri"><mesh>
    <source id="pos"><float_array id="pos-a" count="9">-1 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#pos-a" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="verts"><input semantic="POSITION" source="#pos"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#verts" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene" name="scene">
    <node id="camnode" name="camnode"><translate>0 0.5 5</translate><instance_camera url="#cam"/></node>
    <node id="trinode" name="trinode"><instance_geometry url="#tri"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
  const Scene s = load_mesh_file(test::write_file(dir, "cam.dae", dae));
  EXPECT_NEAR(s.view.fov_deg, 37.8492, 0.05);
  EXPECT_TRUE(s.view.from.isApprox(Vec3f(0, 0.5f, 5), 1e-4f)) << s.view.from.transpose();
  const Vec3f dir_seen = (s.view.at - s.view.from).normalized();
  EXPECT_TRUE(dir_seen.isApprox(Vec3f(0, 0, -1), 1e-4f)) << dir_seen.transpose();
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

TEST(CliCamera, PlainMeshesGetAKeyLightWithShadowsUnderADimSky) {
  const auto dir = test::temp_dir("cam_key");
  // A ground quad and a cube floating above it.
  std::string obj = "v -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\n";
  for (int i = 0; i < 8; ++i)
    obj += "v " + std::to_string((i & 1) ? 1 : -1) + " " + std::to_string((i & 2) ? 3 : 1) + " " +
           std::to_string((i & 4) ? 1 : -1) + "\n";
  obj += "f 1 4 3 2\nf 5 7 8 6\nf 9 10 12 11\nf 5 6 10 9\nf 7 11 12 8\nf 5 9 11 7\nf 6 8 12 10\n";
  const std::string mesh = test::write_file(dir, "scene.obj", obj);
  const Scene s = load_mesh_file(mesh);
  EXPECT_GT(s.key_light.minCoeff(), 0.0f);
  EXPECT_LT(s.background.maxCoeff(), 0.5f) << "a dim sky: objects stand out against it";
  EXPECT_GT(s.key_light_dir.dot(s.view.up.normalized()), 0.5f) << "the light comes from above";
  const auto r = test::run_raylab("render " + q(mesh) + " -s 16 --size 48x48 -t 1 -q -o " + q(dir / "k.pfm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image img = read_pfm((dir / "k.pfm").string());
  // The ground has lit pixels and pixels in the cube's shadow: several times darker.
  float lo = 1e9f, hi = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float v = img.pixel(x, y).x();
      if (std::fabs(v - s.background.x()) < 1e-4f) continue;  // sky
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  EXPECT_GT(hi, 3 * lo) << "no shadow or shading contrast: lo " << lo << " hi " << hi;
  EXPECT_LT(hi, 1.0f) << "washed out";
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

TEST(CliVocabulary, RaysCommandSpeaksTheSameVocabulary) {
  const auto dir = test::temp_dir("voc_rays_cmd");
  // Positional scene, --ray-sets for the set, --rays for the count, -o for the file.
  const auto r = test::run_raylab("rays soup:n=50 --ray-sets random --rays 321 -o " + q(dir / "r.rays"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("321 random rays"));
  const auto b = test::run_raylab("bench soup:n=50 --ray-file " + q(dir / "r.rays") +
                                  " --accel embree --repeats 1 --min-time 0 -t 1 -q -o " + q(dir / "b.json"));
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(read_json(dir / "b.json")["records"][0]["rays"], 321);
  const auto two = test::run_raylab("rays cornell --ray-sets primary,random -o " + q(dir / "x.rays"));
  EXPECT_EQ(two.exit_code, 2);
  EXPECT_THAT(two.output, HasSubstr("write one file per set"));
  const auto name = test::run_raylab("rays cornell --ray-sets random --rays random -o " + q(dir / "x.rays"));
  EXPECT_EQ(name.exit_code, 2);
  EXPECT_THAT(name.output, HasSubstr("--ray-sets"));
  EXPECT_FALSE(fs::exists(dir / "x.rays"));
}

}  // namespace
}  // namespace raylab

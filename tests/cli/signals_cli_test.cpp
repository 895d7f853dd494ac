// A run stopped by SIGTERM or SIGINT removes its partial output and exits
// with 128 + the signal; what a killed run left is removed by the next one.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli_support.h"

namespace spec2fab_cli_test {
namespace {

using ::testing::HasSubstr;

// Starts a long run — a two-material sphere fabricated at the J750's
// resolution (1.3e9 voxels, tens of seconds; every build has what it
// needs) — waits for its partial folder, sends `signal`, and returns the
// run's exit code and output.
Result stop_a_run(const fs::path& dir, const std::string& body, const std::string& signal) {
  const fs::path file = dir / "long.json";
  std::ofstream(file) << body;
  const std::string out = (dir / "run").string();
  const std::string script =
      std::string(SPEC2FAB_CLI_PATH) + " run -q " + file.string() + " --out " + out + " & pid=$!; " +
      "for i in $(seq 1 1200); do ls -d " + (dir / ".run.partial-").string() + "* >/dev/null 2>&1 && break; sleep 0.05; done; " +
      "sleep 0.5; kill -" + signal + " $pid; wait $pid";
  return run_command("sh -c '" + script + "'");
}

/// The run folder and staging folders of the run into `dir`/run.
std::vector<std::string> leftovers(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name == "run" || name.rfind(".run.partial-", 0) == 0) out.push_back(name);
  }
  return out;
}

std::string long_run_body(const Cli& /*fixture*/) {
  return R"({"translator": "tree", "geometry": {"mesh": ")" + (kDatasets / "meshes/sphere_r25.obj").string() +
         R"(", "uv": "mesh"}, "goal": {"tree": {"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}}},
         "output": {"stl": false, "3mf": false, "render": false}, "materials": ")" +
         (kDatasets / "materials/polyjet.json").string() + R"(", "printer": ")" + (kDatasets / "printers/j750.json").string() + R"("})";
}

TEST_F(Cli, SigtermRemovesThePartialOutputAndExits143) {
  const Result r = stop_a_run(dir_, long_run_body(*this), "TERM");
  EXPECT_EQ(r.code, 143) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("stopped by SIGTERM; removed the partial output"));
  EXPECT_THAT(leftovers(dir_), ::testing::IsEmpty());  // no run folder, no partial folder
}

TEST_F(Cli, SigintRemovesThePartialOutputAndExits130) {
  const Result r = stop_a_run(dir_, long_run_body(*this), "INT");
  EXPECT_EQ(r.code, 130) << r.out;
  EXPECT_THAT(r.out, HasSubstr("stopped by SIGINT"));
  EXPECT_THAT(leftovers(dir_), ::testing::IsEmpty());
}

TEST_F(Cli, TheNextRunRemovesWhatAKilledRunLeft) {
  // A process id that is not running: the highest the kernel can hand out, plus one.
  const fs::path stale = dir_ / ".old.partial-99999999";
  fs::create_directories(stale / "preview");
  std::ofstream(stale / "preview" / "half.png") << "x";
  const fs::path alive = dir_ / (".other.partial-" + std::to_string(getpid()));  // this test: alive
  fs::create_directories(alive);
  const Result r = run_spec2fab("run " + experiment("small", valid_body(R"({"type": "layered", "material": "VeroCyan"})",
                                                                       R"(, "output": {"slices": false, "stl": false, "3mf": false, "render": false})"))
                                             .string() +
                                " --out " + (dir_ / "small").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("left by a run that was killed (process 99999999)"));
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(alive));
  EXPECT_TRUE(fs::exists(dir_ / "small" / "result.json"));
}

}  // namespace
}  // namespace spec2fab_cli_test

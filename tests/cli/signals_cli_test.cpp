// A run stopped by SIGTERM or SIGINT removes its partial output and exits
// with 128 + the signal; what a killed run left is removed by the next one.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli_support.h"

namespace spec2fab_cli_test {
namespace {

using ::testing::HasSubstr;

// Starts a long run (the smooth caustics ring: quick to set up, then tens
// of seconds of transport and tuning), waits for its partial folder, sends
// `signal`, and returns its exit code and output.
Result stop_a_run(const fs::path& dir, const std::string& signal) {
  const std::string out = (dir / "run").string();
  const std::string script =
      std::string(SPEC2FAB_CLI_PATH) + " run -q " + (kDatasets / "experiments/smooth_caustics_ring.json").string() +
      " --out " + out + " & pid=$!; " +
      "for i in $(seq 1 1200); do ls -d " + (dir / ".run.partial-").string() + "* >/dev/null 2>&1 && break; sleep 0.05; done; " +
      "sleep 0.5; kill -" + signal + " $pid; wait $pid";
  return run_command("sh -c '" + script + "'");
}

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST_F(Cli, SigtermRemovesThePartialOutputAndExits143) {
  const size_t before = entries(dir_);
  const Result r = stop_a_run(dir_, "TERM");
  EXPECT_EQ(r.code, 143) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("stopped by SIGTERM; removed the partial output"));
  EXPECT_EQ(entries(dir_), before);  // no run folder, no partial folder
}

TEST_F(Cli, SigintRemovesThePartialOutputAndExits130) {
  const size_t before = entries(dir_);
  const Result r = stop_a_run(dir_, "INT");
  EXPECT_EQ(r.code, 130) << r.out;
  EXPECT_THAT(r.out, HasSubstr("stopped by SIGINT"));
  EXPECT_EQ(entries(dir_), before);
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

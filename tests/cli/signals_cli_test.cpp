// A run stopped by SIGTERM or SIGINT removes its partial output and exits
// with 128 + the signal; what a killed run left is removed by the next one,
// or continued by `run --resume` to the files an uninterrupted run writes.

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

// Three phases of 4 x 4 colour patches (albedo tuners on a 4-neighbour
// network): error diffusion, parallel annealing whose temperature schedule
// spans its sweeps (state an optimizer carries between runs), and a serial
// pass; then slices and STLs on a coarse printer.
std::string three_phase_body(const fs::path& printer) {
  std::string tuners;
  const char* colours[] = {"[0.45, 0.75, 0.9]", "[0.9, 0.5, 0.7]", "[0.95, 0.92, 0.45]", "[0.1, 0.65, 0.85]"};
  for (int i = 0; i < 16; ++i) {
    tuners += std::string(i ? ", " : "") + R"({"name": "p)" + std::to_string(i) + R"(", "node": "shell/)" +
              std::to_string(i) + R"(", "simulator": {"type": "albedo", "depth_mm": 1}, "metric": {"type": "ciede2000"},
        "goal": {"type": "albedo", "srgb": )" + colours[i % 4] + R"(},
        "optimizer": {"type": "annealing", "iterations": 6000, "schedule_iterations": 60000, "initial_temperature": 2}})";
  }
  return R"({"translator": "tree", "geometry": {"mesh": ")" + (kDatasets / "meshes/box_40x30x20.stl").string() +
         R"(", "uv": "planar"}, "goal": {"tree": {"type": "stratum", "depth_mm": 1, "shell": {"type": "column", "count": [4, 4],
           "child": {"type": "layered", "layers": [
             {"material": {"value": "VeroCyan", "choices": ["VeroCyan", "VeroMagenta", "VeroYellow"]}, "thickness_mm": {"value": 0.135, "min": 0, "max": 0.54}},
             {"material": {"value": "VeroWhitePlus", "choices": ["VeroWhitePlus", "VeroYellow"]}, "thickness_mm": {"value": 0.2, "min": 0, "max": 0.54}},
             {"material": "VeroWhitePlus"}]}},
           "core": {"type": "layered", "material": "VeroWhitePlus"}},
         "tuners": [)" + tuners + R"(], "network": {"type": "grid4", "width": 4},
         "schedule": [{"name": "diffuse", "mode": "serial", "coupling": "error_diffusion"},
                      {"name": "anneal", "mode": "parallel", "sweeps": 10},
                      {"name": "polish", "mode": "serial", "sweeps": 2}]},
         "output": {"3mf": false, "render": false}, "seed": 3, "materials": ")" +
         (kDatasets / "materials/polyjet.json").string() + R"(", "printer": ")" + printer.string() + R"("})";
}

TEST_F(Cli, AKilledRunResumesFromItsLastPhaseToTheFilesOfAnUninterruptedRun) {
  const fs::path printer = dir_ / "four_inks.json";
  std::ofstream(printer) << R"({"name": "coarse", "technology": "polyjet", "resolution_dpi": [63.5, 63.5], "layer_mm": 0.4,
      "build_volume_mm": [200, 200, 200], "model_materials": ["VeroCyan", "VeroMagenta", "VeroYellow", "VeroWhitePlus"],
      "source": "test"})";
  const fs::path file = experiment("three_phases", three_phase_body(printer));
  const Result whole = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "whole").string() + " --threads 2");
  ASSERT_EQ(whole.code, 0) << whole.out;

  // kill -9 as soon as the first phase's checkpoint is on disk (one thread:
  // the rest takes seconds).
  const std::string partial = (dir_ / ".run.partial-").string();
  const Result killed = run_command(
      "sh -c '" + std::string(SPEC2FAB_CLI_PATH) + " run -q " + file.string() + " --out " + (dir_ / "run").string() +
      " --threads 1 & pid=$!; for i in $(seq 1 3000); do ls " + partial + "*/checkpoint/schedule.cbor >/dev/null 2>&1 && break; "
      "sleep 0.01; done; kill -9 $pid; wait $pid'");
  ASSERT_EQ(killed.code, 128 + 9) << "the run ended before it was killed: " << killed.out;
  ASSERT_EQ(leftovers(dir_).size(), 1u);
  const fs::path left = dir_ / leftovers(dir_).front();

  // A resume of other inputs is refused, and the checkpoint is kept.
  const Result other = run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string() + " --seed 4 --resume");
  EXPECT_EQ(other.code, 2) << other.out;
  EXPECT_THAT(single_line(other.out), HasSubstr("--resume: the killed run had another seed"));
  EXPECT_TRUE(fs::exists(left / "checkpoint" / "schedule.cbor"));

  const Result resumed = run_spec2fab("run " + file.string() + " --out " + (dir_ / "run").string() + " --threads 2 --resume");
  ASSERT_EQ(resumed.code, 0) << resumed.out;
  EXPECT_THAT(resumed.out, HasSubstr("resuming after phase '"));
  expect_same_files(files_of(dir_ / "whole"), dir_ / "run", "after --resume");
  EXPECT_THAT(leftovers(dir_), ::testing::ElementsAre("run"));
  EXPECT_FALSE(fs::exists(dir_ / "run" / "checkpoint"));
}

}  // namespace
}  // namespace spec2fab_cli_test

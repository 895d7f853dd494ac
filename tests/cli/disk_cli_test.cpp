// Disk and file-system faults (issue 37): a run whose print cannot fit is
// refused before any work with the figures (exit 2); a write the system
// refuses later is one line naming the file and the system's reason (exit
// 3); either way nothing is left behind. The full disk is a tmpfs the test
// mounts (skipped, with the reason, where this process may not mount); the
// refused write also comes from a file-size limit (ulimit -f), which needs
// no privilege.

#include <sys/mount.h>

#include <cerrno>
#include <cstring>

#include "build_gates.h"
#include "cli_support.h"

namespace spec2fab_cli_test {
namespace {

using ::testing::HasSubstr;

class DiskFaults : public Cli {
 protected:
  /// A tmpfs of `size` (e.g. "200k") at dir_/small; "" when mounted, else why not.
  std::string mount_small_disk(const std::string& size) {
    small_ = dir_ / "small";
    fs::create_directories(small_);
    if (::mount("tmpfs", small_.c_str(), "tmpfs", 0, ("size=" + size).c_str()) != 0)
      return std::string("cannot mount a tmpfs here: ") + std::strerror(errno);
    mounted_ = true;
    return "";
  }
  ~DiskFaults() override {
    if (mounted_) ::umount2(small_.c_str(), MNT_DETACH);
  }
  /// What is in `folder`, hidden entries included.
  static std::vector<std::string> entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
    return names;
  }
  fs::path small_;
  bool mounted_ = false;
};

TEST_F(DiskFaults, APrintThatCannotFitIsRefusedBeforeAnyWork) {
  if (const std::string why = mount_small_disk("2m"); !why.empty()) GTEST_SKIP() << why;
  // 0.04 mm voxels over a 50 mm sphere: ~2e9 voxels, ~100 MB of slices estimated.
  std::ofstream(dir_ / "fine_printer.json")
      << R"({"name": "fine", "technology": "polyjet", "resolution_dpi": [635, 635], "layer_mm": 0.04,
             "build_volume_mm": [200, 200, 200], "model_materials": ["VeroCyan", "VeroWhitePlus"],
             "source": "test"})";
  std::string body = valid_body(R"({"type": "layered", "material": "VeroCyan"})");
  body.replace(body.find("coarse_printer.json"), 19, "fine_printer.json");
  const fs::path file = experiment("e", body);
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + (small_ / "out").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("the run's files need ~"));
  EXPECT_THAT(r.out, HasSubstr("free on " + small_.string()));
  EXPECT_TRUE(entries(small_).empty()) << "nothing is written before the refusal";
}

TEST_F(DiskFaults, AWriteTheFullDiskRefusesIsExitThreeAndLeavesNothing) {
  // The coarse print's slices are estimated at ~100 kB and fit; its meshes,
  // 3MF and previews do not.
  if (const std::string why = mount_small_disk("200k"); !why.empty()) GTEST_SKIP() << why;
  const fs::path file = experiment("e", valid_body(R"({"type": "layered", "material": "VeroCyan"})"));
  const Result r = run_spec2fab("run -q " + file.string() + " --out " + (small_ / "out").string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("error: cannot write " + (small_ / "out").string() + "/"));
  EXPECT_THAT(r.out, HasSubstr(": No space left on device"));
  EXPECT_TRUE(entries(small_).empty()) << "the partial folder is removed";
}

TEST_F(DiskFaults, AFileSizeLimitIsAWriteErrorForRunAndExport) {
  const fs::path file = experiment("e", valid_body(R"({"type": "layered", "material": "VeroCyan"})"));
  const fs::path out = dir_ / "out";
  // 16 kB per file (bash counts 1024-byte blocks): the first mesh or preview goes past it.
  Result r = run_command("ulimit -f 16; " + std::string(SPEC2FAB_CLI_PATH) + " run -q " + file.string() +
                         " --out " + out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("error: cannot write " + out.string() + "/"));
  EXPECT_THAT(r.out, HasSubstr(": File too large"));
  for (const std::string& name : entries(dir_))
    EXPECT_EQ(name.find(".out.partial"), std::string::npos) << "left behind: " << name;
  EXPECT_FALSE(fs::exists(out));

  // export of a finished run, under the same limit.
  ASSERT_EQ(run_spec2fab("run -q " + file.string() + " --out " + out.string()).code, 0);
  const fs::path exported = dir_ / "exported";
  r = run_command("ulimit -f 16; " + std::string(SPEC2FAB_CLI_PATH) + " export -q " + out.string() + " --printer " +
                  (dir_ / "coarse_printer.json").string() + " --out " + exported.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("error: cannot write " + exported.string() + "/"));
  EXPECT_FALSE(fs::exists(exported));
}

TEST_F(DiskFaults, AFileSizeLimitIsAWriteErrorForBench) {
  const fs::path out = dir_ / "bench";
  // 2 kB per file: the first plot goes past it.
  const Result r = run_command("ulimit -f 2; " + std::string(SPEC2FAB_CLI_PATH) + " bench -q --out " + out.string() +
                               " --problems albedo_column --optimizers exhaustive --seeds 1");
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("error: cannot write " + out.string() + "/"));
  EXPECT_THAT(r.out, HasSubstr(": File too large"));
  EXPECT_FALSE(fs::exists(out));
  for (const std::string& name : entries(dir_))
    EXPECT_EQ(name.find(".bench.partial"), std::string::npos) << "left behind: " << name;
}

TEST_F(DiskFaults, ASimulationThatCannotFitIsRefusedBeforeSimulating) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_TETGEN);
  if (const std::string why = mount_small_disk("2m"); !why.empty()) GTEST_SKIP() << why;
  // The cantilever at 1 mm³ tets: its fem.vtu, displacements and surface are
  // estimated from the mesh (~4 MB) once it is made, before the solve.
  const Result r = run_spec2fab("simulate -q fem " + (kDatasets / "simulations/fem_cantilever.json").string() +
                                " --out " + (small_ / "out").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("the simulation's files need ~"));
  EXPECT_THAT(r.out, HasSubstr("free on " + small_.string()));
  EXPECT_TRUE(entries(small_).empty()) << "nothing is written before the refusal";
}

TEST_F(DiskFaults, ABenchThatCannotFitIsRefusedBeforeItRuns) {
  // One problem and one run: ~1.3 MB estimated (its page's script alone is ~0.7 MB).
  if (const std::string why = mount_small_disk("1m"); !why.empty()) GTEST_SKIP() << why;
  const Result r = run_command(std::string(SPEC2FAB_CLI_PATH) + " bench -q --out " + (small_ / "bench").string() +
                               " --problems albedo_column --optimizers exhaustive --seeds 1");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("the benchmark's files need ~"));
  EXPECT_THAT(r.out, HasSubstr("free on " + small_.string()));
  EXPECT_TRUE(entries(small_).empty()) << "nothing is written before the refusal";
}

TEST_F(DiskFaults, AFileSizeLimitIsAWriteErrorForSimulate) {
  const fs::path out = dir_ / "simulated";
  // 4 kB per file: the radial profile's table goes past it.
  const Result r = run_command("ulimit -f 4; " + std::string(SPEC2FAB_CLI_PATH) + " simulate -q subsurface " +
                               (kDatasets / "simulations/subsurface_white_over_cyan.json").string() + " --out " +
                               out.string());
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_THAT(single_line(r.out), HasSubstr("error: cannot write " + out.string() + "/"));
  EXPECT_THAT(r.out, HasSubstr(": File too large"));
  EXPECT_FALSE(fs::exists(out));
  for (const std::string& name : entries(dir_)) EXPECT_EQ(name.find("partial"), std::string::npos) << "left behind: " << name;
}

}  // namespace
}  // namespace spec2fab_cli_test

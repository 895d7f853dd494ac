// Limits travel with a run (core/limits.h): an experiment's "limits" bind
// that experiment only, and the command line's win over them — so several
// experiments prepared in one process (the Python module, a notebook) keep
// their own.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/run_cache.h"
#include "spec/translator.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class RunLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("spec2fab_run_limits_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A tree experiment on the 40 x 30 x 20 mm box (or `mesh`); `limits` is its "limits" object, or "".
  fs::path experiment(const std::string& name, const std::string& limits, fs::path mesh = {}) const {
    const fs::path datasets = fs::absolute(SPEC2FAB_DATASETS_DIR);
    if (mesh.empty()) mesh = datasets / "meshes/box_40x30x20.stl";
    const fs::path file = dir_ / (name + ".json");
    std::ofstream(file) << R"({"translator": "tree", "geometry": {"mesh": ")" << mesh.string()
                        << R"(", "uv": "planar"}, "goal": {"tree": {"type": "layered", "material": "VeroWhitePlus"}}, "materials": ")"
                        << (datasets / "materials/polyjet.json").string() << R"(", "printer": ")"
                        << (datasets / "printers/j750.json").string() << R"(")"
                        << (limits.empty() ? "" : R"(, "limits": )" + limits) << "}";
    return file;
  }

  static std::string refusal(const fs::path& file, const Limits& command_line) {
    try {
      prepare_experiment(file, command_line);
    } catch (const InputError& e) {
      return e.what();
    }
    return "prepared";
  }

  fs::path dir_;
};

// A process-wide setting would pass the first half (each load replaced it)
// but not the second: there the first experiment's limits must outlast the
// preparation of the next.
TEST_F(RunLimits, TwoExperimentsPreparedSideBySideKeepTheirOwn) {
  // The census of the default 40/128 mm voxels has ~1.3e6 voxels: 1000 refuses it.
  const fs::path tight = experiment("tight", R"({"census_voxels": 1000})");
  const fs::path plain = experiment("plain", "");
  EXPECT_EQ(refusal(plain, Limits()), "prepared");
  EXPECT_THAT(refusal(tight, Limits()), HasSubstr("census_voxel_mm"));
  EXPECT_EQ(refusal(plain, Limits()), "prepared") << "the tight experiment's limit leaked into the next one";
  // Two prepared at once keep their own: the first's parts still go by its
  // limits when it runs after the second was prepared.
  const PreparedExperiment roomy = prepare_experiment(experiment("roomy", R"({"census_voxels": 5e6})"), Limits());
  const PreparedExperiment a = prepare_experiment(plain, Limits());
  EXPECT_EQ(roomy.experiment->limits().get("census_voxels"), 5e6);
  EXPECT_EQ(a.experiment->limits().get("census_voxels"), 1e9);
}

TEST_F(RunLimits, TheCommandLineWinsOverTheExperiment) {
  const fs::path tight = experiment("tight", R"({"census_voxels": 1000})");
  Limits command_line;
  command_line.set_from_command_line("census_voxels=1e8");
  const PreparedExperiment prepared = prepare_experiment(tight, command_line);
  EXPECT_EQ(prepared.experiment->limits().get("census_voxels"), 1e8);
  Limits strict;
  strict.set_from_command_line("census_voxels=10");
  EXPECT_THAT(refusal(experiment("plain", ""), strict), HasSubstr("limit census_voxels = 10"));
}

// A process that prepares many experiments (the fuzz harness) hands them one
// session cache: an unchanged mesh is read once, an edited one again; its
// experiments share the solid (field and all: they are prepared, not run),
// and experiments without a session share nothing.
TEST_F(RunLimits, ASessionCacheReadsAnUnchangedMeshOnce) {
  const fs::path mesh = dir_ / "box.stl";
  fs::copy_file(fs::path(SPEC2FAB_DATASETS_DIR) / "meshes/box_40x30x20.stl", mesh);
  const fs::path file = experiment("box", "", mesh);
  const auto session = std::make_shared<RunCache>();
  const PreparedExperiment a = prepare_experiment(file, Limits(), session);
  const size_t values = session->size();
  const PreparedExperiment b = prepare_experiment(file, Limits(), session);
  EXPECT_EQ(&a.experiment->cache(), session.get());
  EXPECT_EQ(session->size(), values) << "the second preparation made something again";
  EXPECT_EQ(&a.experiment->palette(), &b.experiment->palette());
  EXPECT_EQ(&a.experiment->solid(), &b.experiment->solid());

  fs::last_write_time(mesh, fs::last_write_time(mesh) + std::chrono::seconds(5));  // edited
  const PreparedExperiment edited = prepare_experiment(file, Limits(), session);
  EXPECT_EQ(session->size(), values + 2) << "the edited mesh is read again, its solid made again, and nothing else";
  EXPECT_NE(&edited.experiment->solid(), &a.experiment->solid());
  EXPECT_EQ(&edited.experiment->palette(), &a.experiment->palette()) << "the materials and printer did not change";

  const PreparedExperiment alone = prepare_experiment(file, Limits());
  const PreparedExperiment alone_again = prepare_experiment(file, Limits());
  EXPECT_NE(&alone.experiment->solid(), &alone_again.experiment->solid());
  EXPECT_NE(&alone.experiment->cache(), &alone_again.experiment->cache());
}

}  // namespace
}  // namespace spec2fab

// A translator's default optimizer is written as a user would write one
// (OptimizerChoice, tuning/optimizer.h), so a typo in it must fail in a
// test: the shipped experiments that name their optimizers never build the
// defaults. Each is validated again here without its optimizer sections, in
// a copy of the datasets folder's layout (its relative paths unchanged).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "spec/translator.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;

TEST(DefaultOptimizers, EveryShippedTranslatorBuildsItsDefaults) {
  const fs::path datasets = fs::path(SPEC2FAB_DATASETS_DIR);
  const fs::path copy = fs::temp_directory_path() / ("spec2fab_default_optimizers_" + std::to_string(::getpid()));
  fs::remove_all(copy);
  fs::create_directories(copy / "experiments");
  for (const auto& entry : fs::directory_iterator(datasets))
    if (entry.is_directory() && entry.path().filename() != "experiments")
      fs::create_directory_symlink(fs::absolute(entry.path()), copy / entry.path().filename());
  int stripped = 0;
  for (const auto& entry : fs::directory_iterator(datasets / "experiments")) {
    if (entry.path().extension() != ".json") continue;
    nlohmann::json experiment = nlohmann::json::parse(std::ifstream(entry.path()));
    bool named = false;
    for (const char* key : {"optimizer", "swap_optimizer", "texture_optimizer"}) named |= experiment.erase(key) > 0;
    if (!named) continue;  // validated as it is by the CLI tests, defaults and all
    ++stripped;
    const fs::path file = copy / "experiments" / entry.path().filename();
    std::ofstream(file) << experiment.dump(2);
    try {
      prepare_experiment(file, Limits());
    } catch (const InputError& e) {
      // A build without an optional module says so: the default is then
      // unavailable, not wrong.
      EXPECT_THAT(e.what(), ::testing::HasSubstr("is left out of this build")) << entry.path().filename();
    }
  }
  fs::remove_all(copy);
  EXPECT_GE(stripped, 5) << "the shipped experiments that name optimizers (smooth, facet, caustics_texture…)";
}

}  // namespace
}  // namespace spec2fab

// Resource limits: defaults, an experiment's "limits", the command line's
// --limit winning over both, and refusals of what cannot be a limit.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/limits.h"
#include "core/properties.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

struct LimitsTest : ::testing::Test {};

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST_F(LimitsTest, TheCommandLineWinsOverTheExperimentWhichWinsOverTheDefault) {
  Limits limits;
  EXPECT_EQ(limits.get("tets"), 1e7);
  limits.set_from_experiment(Properties::parse(R"({"tets": 5000, "census_voxels": 2e9})", "e.json", "."));
  EXPECT_EQ(limits.get("tets"), 5000);
  EXPECT_EQ(limits.get("census_voxels"), 2e9);
  limits.set_from_command_line("tets=7e4");
  EXPECT_EQ(limits.get("tets"), 7e4);
  EXPECT_EQ(limits.get("census_voxels"), 2e9);
  // Another experiment replaces the first's limits, not the command line's.
  limits.set_from_experiment(Properties::parse(R"({})", "f.json", "."));
  EXPECT_EQ(limits.get("census_voxels"), 1e9);
  EXPECT_EQ(limits.get("tets"), 7e4);
  EXPECT_THAT(limits.how_to_change("tets"), HasSubstr("limit tets = 7e+04; set it with --limit tets="));
  EXPECT_THROW(limits.get("tet"), std::logic_error);
}

// The values travel with a run: one run's limits are not another's (no
// process state), so runs in one process (Python, threads) keep their own.
TEST_F(LimitsTest, EachRunHasItsOwn) {
  Limits first, second;
  first.set_from_experiment(Properties::parse(R"({"tets": 5000})", "a.json", "."));
  second.set_from_command_line("tets=7e4");
  EXPECT_EQ(first.get("tets"), 5000);
  EXPECT_EQ(second.get("tets"), 7e4);
  EXPECT_EQ(Limits().get("tets"), 1e7);
}

TEST_F(LimitsTest, WhatCannotBeALimitIsRefused) {
  Limits limits;
  EXPECT_THAT(refusal([&] { limits.set_from_command_line("tet=5"); }), HasSubstr("did you mean 'tets'?"));
  EXPECT_THAT(refusal([&] { limits.set_from_command_line("tets"); }), HasSubstr("NAME=VALUE with a positive number"));
  EXPECT_THAT(refusal([&] { limits.set_from_command_line("tets=-1"); }), HasSubstr("positive number"));
  EXPECT_THAT(refusal([&] { limits.set_from_command_line("tets=1e9x"); }), HasSubstr("positive number"));
  EXPECT_THAT(refusal([&] { limits.set_from_command_line("tree_depth=2000"); }), HasSubstr("at most 1000"));
  EXPECT_THAT(refusal([&] { limits.set_from_experiment(Properties::parse(R"({"tets": 0})", "e.json", ".")); }),
              HasSubstr("e.json: /tets: must be a positive number"));
  EXPECT_EQ(limits.get("tets"), 1e7);  // nothing refused was kept
}

// Each part declares its limits (SPEC2FAB_LIMIT): the program lists them by
// name, each once, and each is in docs/robustness.md's table.
TEST_F(LimitsTest, EveryLimitIsDeclaredOnceListedByNameAndDocumented) {
  const std::vector<LimitDoc> all = limits::docs();
  ASSERT_GE(all.size(), 12u);
  for (size_t i = 1; i < all.size(); ++i) EXPECT_LT(all[i - 1].name, all[i].name);
  std::ifstream in(SPEC2FAB_DATASETS_DIR "/../docs/robustness.md");
  const std::string markdown((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const LimitDoc& doc : all) EXPECT_THAT(markdown, HasSubstr("| `" + doc.name + "` |")) << doc.name;
  EXPECT_THROW(limits::declare("tets", 5, "again"), std::logic_error);
}

}  // namespace
}  // namespace spec2fab

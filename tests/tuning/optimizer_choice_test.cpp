// A translator's optimizer: the experiment's own section, read where the
// user wrote it, or the translator's default; a default the translator gets
// wrong is its bug (std::logic_error), not the user's input.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>

#include "core/properties.h"
#include "tuning/optimizer.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

TEST(OptimizerChoice, TakesTheExperimentsSectionOrElseTheDefault) {
  const Properties given =
      Properties::parse(R"({"optimizer": {"type": "annealing", "iterations": 7}})", "exp.json");
  const OptimizerChoice chosen(given, "optimizer", {{"type", "exhaustive"}});
  EXPECT_EQ(chosen.spec().at("type"), "annealing");
  EXPECT_EQ(chosen.build()->name(), "annealing");
  EXPECT_NE(chosen.build().get(), chosen.build().get()) << "one optimizer per tuner";
  given.check_all_read();  // the section's keys were read where the user wrote them

  const Properties none = Properties::parse("{}", "exp.json");
  const OptimizerChoice fallback(none, "optimizer", {{"type", "exhaustive"}});
  EXPECT_EQ(fallback.spec().at("type"), "exhaustive");
  EXPECT_EQ(fallback.build()->name(), "exhaustive");
}

TEST(OptimizerChoice, TheUsersMistakeIsReportedWhereTheyMadeIt) {
  const Properties given = Properties::parse(R"({"swap_optimizer": {"type": "anealing"}})", "exp.json");
  try {
    OptimizerChoice(given, "swap_optimizer", {{"type", "annealing"}});
    ADD_FAILURE() << "a misspelt optimizer was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("exp.json: /swap_optimizer/type: unknown optimizer 'anealing'"));
  }
}

TEST(OptimizerChoice, ADefaultThatDoesNotBuildIsTheTranslatorsBug) {
  const Properties none = Properties::parse("{}", "exp.json");
  EXPECT_THROW(OptimizerChoice(none, "optimizer", {{"type", "annealing"}, {"iteratoins", 7}}), std::logic_error);
  EXPECT_THROW(OptimizerChoice(none, "optimizer", {{"type", "no_such_optimizer"}}), std::logic_error);
}

}  // namespace
}  // namespace spec2fab

// Tuners that weigh several terms: weighted sums reach the weighted optimum,
// a limited term is honoured (and pruned on by branch and bound), the terms
// come from JSON with every key checked, and each term's value is reported.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "materials/palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/tuner.h"
#include "tuning/vector_parts.h"
#include "tuning_test_parts.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::optimizer;

/// The subtree's free parameters' values, in visiting order: a simulator
/// whose optimum every term's closed form gives.
class ParametersSimulator final : public SimulatorFor<VectorObservation> {
 public:
  ParametersSimulator() = default;
  ParametersSimulator(const Properties&, const PartContext&) {}
  std::string name() const override { return "test_parameters"; }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    out.data.clear();
    subtree.read_parameters([&](const std::string&, const Parameter& p) {
      if (p.is_free()) out.data.push_back(p.value());
    });
  }
  static TypeDoc doc() { return {"test: the free parameters' values", {}, R"({"type": "test_parameters"})"}; }
};

SPEC2FAB_REGISTER(SimulatorRegistry, ParametersSimulator, "test_parameters")

class TunerTerms : public ::testing::Test {
 protected:
  TunerTerms() : palette_(std::vector<Material>(1)) {}

  /// Two layers whose thicknesses are free on 0, 0.1, …, 1 (or the first alone).
  std::unique_ptr<ReducerTree> layers(int free) {
    const std::string thickness = R"({"value": 0, "min": 0, "max": 1, "step": 0.1})";
    return std::make_unique<ReducerTree>(
        Properties::parse(R"({"type": "layered", "layers": [{"material": "void", "thickness_mm": )" + thickness +
                              R"(}, {"material": "void", "thickness_mm": )" + (free == 2 ? thickness : "0.5") +
                              R"(}, {"material": "void"}]})",
                          "tree.json"),
        palette_);
  }
  /// ‖values − at‖² of the free parameters.
  TunerTerm distance_to(std::vector<double> at, TermRule rule, std::string name = "near") {
    return {std::move(name), std::make_unique<ParametersSimulator>(), std::make_unique<SquaredDistance>(),
            std::make_unique<FixedValuesGoal>(std::move(at)), rule};
  }
  std::unique_ptr<Tuner> tuner(std::vector<double> objective_at, const std::string& optimizer_json) {
    return std::make_unique<Tuner>("t", std::make_unique<ParametersSimulator>(), std::make_unique<SquaredDistance>(),
                                   std::make_unique<FixedValuesGoal>(std::move(objective_at)), optimizer(optimizer_json));
  }

  MaterialPalette palette_;
};

// (t − 0.2)² + w (t − 1)² is least at t = (0.2 + w) / (1 + w): 0.6 for w = 1,
// 0.8 for w = 3, on the 0.1 grid exactly.
TEST_F(TunerTerms, AWeightedSumReachesTheWeightedOptimum) {
  for (const auto& [weight, expected] : {std::pair{1.0, 0.6}, std::pair{3.0, 0.8}}) {
    auto tree = layers(1);
    auto t = tuner({0.2}, R"({"type": "exhaustive"})");
    t->add_term(distance_to({1.0}, TermRule{weight, std::nullopt, 1e3}));
    t->set_node(tree->root());
    const Summary summary = t->tune();
    ASSERT_TRUE(summary.usable()) << summary.full_report();
    const double chosen = t->search_space().values()[0];
    EXPECT_NEAR(chosen, expected, 1e-12) << "weight " << weight;
    const std::vector<TermValue> values = t->term_values();
    ASSERT_EQ(values.size(), 2u);
    EXPECT_EQ(values[0].name, "objective");
    EXPECT_NEAR(values[0].error, (chosen - 0.2) * (chosen - 0.2), 1e-12);
    EXPECT_EQ(values[1].name, "near");
    EXPECT_NEAR(values[1].error, (chosen - 1) * (chosen - 1), 1e-12);
    EXPECT_NEAR(values[1].contribution, weight * values[1].error, 1e-12);
    EXPECT_NEAR(summary.final_error, values[0].contribution + values[1].contribution, 1e-12);
  }
}

// Minimise (t − 1)² with (t − 0.2)² at most 0.09: t may not pass 0.5.
// Without the limit the optimum is t = 1.
TEST_F(TunerTerms, ALimitedTermIsHonoured) {
  auto tree = layers(1);
  auto t = tuner({1.0}, R"({"type": "exhaustive"})");
  t->add_term(distance_to({0.2}, TermRule{1, 0.09, 1e3}, "within"));
  t->set_node(tree->root());
  ASSERT_TRUE(t->tune().usable());
  EXPECT_NEAR(t->search_space().values()[0], 0.5, 1e-12);
  const std::vector<TermValue> values = t->term_values();
  EXPECT_NEAR(values[1].error, 0.09, 1e-12);
  EXPECT_EQ(values[1].at_most, 0.09);
  EXPECT_EQ(values[1].contribution, 0) << "within its limit it adds nothing";
  EXPECT_EQ(values[1].weight, 0);

  auto free_tree = layers(1);
  auto free_tuner = tuner({1.0}, R"({"type": "exhaustive"})");
  free_tuner->set_node(free_tree->root());
  ASSERT_TRUE(free_tuner->tune().usable());
  EXPECT_NEAR(free_tuner->search_space().values()[0], 1.0, 1e-12);
}

// Two thicknesses x on the 0.1 grid: minimise ‖x − (1, 1)‖² with ‖x‖² ≤ 0.5.
// The optimum is (0.5, 0.5). Branch and bound finds it with the objective's
// bound alone and, pruning on the limited term's bound too, with fewer
// evaluations.
TEST_F(TunerTerms, BranchAndBoundPrunesOnALimitedTermsBound) {
  const auto sum_of_squares = [](std::span<const double> x, int assigned, double centre) {
    double sum = 0;
    for (int i = 0; i < assigned; ++i) sum += (x[i] - centre) * (x[i] - centre);
    return sum;
  };
  long long evaluations[2] = {0, 0};
  for (int with_term_bound = 0; with_term_bound < 2; ++with_term_bound) {
    auto tree = layers(2);
    auto t = tuner({1.0, 1.0}, R"({"type": "branch_and_bound"})");
    t->add_term(distance_to({0.0, 0.0}, TermRule{1, 0.5, 1e3}, "disc"));
    t->set_node(tree->root());
    t->set_lower_bound([&](std::span<const double> x, int assigned, const Observation&) {
      return sum_of_squares(x, assigned, 1.0);
    });
    if (with_term_bound) {
      t->set_term_lower_bound(1, [&](std::span<const double> x, int assigned) { return sum_of_squares(x, assigned, 0.0); });
    }
    const Summary summary = t->tune();
    ASSERT_TRUE(summary.usable()) << summary.full_report();
    EXPECT_THAT(t->search_space().values(), ::testing::ElementsAre(::testing::DoubleNear(0.5, 1e-12),
                                                                    ::testing::DoubleNear(0.5, 1e-12)));
    EXPECT_NEAR(summary.final_error, 0.5, 1e-12);
    evaluations[with_term_bound] = summary.evaluations;
  }
  EXPECT_LT(evaluations[1], evaluations[0]) << "the limit's bound prunes branches the objective's does not";
  auto tree = layers(2);
  auto t = tuner({1.0, 1.0}, R"({"type": "branch_and_bound"})");
  EXPECT_THROW(t->set_term_lower_bound(1, {}), std::out_of_range) << "no term 1 yet";
}

TEST_F(TunerTerms, RulesAndPartsAreChecked) {
  auto t = tuner({0.0}, R"({"type": "exhaustive"})");
  EXPECT_THAT([&] { t->add_term(distance_to({1.0}, TermRule{-1, std::nullopt, 1e3})); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("term 'near': weight: a finite number ≥ 0")));
  EXPECT_THAT([&] { t->add_term(distance_to({1.0}, TermRule{1, 1, 0})); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("penalty: a finite number > 0")));
  auto tree = layers(1);
  t->set_node(tree->root());
  EXPECT_THROW(t->add_term(distance_to({1.0}, TermRule{})), std::logic_error) << "terms come before set_node";
  // A failed simulation (NaN) is the worst error under either rule, never within a limit.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(TermRule{1, 0.5, 1e3}.contribution(nan)));
  EXPECT_TRUE(std::isnan(TermRule{2, std::nullopt, 1e3}.contribution(nan)));
  EXPECT_EQ((TermRule{1, 0.5, 10}.contribution(0.75)), 2.5);
}

TEST_F(TunerTerms, TermsAreReadFromJsonAndReported) {
  const Properties p = Properties::parse(R"({"tuners": [{
      "simulator": {"type": "test_parameters"}, "metric": {"type": "squared_distance"},
      "goal": {"type": "values", "values": [0.2]}, "optimizer": {"type": "exhaustive"}, "weight": 1,
      "terms": [{"name": "far", "simulator": {"type": "test_parameters"}, "metric": {"type": "squared_distance"},
                 "goal": {"type": "values", "values": [1.0]}, "weight": 3}]}]})",
                                         "exp.json");
  auto t = build_tuner(p.objects("tuners")[0], "t", PartContext{palette_});
  p.check_all_read();
  ASSERT_EQ(t->term_count(), 2u);
  auto tree = layers(1);
  t->set_node(tree->root());
  ASSERT_TRUE(t->tune().usable());
  EXPECT_NEAR(t->search_space().values()[0], 0.8, 1e-12);
  EXPECT_EQ(t->term_values()[1].name, "far");
  EXPECT_EQ(t->term_values()[1].weight, 3);
}

TEST_F(TunerTerms, JsonMistakesInATermAreNamedWhereTheyAre) {
  const auto build = [&](const std::string& term) {
    const Properties p = Properties::parse(R"({"tuners": [{"simulator": {"type": "test_parameters"},
        "metric": {"type": "squared_distance"}, "goal": {"type": "values", "values": [0]},
        "optimizer": {"type": "exhaustive"}, "terms": [)" + term + "]}]}",
                                           "exp.json");
    build_tuner(p.objects("tuners")[0], "t", PartContext{palette_});
    p.check_all_read();
  };
  const std::string parts = R"("simulator": {"type": "test_parameters"}, "metric": {"type": "squared_distance"},
      "goal": {"type": "values", "values": [1]})";
  EXPECT_THAT([&] { build("{" + parts + R"(, "weight": 1, "at_most": 2})"); },
              ThrowsMessage<InputError>(HasSubstr("exp.json: /tuners/0/terms/0/at_most: a term held under a limit "
                                                  "takes no weight")));
  EXPECT_THAT([&] { build("{" + parts + R"(, "wieght": 1})"); },
              ThrowsMessage<InputError>(HasSubstr("exp.json: /tuners/0/terms/0/wieght: unknown key; did you mean "
                                                  "'weight'?")));
  EXPECT_THAT([&] { build(R"({"simulator": {"type": "test_parameters"}, "metric": {"type": "rgb_mse"},
                              "goal": {"type": "values", "values": [1]}})"); },
              ThrowsMessage<InputError>(HasSubstr("exp.json: /tuners/0/terms/0: metric 'rgb_mse' compares albedo "
                                                  "observations, but simulator 'test_parameters' produces vector")));
  EXPECT_THAT([&] { build("{" + parts + R"(, "at_most": -1})"); },
              ThrowsMessage<InputError>(HasSubstr("at_most: a finite number ≥ 0")));
  EXPECT_THAT([&] { build("{" + parts + R"(, "weight": 2, "penalty": 10})"); },
              ThrowsMessage<InputError>(HasSubstr("/terms/0/penalty: only a term held under a limit (at_most) takes "
                                                  "a penalty")));
}

}  // namespace
}  // namespace spec2fab

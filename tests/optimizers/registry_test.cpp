// Every optimizer built from JSON as users write it: defaults valid, doc
// examples that build, bad options and unknown keys reported with their
// field, and problems lacking a needed capability refused.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <tuple>

#include "build_gates.h"
#include "optimizers/optimizer_test_support.h"

namespace spec2fab {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using testing::input_error_of;
using testing::optimizer_from;
using ::testing::StartsWith;

// The Ceres and NLopt adapters are optional modules: listed where built.
const std::vector<std::string> kOptimizers = [] {
  std::vector<std::string> names = {"exhaustive", "annealing", "branch_and_bound", "spsa"};
  if (SPEC2FAB_WITH_CERES) names.push_back("ceres");
  if (SPEC2FAB_WITH_NLOPT) names.push_back("nlopt");
  return names;
}();

// A build without an optional module names the option that left its part out.
TEST(OptimizerRegistry, LeftOutOptimizerNamesTheBuildOption) {
  for (const auto& [name, built, option] : {std::tuple{"ceres", SPEC2FAB_WITH_CERES, "SPEC2FAB_WITH_CERES"},
                                            std::tuple{"nlopt", SPEC2FAB_WITH_NLOPT, "SPEC2FAB_WITH_NLOPT"}}) {
    const std::string type = name;  // clang 14 cannot capture a structured binding
    const std::string error = input_error_of([&] { optimizer_from(R"({"type": ")" + type + R"("})"); });
    if (built) {
      EXPECT_EQ(error, "no error") << name;
    } else {
      EXPECT_EQ(error, std::string("t.json: /type: the optimizer '") + name + "' (" +
                           (std::string(name) == "ceres" ? "Ceres Solver" : "NLopt") +
                           ") is left out of this build: configure with -D" + option + "=ON");
    }
  }
}

TEST(OptimizerRegistry, EveryOptimizerIsRegistered) {
  for (const std::string& name : kOptimizers) {
    EXPECT_TRUE(OptimizerRegistry::instance().contains(name)) << name;
  }
}

TEST(OptimizerRegistry, DefaultOptionsAreValid) {
  for (const std::string& name : kOptimizers) {
    std::unique_ptr<Optimizer> optimizer;
    EXPECT_NO_THROW(optimizer = optimizer_from(R"({"type": ")" + name + R"("})")) << name;
    ASSERT_NE(optimizer, nullptr);
    EXPECT_EQ(optimizer->name(), name);
  }
}

TEST(OptimizerRegistry, DocumentedExamplesBuildAndDocumentEveryProperty) {
  for (const std::string& name : kOptimizers) {
    const TypeDoc& doc = OptimizerRegistry::instance().doc(name);
    EXPECT_FALSE(doc.summary.empty()) << name;
    std::unique_ptr<Optimizer> optimizer;
    EXPECT_NO_THROW(optimizer = optimizer_from(doc.example)) << name << ": " << doc.example;
    ASSERT_NE(optimizer, nullptr);
    EXPECT_EQ(optimizer->name(), name);
    // Every documented property is accepted with its documented default.
    for (const PropertyDoc& property : doc.properties) {
      const std::string json = R"({"type": ")" + name + R"(", ")" + property.name + R"(": )" +
                               property.default_value + "}";
      EXPECT_NO_THROW(optimizer_from(json)) << json;
    }
  }
}

TEST(OptimizerRegistry, BuildsTheDocumentedNloptExample) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  const std::unique_ptr<Optimizer> nlopt =
      optimizer_from(R"({"type": "nlopt", "algorithm": "LD_LBFGS"})");
  EXPECT_EQ(nlopt->name(), "nlopt");
  ASSERT_EQ(nlopt->requirements().size(), 1u);
  EXPECT_EQ(nlopt->requirements()[0], Capability::gradient);
  EXPECT_TRUE(
      optimizer_from(R"({"type": "nlopt", "algorithm": "LN_BOBYQA"})")->requirements().empty());
  // NLopt's names are upper case; lower case is accepted.
  EXPECT_EQ(optimizer_from(R"({"type": "nlopt", "algorithm": "ld_mma"})")->requirements().size(),
            1u);
}

struct BadOption {
  std::string json;
  std::string message;  // a substring of the InputError
};

TEST(OptimizerRegistry, BadOptionsNameTheField) {
  // Each option's range and choices are declared once (core/options.h): the
  // error names the key's JSON path and says what it must be.
  const std::vector<BadOption> cases = {
      {R"({"type": "exhaustive", "max_candidates": 0})", "t.json: /max_candidates: 0 is not at least 1"},
      {R"({"type": "annealing", "iterations": 0})", "t.json: /iterations: 0 is not at least 1"},
      {R"({"type": "annealing", "cooling": 1.5})", "t.json: /cooling: 1.5 is not in (0, 1]"},
      {R"({"type": "annealing", "schedule": "exponentail"})",
       "t.json: /schedule: unknown value 'exponentail'; did you mean 'exponential'? (known: exponential, linear, "
       "logarithmic)"},
      {R"({"type": "annealing", "swap_probability": -0.1})", "t.json: /swap_probability: -0.1 is not in [0, 1]"},
      {R"({"type": "annealing", "iterations": "many"})",
       "t.json: /iterations: expected an integer, got a string"},
      {R"({"type": "annealing", "iterations": 100, "schedule_iterations": 50})",
       "t.json: /schedule_iterations: must be 0 or at least iterations"},
      {R"({"type": "branch_and_bound", "continuous_steps": 0})", "t.json: /continuous_steps: 0 is not at least 1"},
      {R"({"type": "branch_and_bound", "value_order": "best_bound"})",
       "t.json: /value_order: unknown value 'best_bound'"},
      {R"({"type": "spsa", "iterations": -5})", "t.json: /iterations: -5 is not at least 1"},
      {R"({"type": "spsa", "c": 0})", "t.json: /c: 0 is not above 0"},
      {R"({"type": "spsa", "gamma": 0.9})", "t.json: /gamma: must lie in (0, alpha]"},
      {R"({"type": "spsa", "result": "best"})", "t.json: /result: unknown value 'best'"},
      {R"({"type": "ceres", "max_iterations": 0})", "t.json: /max_iterations: 0 is not at least 1"},
      {R"({"type": "ceres", "linear_solver": "dense_qrr"})",
       "t.json: /linear_solver: unknown value 'dense_qrr'; did you mean 'dense_qr'?"},
      {R"({"type": "ceres", "derivatives": "automatic"})", "t.json: /derivatives: unknown value"},
      {R"({"type": "ceres", "trust_region": "dogleg2"})", "t.json: /trust_region:"},
      {R"({"type": "nlopt", "algorithm": "LD_LBFSG"})",
       "t.json: /algorithm: unknown NLopt algorithm 'LD_LBFSG'; did you mean 'LD_LBFGS'?"},
      {R"({"type": "nlopt", "max_evaluations": 0})", "t.json: /max_evaluations: 0 is not at least 1"},
      {R"({"type": "nlopt", "max_seconds": -1})", "t.json: /max_seconds: -1 is not at least 0"},
  };
  for (const BadOption& c : cases) {
    if (!testing::optimizer_built(c.json)) continue;
    EXPECT_THAT(input_error_of([&] { optimizer_from(c.json); }), HasSubstr(c.message)) << c.json;
  }
}

// Declared once: what list --verbose shows is what reading enforces, and a
// struct built in C++ is checked by the same declaration.
TEST(OptimizerRegistry, OptionsDocumentedAndCheckedFromTheirDeclaration) {
  const TypeDoc& doc = OptimizerRegistry::instance().doc("annealing");
  const auto row = std::find_if(doc.properties.begin(), doc.properties.end(),
                                [](const PropertyDoc& p) { return p.name == "cooling"; });
  ASSERT_NE(row, doc.properties.end());
  EXPECT_EQ(row->type, "number in (0, 1]");
  EXPECT_EQ(row->default_value, "0.999");
  const TypeDoc& bnb = OptimizerRegistry::instance().doc("branch_and_bound");
  EXPECT_EQ(bnb.properties[1].type, "natural | best_bound_first");
  EXPECT_EQ(bnb.properties[1].default_value, "\"natural\"");
}

TEST(OptimizerRegistry, UnknownNloptAlgorithmListsValidOnes) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  EXPECT_THAT(input_error_of([] { optimizer_from(R"({"type": "nlopt", "algorithm": "BFGS"})"); }),
              AllOf(HasSubstr("algorithm: unknown NLopt algorithm 'BFGS'"), HasSubstr("LD_LBFGS"),
                    HasSubstr("LN_BOBYQA")));
}

TEST(OptimizerRegistry, UnknownKeyIsRejected) {
  EXPECT_THAT(input_error_of([] { optimizer_from(R"({"type": "annealing", "iteratoins": 100})"); }),
              AllOf(StartsWith("t.json: /iteratoins: unknown key"), HasSubstr("iterations")));
  EXPECT_THAT(input_error_of([] { optimizer_from(R"({"type": "spsa", "tolerance": 1e-9})"); }),
              StartsWith("t.json: /tolerance: unknown key"));
}

TEST(OptimizerRegistry, UnknownOptimizerListsKnownOnes) {
  EXPECT_THAT(input_error_of([] { optimizer_from(R"({"type": "aneal"})"); }),
              AllOf(HasSubstr("unknown optimizer 'aneal'"), HasSubstr("annealing")));
}

// A continuous problem with nothing but error().
FunctionProblem plain_quadratic() {
  return FunctionProblem({VariableDomain::continuous(-1, 1), VariableDomain::continuous(-1, 1)},
                         [](std::span<const double> x) { return x[0] * x[0] + x[1] * x[1]; });
}

std::string refusal(const std::string& json, Problem& problem) {
  std::vector<double> x(static_cast<size_t>(problem.dimension()), 0.5);
  try {
    optimizer_from(json)->minimize(problem, x);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no refusal";
}

TEST(OptimizerCapabilities, MissingCapabilityIsRefusedNamingBoth) {
  FunctionProblem problem = plain_quadratic();
  if (SPEC2FAB_WITH_NLOPT) {
    EXPECT_THAT(refusal(R"({"type": "nlopt", "algorithm": "LD_LBFGS"})", problem),
                AllOf(HasSubstr("'nlopt'"), HasSubstr("gradient")));
  }
  EXPECT_THAT(refusal(R"({"type": "branch_and_bound"})", problem),
              AllOf(HasSubstr("'branch_and_bound'"), HasSubstr("lower bound")));
  if (SPEC2FAB_WITH_CERES) {
    EXPECT_THAT(refusal(R"({"type": "ceres"})", problem),
                AllOf(HasSubstr("'ceres'"), HasSubstr("residuals")));
  }
  EXPECT_THAT(refusal(R"({"type": "exhaustive"})", problem),
              AllOf(HasSubstr("'exhaustive'"), HasSubstr("discrete")));
  // Derivative-free methods need nothing more.
  if (SPEC2FAB_WITH_NLOPT) {
    EXPECT_EQ(refusal(R"({"type": "nlopt", "algorithm": "LN_BOBYQA"})", problem), "no refusal");
  }
  EXPECT_EQ(refusal(R"({"type": "annealing", "iterations": 10})", problem), "no refusal");
  EXPECT_EQ(refusal(R"({"type": "spsa", "iterations": 10})", problem), "no refusal");
}

TEST(OptimizerCapabilities, WrongStartSizeIsRefused) {
  FunctionProblem problem = plain_quadratic();
  std::vector<double> x = {0.5};
  EXPECT_THROW(optimizer_from(R"({"type": "spsa"})")->minimize(problem, x), std::invalid_argument);
}

TEST(Summary, NotRunUntilMinimized) {
  const Summary summary;
  EXPECT_EQ(summary.termination, Termination::not_run);
  EXPECT_EQ(summary.message, "Solve was not called.");
  EXPECT_FALSE(summary.usable());
}

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
namespace {

// What a schedule counts before it starts (Schedule::check_plan): each
// optimizer's planned evaluations bound what a run spends, and equal it
// where the method always runs to its length.
TEST(OptimizerRegistry, PlannedEvaluationsBoundWhatARunSpends) {
  struct Case {
    std::string json;
    bool runs_to_its_length;
  };
  const std::vector<Case> cases = {
      {R"({"type": "annealing", "iterations": 300})", true},
      {R"({"type": "spsa", "iterations": 50})", true},
      {R"({"type": "spsa", "iterations": 50, "a": 0})", true},
      {R"({"type": "exhaustive"})", true},
      {R"({"type": "nlopt", "algorithm": "GN_DIRECT", "max_evaluations": 200})", true},
      {R"({"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 200})", false},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.json);
    if (!testing::optimizer_built(c.json)) continue;
    auto optimizer = optimizer_from(c.json);
    const bool discrete = c.json.find("exhaustive") != std::string::npos;
    testing::LeastSquaresProblem problem = testing::rosenbrock(3, -2, 2);
    testing::LeastSquaresProblem grid(std::vector<VariableDomain>(3, VariableDomain::discrete(-2, 2, 0.5)),
                                      problem.residual_count(),
                                      [&](std::span<const double> x, std::span<double> r, std::span<double> j) {
                                        problem.residuals(x, r, j);
                                      });
    Problem& target = discrete ? static_cast<Problem&>(grid) : problem;
    const std::optional<double> planned = optimizer->planned_evaluations(target);
    ASSERT_TRUE(planned.has_value());
    std::vector<double> x(3, discrete ? 0.5 : -1.2);
    const Summary summary = optimizer->minimize(target, x);
    if (c.runs_to_its_length)
      EXPECT_EQ(static_cast<double>(summary.evaluations), *planned);
    else
      EXPECT_LE(static_cast<double>(summary.evaluations), *planned);
    EXPECT_GT(summary.evaluations, 1);
  }
  // Branch and bound prunes as it goes, and Ceres evaluates as often as its
  // steps need (76 evaluations in 20 iterations on rosenbrock(3)): neither can say.
  testing::LeastSquaresProblem problem = testing::rosenbrock(2);
  EXPECT_FALSE(optimizer_from(R"({"type": "branch_and_bound"})")->planned_evaluations(problem).has_value());
  if (SPEC2FAB_WITH_CERES) {
    EXPECT_FALSE(optimizer_from(R"({"type": "ceres"})")->planned_evaluations(problem).has_value());
  }
}

}  // namespace
}  // namespace spec2fab

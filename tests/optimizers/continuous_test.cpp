// Gradient-based optimizers (Ceres, NLopt) on Rosenbrock functions, whose
// minimum is known: 0 at x = (1, ..., 1). Every analytic derivative used here
// is first checked against central differences.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <memory>

#include "build_gates.h"
#include "optimizers/optimizer_test_support.h"

namespace spec2fab {
namespace {

using testing::gradient_matches;
using ::testing::HasSubstr;
using testing::jacobian_matches;
using testing::LeastSquaresProblem;
using testing::optimizer_from;
using testing::rosenbrock;

// Where the derivative checks look: the classic start, the optimum and a few
// points with large derivatives.
std::vector<std::vector<double>> check_points(int n) {
  std::vector<std::vector<double>> points;
  testing::Sequence sequence(7);
  for (int p = 0; p < 4; ++p) {
    std::vector<double> x(static_cast<size_t>(n));
    for (double& v : x) v = -2.0 + 0.01 * sequence.next(400);
    points.push_back(x);
  }
  points.push_back(std::vector<double>(static_cast<size_t>(n), 1.0));
  std::vector<double> classic(static_cast<size_t>(n), 1.0);
  for (size_t i = 0; i < classic.size(); i += 2) classic[i] = -1.2;
  points.push_back(classic);
  return points;
}

// The start used for both sizes: the classic (−1.2, 1) pattern.
std::vector<double> classic_start(int n) { return check_points(n).back(); }

TEST(DerivativeChecks, RosenbrockJacobianAndGradientMatchCentralDifferences) {
  for (int n : {2, 10}) {
    LeastSquaresProblem problem = rosenbrock(n);
    for (const std::vector<double>& x : check_points(n)) {
      EXPECT_TRUE(jacobian_matches(problem, x)) << "n = " << n;
      EXPECT_TRUE(gradient_matches(problem, x)) << "n = " << n;
    }
  }
}

TEST(DerivativeChecks, CheckerCatchesAWrongDerivative) {
  // Rosenbrock with ∂r0/∂x0 = −19·x0 instead of −20·x0: the checker must object.
  testing::LeastSquaresProblem wrong(
      {VariableDomain::continuous(-5, 5), VariableDomain::continuous(-5, 5)}, 2,
      [](std::span<const double> x, std::span<double> r, std::span<double> jacobian) {
        r[0] = 10 * (x[1] - x[0] * x[0]);
        r[1] = 1 - x[0];
        if (!jacobian.empty()) {
          jacobian[0] = -19 * x[0];
          jacobian[1] = 10;
          jacobian[2] = -1;
          jacobian[3] = 0;
        }
      });
  EXPECT_FALSE(jacobian_matches(wrong, {-1.2, 1.0}));
  EXPECT_FALSE(gradient_matches(wrong, {-1.2, 1.0}));
}

void expect_at_optimum(const std::vector<double>& x, double tolerance = 1e-8) {
  for (size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(x[i], 1.0, tolerance) << "x[" << i << "]";
}

struct Case {
  int n;
  std::string json;
};

class RosenbrockMinimum : public ::testing::TestWithParam<Case> {};

TEST_P(RosenbrockMinimum, ReachedTo1e8InX) {
  const Case& c = GetParam();
  if (!testing::optimizer_built(c.json)) GTEST_SKIP() << c.json << " is left out of this build";
  LeastSquaresProblem problem = rosenbrock(c.n);
  std::vector<double> x = classic_start(c.n);
  const Summary summary = optimizer_from(c.json)->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::converged) << summary.full_report();
  expect_at_optimum(x);
  EXPECT_EQ(summary.final_x, x);
  EXPECT_LT(summary.final_error, 1e-16);
  EXPECT_GT(summary.initial_error, 1.0);
  EXPECT_FALSE(summary.trace.empty());
  EXPECT_GT(summary.evaluations, summary.iterations);
}

INSTANTIATE_TEST_SUITE_P(
    Rosenbrock2D, RosenbrockMinimum,
    ::testing::Values(
        Case{2, R"({"type": "ceres"})"}, Case{2, R"({"type": "ceres", "derivatives": "numeric"})"},
        Case{2, R"({"type": "ceres", "trust_region": "dogleg"})"},
        Case{2,
             R"({"type": "nlopt", "algorithm": "LD_LBFGS", "ftol_rel": 0, "xtol_rel": 1e-12})"}));

INSTANTIATE_TEST_SUITE_P(
    Rosenbrock10D, RosenbrockMinimum,
    ::testing::Values(
        Case{10, R"({"type": "ceres"})"},
        Case{10, R"({"type": "ceres", "derivatives": "numeric"})"},
        Case{10, R"({"type": "ceres", "trust_region": "dogleg"})"},
        Case{10,
             R"({"type": "nlopt", "algorithm": "LD_LBFGS", "ftol_rel": 0, "xtol_rel": 1e-12})"}));

// With x0 ≤ 0.5 the minimum moves to the bound: x = (0.5, 0.25), where
// r0 = 0 and error = ½(1 − 0.5)² = 0.125.
LeastSquaresProblem bounded_rosenbrock() {
  return LeastSquaresProblem(
      {VariableDomain::continuous(-2, 0.5), VariableDomain::continuous(-2, 2)}, 2,
      [](std::span<const double> x, std::span<double> r, std::span<double> jacobian) {
        rosenbrock(2).residuals(x, r, jacobian);
      });
}

TEST(BoundedRosenbrock, NloptReachesTheMinimumOnTheBound) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  LeastSquaresProblem problem = bounded_rosenbrock();
  std::vector<double> x = {-1.2, 1.0};
  const Summary summary =
      optimizer_from(
          R"({"type": "nlopt", "algorithm": "LD_LBFGS", "ftol_rel": 0, "xtol_rel": 1e-12})")
          ->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::converged) << summary.full_report();
  EXPECT_NEAR(x[0], 0.5, 1e-8);
  EXPECT_NEAR(x[1], 0.25, 1e-8);
  EXPECT_NEAR(summary.final_error, 0.125, 1e-12);
}

// Ceres projects its steps onto the bounds; with x0 held at its bound the
// projected steps along the curved valley shrink, and it stops (parameter
// tolerance) a little short of the constrained minimum. It keeps the bound.
TEST(BoundedRosenbrock, CeresKeepsTheBoundAndGetsClose) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_CERES);
  for (const std::string derivatives : {"analytic", "numeric"}) {
    LeastSquaresProblem problem = bounded_rosenbrock();
    std::vector<double> x = {-1.2, 1.0};
    const Summary summary =
        optimizer_from(R"({"type": "ceres", "derivatives": ")" + derivatives + R"("})")
            ->minimize(problem, x);
    EXPECT_TRUE(summary.usable()) << summary.full_report();
    EXPECT_DOUBLE_EQ(x[0], 0.5) << derivatives;
    EXPECT_NEAR(x[1], 0.25, 5e-3) << derivatives;
    EXPECT_NEAR(summary.final_error, 0.125, 1e-3) << derivatives;
  }
}

TEST(Nlopt, DerivativeFreeAndGlobalAlgorithmsFindAQuadraticsMinimum) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  FunctionProblem problem({VariableDomain::continuous(-1, 1), VariableDomain::continuous(-1, 1)},
                          [](std::span<const double> x) {
                            return (x[0] - 0.3) * (x[0] - 0.3) + 2 * (x[1] + 0.6) * (x[1] + 0.6);
                          });
  for (const std::string algorithm : {"LN_BOBYQA", "LN_COBYLA", "LN_NELDERMEAD", "GN_DIRECT_L"}) {
    std::vector<double> x = {0.9, 0.9};
    const Summary summary =
        optimizer_from(R"({"type": "nlopt", "max_evaluations": 2000, "algorithm": ")" + algorithm +
                       R"("})")
            ->minimize(problem, x);
    EXPECT_TRUE(summary.usable()) << summary.full_report();
    EXPECT_NEAR(x[0], 0.3, 1e-3) << algorithm;
    EXPECT_NEAR(x[1], -0.6, 1e-3) << algorithm;
    EXPECT_LE(summary.evaluations, 2001 + 1) << algorithm;
  }
}

TEST(Nlopt, GlobalAlgorithmNeedsFiniteBounds) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  const double inf = std::numeric_limits<double>::infinity();
  FunctionProblem problem({VariableDomain::continuous(-inf, inf)},
                          [](std::span<const double> x) { return x[0] * x[0]; });
  std::vector<double> x = {1.0};
  const Summary summary =
      optimizer_from(R"({"type": "nlopt", "algorithm": "GN_DIRECT_L"})")->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::failure);
  EXPECT_THAT(summary.message, HasSubstr("needs finite bounds on every variable"));
  EXPECT_EQ(x, std::vector<double>{1.0});
}

TEST(Nlopt, MaxEvaluationsIsReported) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  LeastSquaresProblem problem = rosenbrock(2);
  std::vector<double> x = {-1.2, 1.0};
  const Summary summary =
      optimizer_from(R"({"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 15})")
          ->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::max_evaluations) << summary.full_report();
  EXPECT_EQ(summary.iterations, 15);
  EXPECT_EQ(summary.evaluations, 15 + 1);
  EXPECT_LT(summary.final_error, summary.initial_error);
}

TEST(Ceres, MaxIterationsIsReported) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_CERES);
  LeastSquaresProblem problem = rosenbrock(10);
  std::vector<double> x = classic_start(10);
  const Summary summary =
      optimizer_from(R"({"type": "ceres", "max_iterations": 2})")->minimize(problem, x);
  EXPECT_EQ(summary.termination, Termination::max_iterations) << summary.full_report();
  EXPECT_EQ(summary.iterations, 2);
}

// A callback that stops after `rows` trace rows, with `answer`.
IterationCallback stop_after(int rows, CallbackResult answer) {
  auto seen = std::make_shared<int>(0);
  return [seen, rows, answer](const IterationRecord&) {
    return ++*seen >= rows ? answer : CallbackResult::proceed;
  };
}

TEST(Callbacks, AbortDiscardsAndTerminateKeepsProgress) {
  for (const std::string json :
       {R"({"type": "ceres"})", R"({"type": "nlopt", "algorithm": "LD_LBFGS"})"}) {
    if (!testing::optimizer_built(json)) continue;
    LeastSquaresProblem problem = rosenbrock(2);
    std::vector<double> x = {-1.2, 1.0};
    Summary summary =
        optimizer_from(json)->minimize(problem, x, stop_after(3, CallbackResult::abort));
    EXPECT_EQ(summary.termination, Termination::user_abort) << json << summary.full_report();
    EXPECT_EQ(x, (std::vector<double>{-1.2, 1.0})) << json;
    EXPECT_EQ(summary.trace.size(), 3u) << json;

    x = {-1.2, 1.0};
    summary = optimizer_from(json)->minimize(problem, x, stop_after(3, CallbackResult::terminate));
    EXPECT_EQ(summary.termination, Termination::user_terminate) << json << summary.full_report();
    EXPECT_TRUE(summary.usable());
    EXPECT_LE(summary.final_error, summary.initial_error) << json;
    EXPECT_EQ(summary.trace.size(), 3u) << json;
  }
}

TEST(Callbacks, TraceRowsCountEvaluations) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  LeastSquaresProblem problem = rosenbrock(2);
  std::vector<double> x = {-1.2, 1.0};
  const Summary summary =
      optimizer_from(R"({"type": "nlopt", "algorithm": "LD_LBFGS"})")->minimize(problem, x);
  ASSERT_GE(summary.trace.size(), 2u);
  for (size_t i = 0; i < summary.trace.size(); ++i) {
    // One row per NLopt evaluation, after minimize's own initial evaluation.
    EXPECT_EQ(summary.trace[i].evaluations, static_cast<long long>(i) + 2);
    if (i > 0) {
      EXPECT_LE(summary.trace[i].best_error, summary.trace[i - 1].best_error);
    }
  }
}

}  // namespace
}  // namespace spec2fab

// "ceres": bounded nonlinear least squares with Ceres Solver on the problem's
// residuals (error = ½‖r(x)‖²), with the problem's analytic Jacobian or
// central finite differences of its residuals. Finite variable bounds
// become parameter bounds (Ceres projects steps onto them, which can stall a
// little short of a minimum on an active bound in a curved valley; NLopt's
// bounded methods do better there); discrete and choice variables are relaxed to
// their range and snapped to the nearest admissible value at the end.
// Ceres' own logging is silenced; its iterations become trace rows and
// consult the callback.
//
//   {"type": "ceres", "max_iterations": 100, "derivatives": "analytic",
//    "trust_region": "levenberg_marquardt", "linear_solver": "dense_qr"}

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "core/strings.h"
#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

namespace {

const std::vector<std::string> kLinearSolvers = {
    "dense_qr",     "dense_normal_cholesky", "dense_schur", "sparse_normal_cholesky",
    "sparse_schur", "iterative_schur",       "cgnr"};
const std::vector<std::string> kTrustRegions = {"levenberg_marquardt", "dogleg"};
const std::vector<std::string> kDerivatives = {"analytic", "numeric"};

// Problem::residuals behind Ceres' interface. Exceptions must not cross
// Ceres' frames: the first is kept and rethrown after Solve.
class Residuals {
 public:
  Residuals(Problem& problem, std::exception_ptr& failure) : problem_(problem), failure_(failure) {}

  bool evaluate(const double* x, double* residuals, double* jacobian) const {
    const auto n = static_cast<size_t>(problem_.dimension());
    const auto m = static_cast<size_t>(problem_.residual_count());
    // Problems see admissible points only: a discrete variable is relaxed for
    // Ceres and evaluated at its nearest admissible value.
    point_.resize(n);
    for (size_t i = 0; i < n; ++i) {
      point_[i] = problem_.domain(static_cast<int>(i)).nearest_admissible(x[i]);
    }
    try {
      problem_.residuals(point_, {residuals, m},
                         jacobian ? std::span<double>(jacobian, m * n) : std::span<double>());
    } catch (...) {
      if (!failure_) failure_ = std::current_exception();
      return false;
    }
    return std::all_of(residuals, residuals + m, [](double r) { return std::isfinite(r); });
  }

  // Functor of DynamicNumericDiffCostFunction.
  bool operator()(double const* const* parameters, double* residuals) const {
    return evaluate(parameters[0], residuals, nullptr);
  }

 private:
  Problem& problem_;
  std::exception_ptr& failure_;
  mutable std::vector<double> point_;  // Ceres evaluates on one thread here
};

class AnalyticCost final : public ceres::CostFunction {
 public:
  explicit AnalyticCost(const Residuals& residuals, int n, int m) : residuals_(residuals) {
    set_num_residuals(m);
    mutable_parameter_block_sizes()->push_back(n);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return residuals_.evaluate(parameters[0], residuals, jacobians ? jacobians[0] : nullptr);
  }

 private:
  Residuals residuals_;
};

// Ceres iterations → trace rows and our callback's answer.
class Progress final : public ceres::IterationCallback {
 public:
  Progress(const Problem& problem, Summary& summary, const spec2fab::IterationCallback& callback)
      : problem_(problem), summary_(summary), callback_(callback) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& step) override {
    best_ = std::min(best_, step.cost);
    answer = report_iteration(problem_, summary_, callback_, step.iteration, step.cost, best_);
    switch (answer) {
      case CallbackResult::proceed:
        return ceres::SOLVER_CONTINUE;
      case CallbackResult::abort:
        return ceres::SOLVER_ABORT;
      case CallbackResult::terminate:
        return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }

  CallbackResult answer = CallbackResult::proceed;

 private:
  const Problem& problem_;
  Summary& summary_;
  const spec2fab::IterationCallback& callback_;
  double best_ = std::numeric_limits<double>::infinity();
};

}  // namespace

class CeresAdapter final : public Optimizer {
 public:
  struct Options {
    int max_iterations = 100;
    // Ceres' own defaults.
    double function_tolerance = 1e-6;
    double gradient_tolerance = 1e-10;
    double parameter_tolerance = 1e-8;
    std::string derivatives = "analytic";
    std::string linear_solver = "dense_qr";
    std::string trust_region = "levenberg_marquardt";

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.max_iterations, "max_iterations", Range::at_least(1), "Ceres' max_num_iterations");
      d.number(o.function_tolerance, "function_tolerance", Range::at_least(0), "stop when |Δcost|/cost falls below");
      d.number(o.gradient_tolerance, "gradient_tolerance", Range::at_least(0),
               "stop when the projected gradient's max norm falls below");
      d.number(o.parameter_tolerance, "parameter_tolerance", Range::at_least(0),
               "stop when |Δx|/(|x| + tol) falls below");
      d.choice(o.derivatives, "derivatives", kDerivatives,
               "analytic (the problem's Jacobian: a tuner's comes through its simulator's pull_back, one "
               "reverse pass per residual) or numeric (central differences of residuals)");
      d.choice(o.linear_solver, "linear_solver", kLinearSolvers, "Ceres' linear solver for the trust-region step");
      d.choice(o.trust_region, "trust_region", kTrustRegions, "Ceres' trust-region strategy");
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit CeresAdapter(const Properties& properties)
      : options_(read_options<Options>(properties)) {}

  static TypeDoc doc() {
    return {"Bounded nonlinear least squares with Ceres Solver on the problem's residuals.",
            option_docs<Options>(),
            R"({"type": "ceres", "max_iterations": 100, "derivatives": "analytic", )"
            R"("trust_region": "levenberg_marquardt", "linear_solver": "dense_qr"})"};
  }

  std::string name() const override { return "ceres"; }
  /// Analytic derivatives need the problem's Jacobian, which a tuner has
  /// where its simulator and metric are differentiable (Capability::gradient).
  std::vector<Capability> requirements() const override {
    if (options_.derivatives == "analytic") return {Capability::residuals, Capability::gradient};
    return {Capability::residuals};
  }
  /// Ceres has no evaluation limit: iterations (each one or more evaluations)
  /// are let run up to the budget, and the caller's callback ends the run.
  void plan_evaluations(long long evaluations) override {
    options_.max_iterations = static_cast<int>(std::clamp<long long>(evaluations, 1, 1'000'000'000));
  }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    const int n = problem.dimension();
    const int m = problem.residual_count();
    if (n == 0 || m <= 0) {
      summary.termination = Termination::failure;
      summary.message = n == 0 ? "the problem has no variables" : "the problem has no residuals";
      return;
    }
    std::exception_ptr failure;
    const Residuals residuals(problem, failure);
    ceres::CostFunction* cost = nullptr;  // owned by the ceres::Problem
    if (options_.derivatives == "numeric") {
      auto* numeric = new ceres::DynamicNumericDiffCostFunction<Residuals, ceres::CENTRAL>(
          new Residuals(residuals));
      numeric->AddParameterBlock(n);
      numeric->SetNumResiduals(m);
      cost = numeric;
    } else {
      cost = new AnalyticCost(residuals, n, m);
    }
    ceres::Problem least_squares;
    least_squares.AddResidualBlock(cost, nullptr, x.data());
    for (int i = 0; i < n; ++i) {
      const VariableDomain& d = problem.domain(i);
      if (std::isfinite(d.smallest()))
        least_squares.SetParameterLowerBound(x.data(), i, d.smallest());
      if (std::isfinite(d.largest()))
        least_squares.SetParameterUpperBound(x.data(), i, d.largest());
    }

    ceres::Solver::Options solver = solver_options();
    Progress progress(problem, summary, callback);
    solver.callbacks.push_back(&progress);
    std::string invalid;
    if (!solver.IsValid(&invalid)) {
      // e.g. a sparse linear solver this Ceres was built without.
      summary.termination = Termination::failure;
      summary.message = "Ceres rejected the options: " + invalid;
      return;
    }

    ceres::Solver::Summary result;
    ceres::Solve(solver, &least_squares, &result);
    if (failure) std::rethrow_exception(failure);

    // Ceres counts iteration 0 (the start) among its successful steps.
    summary.iterations = result.iterations.empty() ? 0 : result.iterations.back().iteration;
    summary.message = "Ceres: " + result.message;
    summary.details["successful_steps"] = result.num_successful_steps;
    summary.details["unsuccessful_steps"] = result.num_unsuccessful_steps;
    summary.details["residual_evaluations"] = result.num_residual_evaluations;
    summary.details["jacobian_evaluations"] = result.num_jacobian_evaluations;
    switch (result.termination_type) {
      case ceres::CONVERGENCE:
        summary.termination = Termination::converged;
        break;
      case ceres::NO_CONVERGENCE:
        summary.termination = Termination::max_iterations;
        break;
      case ceres::USER_SUCCESS:
      case ceres::USER_FAILURE:
        if (!stop_requested(progress.answer, summary)) {
          summary.termination = Termination::failure;  // a user callback we did not install
        }
        break;
      case ceres::FAILURE:
      default:
        summary.termination = Termination::failure;
        break;
    }
    for (int i = 0; i < n; ++i) {
      x[static_cast<size_t>(i)] = problem.domain(i).nearest_admissible(x[static_cast<size_t>(i)]);
    }
  }

 private:
  /// Ceres' options from ours, silent (progress goes through the callback).
  ceres::Solver::Options solver_options() const {
    ceres::Solver::Options solver;
    solver.max_num_iterations = options_.max_iterations;
    solver.function_tolerance = options_.function_tolerance;
    solver.gradient_tolerance = options_.gradient_tolerance;
    solver.parameter_tolerance = options_.parameter_tolerance;
    ceres::StringToLinearSolverType(options_.linear_solver, &solver.linear_solver_type);
    ceres::StringToTrustRegionStrategyType(options_.trust_region,
                                           &solver.trust_region_strategy_type);
    solver.logging_type = ceres::SILENT;
    solver.minimizer_progress_to_stdout = false;
    return solver;
  }

  Options options_;
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::CeresAdapter, "ceres")

// "nlopt": any NLopt algorithm, named as NLopt names it ("LD_LBFGS",
// "LN_BOBYQA", "GN_DIRECT_L", ...). Gradient-based algorithms (LD_, GD_)
// need a problem with a gradient; global ones (GN_, GD_, G_MLSL) need finite
// bounds on every variable. Discrete and choice variables are relaxed to
// their range, evaluated at (and finally snapped to) the nearest admissible
// value. MLSL and AUGLAG variants get LD_LBFGS (gradient variants) or
// LN_BOBYQA as their local optimizer. NLopt has no iterations: each
// evaluation is a trace row and consults the callback.
//
//   {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 1000,
//    "ftol_rel": 1e-10, "xtol_rel": 1e-8}

#include <nlopt.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/strings.h"
#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

namespace {

std::vector<std::string> algorithm_names() {
  std::vector<std::string> names;
  for (int i = 0; i < NLOPT_NUM_ALGORITHMS; ++i) {
    names.emplace_back(nlopt_algorithm_to_string(static_cast<nlopt_algorithm>(i)));
  }
  return names;
}

std::string upper_case(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

bool starts_with_any(const std::string& name, std::initializer_list<const char*> prefixes) {
  for (const char* prefix : prefixes) {
    if (name.starts_with(prefix)) return true;
  }
  return false;
}

// What the objective needs; NLopt hands it back as void*.
struct Context {
  Problem& problem;
  Summary& summary;
  const IterationCallback& callback;
  nlopt_opt optimizer = nullptr;
  long long budget = 0;  // max_evaluations, for sampling trace rows
  std::vector<double> point{}, best_point{};
  long long evaluations = 0;
  double best = std::numeric_limits<double>::infinity();
  CallbackResult answer = CallbackResult::proceed;
  bool stopped = false;          // by the callback, max_evaluations or an exception
  std::exception_ptr failure{};  // exceptions must not cross NLopt's C frames
};

double objective(unsigned n, const double* x, double* gradient, void* data) {
  Context& c = *static_cast<Context*>(data);
  // NLopt may call again after nlopt_force_stop (and, left alone, goes one
  // evaluation past maxeval): such calls evaluate nothing and can never be
  // taken for the best point.
  if (c.stopped) {
    if (gradient) std::fill(gradient, gradient + n, 0.0);
    return HUGE_VAL;
  }
  try {
    for (unsigned i = 0; i < n; ++i) {
      c.point[i] = c.problem.domain(static_cast<int>(i)).nearest_admissible(x[i]);
    }
    const double error =
        gradient ? c.problem.error_and_gradient(c.point, {gradient, n}) : c.problem.error(c.point);
    if (error < c.best || c.evaluations == 0) {
      c.best = error;
      c.best_point = c.point;
    }
    c.answer = report_iteration(c.problem, c.summary, c.callback, static_cast<int>(c.evaluations),
                                error, c.best, trace_keeps(c.evaluations, c.budget));
    ++c.evaluations;
    // Our own stop at max_evaluations keeps the budget exact.
    if (c.answer != CallbackResult::proceed || c.evaluations >= c.budget) {
      c.stopped = true;
      nlopt_force_stop(c.optimizer);
    }
    return error;
  } catch (...) {
    if (!c.failure) c.failure = std::current_exception();
    c.stopped = true;
    nlopt_force_stop(c.optimizer);
    return HUGE_VAL;
  }
}

}  // namespace

class NloptAdapter final : public Optimizer {
 public:
  struct Options {
    std::string algorithm = "LN_BOBYQA";
    int max_evaluations = 1000;
    double ftol_rel = 1e-10;
    double xtol_rel = 1e-8;
    double max_seconds = 0;  ///< 0: no limit (a limit makes runs depend on the machine)
    int seed = 1;

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.value(o.algorithm, "algorithm", "NLopt's name, e.g. LD_LBFGS, LD_MMA, LN_BOBYQA, LN_COBYLA, GN_DIRECT_L");
      d.number(o.max_evaluations, "max_evaluations", Range::at_least(1), "error (and gradient) evaluations");
      d.number(o.ftol_rel, "ftol_rel", Range::at_least(0), "stop when the relative change of error falls below");
      d.number(o.xtol_rel, "xtol_rel", Range::at_least(0), "stop when the relative change of x falls below");
      d.number(o.max_seconds, "max_seconds", Range::at_least(0), "wall-time limit; 0: none");
      d.number(o.seed, "seed", Range::at_least(0),
               "picks the stream of NLopt's stochastic algorithms (under a schedule, mixed with the run's seed "
               "and the tuner's place)");
    }
    bool check(std::string* why) const {
      if (nlopt_algorithm_from_string(upper_case(algorithm).c_str()) >= 0) return true;
      *why = "algorithm: unknown NLopt algorithm '" + algorithm + "'" +
             did_you_mean(upper_case(algorithm), algorithm_names()) +
             " (for example LD_LBFGS, LD_MMA, LD_SLSQP, LN_BOBYQA, LN_COBYLA, LN_SBPLX, "
             "LN_NELDERMEAD, GN_DIRECT_L, GN_CRS2_LM, GN_ISRES; see NLopt's algorithm list)";
      return false;
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit NloptAdapter(const Properties& properties)
      : options_(read_options<Options>(properties)),
        algorithm_(upper_case(options_.algorithm)) {}

  static TypeDoc doc() {
    return {"Any NLopt algorithm by name: local or global, derivative-free or gradient-based.",
            option_docs<Options>(),
            R"({"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 1000, )"
            R"("ftol_rel": 1e-10, "xtol_rel": 1e-8})"};
  }

  std::string name() const override { return "nlopt"; }
  std::vector<Capability> requirements() const override {
    if (gradient_based()) return {Capability::gradient};
    return {};
  }
  /// The algorithms that draw random numbers (NLopt's nlopt_srand stream).
  bool stochastic() const override {
    return starts_with_any(algorithm_, {"GN_CRS2", "GN_ISRES", "GN_ESCH", "GN_MLSL", "GD_MLSL", "G_MLSL",
                                        "GD_STOGO_RAND"});
  }
  void plan_evaluations(long long evaluations) override {
    options_.max_evaluations = static_cast<int>(std::clamp<long long>(evaluations - 1, 1, 1'000'000'000));
  }
  std::optional<double> planned_evaluations(const Problem& /*problem*/) const override {
    return options_.max_evaluations + 1.0;
  }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    const auto n = static_cast<unsigned>(problem.dimension());
    std::vector<double> lower(n), upper(n);
    for (unsigned i = 0; i < n; ++i) {
      lower[i] = problem.domain(static_cast<int>(i)).smallest();
      upper[i] = problem.domain(static_cast<int>(i)).largest();
      if (global() && !(std::isfinite(lower[i]) && std::isfinite(upper[i]))) {
        summary.termination = Termination::failure;
        summary.message = "NLopt " + algorithm_ +
                          " is a global algorithm and needs finite bounds on every variable; "
                          "variable " +
                          std::to_string(i) + " has none";
        return;
      }
    }
    if (n == 0) {
      summary.termination = Termination::failure;
      summary.message = "the problem has no variables";
      return;
    }
    const auto algorithm = nlopt_algorithm_from_string(algorithm_.c_str());
    const std::unique_ptr<nlopt_opt_s, decltype(&nlopt_destroy)> optimizer(
        nlopt_create(algorithm, n), &nlopt_destroy);
    std::unique_ptr<nlopt_opt_s, decltype(&nlopt_destroy)> local(nullptr, &nlopt_destroy);
    if (!optimizer) throw std::runtime_error("NLopt could not create " + algorithm_);
    nlopt_opt opt = optimizer.get();

    Context context{problem, summary, callback};
    context.optimizer = opt;
    context.budget = options_.max_evaluations;
    context.point.resize(n);
    nlopt_set_min_objective(opt, objective, &context);
    nlopt_set_lower_bounds(opt, lower.data());
    nlopt_set_upper_bounds(opt, upper.data());
    nlopt_set_maxeval(opt, options_.max_evaluations);
    nlopt_set_ftol_rel(opt, options_.ftol_rel);
    nlopt_set_xtol_rel(opt, options_.xtol_rel);
    if (options_.max_seconds > 0) nlopt_set_maxtime(opt, options_.max_seconds);
    if (algorithm_.find("MLSL") != std::string::npos ||
        algorithm_.find("AUGLAG") != std::string::npos) {
      local.reset(nlopt_create(gradient_based() ? NLOPT_LD_LBFGS : NLOPT_LN_BOBYQA, n));
      nlopt_set_ftol_rel(local.get(), options_.ftol_rel);
      nlopt_set_xtol_rel(local.get(), options_.xtol_rel);
      nlopt_set_local_optimizer(opt, local.get());
    }
    nlopt_srand(static_cast<unsigned long>(random_seed(options_.seed)));

    double minimum = 0;
    const nlopt_result result = nlopt_optimize(opt, x.data(), &minimum);
    if (context.failure) std::rethrow_exception(context.failure);

    summary.iterations = static_cast<int>(context.evaluations);
    summary.message = "NLopt " + algorithm_ + ": " + nlopt_result_to_string(result);
    // After a stop of ours NLopt may report FORCED_STOP or, from inside a line
    // search, FAILURE, and x may not be its best: decide and pick ourselves.
    if (context.stopped && context.evaluations > 0) {
      x = context.best_point;
      if (stop_requested(context.answer, summary)) return;
      summary.termination = Termination::max_evaluations;
      summary.message = "NLopt " + algorithm_ + ": max_evaluations reached";
      return;
    }
    if (!read_result(result, opt, summary)) return;
    for (unsigned i = 0; i < n; ++i)
      x[i] = problem.domain(static_cast<int>(i)).nearest_admissible(x[i]);
  }


 private:
  /// NLopt's result as a termination (its message appended); false when it failed.
  static bool read_result(nlopt_result result, nlopt_opt opt, Summary& summary) {
    switch (result) {
      case NLOPT_SUCCESS:
      case NLOPT_STOPVAL_REACHED:
      case NLOPT_FTOL_REACHED:
      case NLOPT_XTOL_REACHED:
        summary.termination = Termination::converged;
        break;
      case NLOPT_ROUNDOFF_LIMITED:
        // NLopt's own advice: the point is then typically as good as rounding allows.
        summary.termination = Termination::converged;
        summary.message += " (rounding limited further progress)";
        break;
      case NLOPT_MAXEVAL_REACHED:
        summary.termination = Termination::max_evaluations;
        break;
      case NLOPT_MAXTIME_REACHED:
        summary.termination = Termination::max_iterations;
        summary.message += " (max_seconds)";
        break;
      default: {
        summary.termination = Termination::failure;
        const char* why = nlopt_get_errmsg(opt);
        if (why) summary.message += std::string(": ") + why;
        return false;
      }
    }
    return true;
  }

  bool gradient_based() const { return starts_with_any(algorithm_, {"LD_", "GD_"}); }
  bool global() const { return starts_with_any(algorithm_, {"GN_", "GD_", "G_MLSL"}); }

  Options options_;
  std::string algorithm_;  ///< upper case, as NLopt spells it
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::NloptAdapter, "nlopt")

// "spsa": simultaneous perturbation stochastic approximation (Spall 1998), as
// Finckh et al. 2010 tuned noisy simulations with it. Iteration k perturbs
// every variable at once by ±c_k (Rademacher signs), estimates the gradient
// from the two errors, steps by −a_k·ĝ and projects onto the bounds:
//   a_k = a/(k + 1 + A)^alpha,  c_k = c/(k + 1)^gamma.
// It works in coordinates scaled to each variable's range (unit scale for an
// unbounded one), so a and c are fractions of the range; discrete and choice
// variables are evaluated at the nearest admissible value. Two evaluations
// per iteration. Returns the best point evaluated (the final iterate, then
// evaluated once more, included), or with result "last_iterate" the final
// iterate: the lowest of many noisy errors mostly measures luckiest noise.
//
//   {"type": "spsa", "iterations": 1000, "c": 0.05, "seed": 1}

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../random.h"
#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

/// Scaled coordinates u: x = offset + scale·u, u in [0, 1] for bounded
/// variables (the perturbation and the first step are fractions of a range).
struct ScaledCoordinates {
  std::vector<double> offset, scale, lower, upper;
  explicit ScaledCoordinates(const Problem& problem) {
    for (int i = 0; i < problem.dimension(); ++i) {
      const VariableDomain& d = problem.domain(i);
      const double lo = d.smallest(), hi = d.largest();
      const bool bounded = std::isfinite(lo) && std::isfinite(hi) && hi > lo;
      offset.push_back(bounded ? lo : 0.0);
      scale.push_back(bounded ? hi - lo : 1.0);
      lower.push_back(bounded ? 0.0 : (lo - offset.back()) / scale.back());
      upper.push_back(bounded ? 1.0 : (hi - offset.back()) / scale.back());
    }
  }
  std::vector<double> of(const std::vector<double>& x) const {
    std::vector<double> u(x.size());
    for (size_t i = 0; i < x.size(); ++i) u[i] = (x[i] - offset[i]) / scale[i];
    return u;
  }
  void to_x(Problem& problem, const std::vector<double>& u, std::vector<double>& x) const {
    for (size_t i = 0; i < u.size(); ++i)
      x[i] = problem.domain(static_cast<int>(i)).nearest_admissible(offset[i] + scale[i] * u[i]);
  }
};

class Spsa final : public Optimizer {
 public:
  struct Options {
    int iterations = 1000;
    double a = 0;     ///< step gain; 0: calibrated at the start (see doc)
    double first_step = 0.1;  ///< calibration's first step, as a fraction of each range
    double c = 0.05;  ///< perturbation, as a fraction of each range
    double A = -1;    ///< stability constant; < 0: 10% of iterations
    double alpha = 0.602;
    double gamma = 0.101;
    int seed = 1;
    /// "best_seen" (Finckh et al.) or "last_iterate" (for noisy errors, where
    /// the lowest error seen flatters the point that drew the luckiest noise)
    std::string result = "best_seen";

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.iterations, "iterations", Range::at_least(1), "gradient estimates and steps");
      d.number(o.a, "a", Range::at_least(0),
               "step gain a; 0 calibrates it from 4 gradient estimates at the start so that the "
               "first step moves about first_step of each range");
      d.number(o.first_step, "first_step", Range::open_closed(0, 1),
               "calibrated first step, as a fraction of each range (small for sensitive errors, e.g. "
               "caustics, where a micrometre of height moves light by a pixel)");
      d.number(o.c, "c", Range::above(0), "perturbation c, as a fraction of each variable's range");
      d.number(o.A, "A", Range::any(), "stability constant A; negative means 10% of iterations");
      d.number(o.alpha, "alpha", Range::open_closed(0, 1), "decay exponent of a_k");
      d.number(o.gamma, "gamma", Range::open_closed(0, 1), "decay exponent of c_k, at most alpha");
      d.number(o.seed, "seed", Range::at_least(0),
               "picks the random stream (under a schedule, mixed with the run's seed and the tuner's place)");
      d.choice(o.result, "result", {"best_seen", "last_iterate"},
               "best_seen: the lowest error evaluated, the final iterate included; last_iterate: "
               "the final iterate (better when the error is noisy)");
    }
    bool check(std::string* why) const {
      if (gamma > alpha) {
        *why = "gamma: must lie in (0, alpha]";
        return false;
      }
      return true;
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit Spsa(const Properties& properties) : options_(read_options<Options>(properties)) {}

  static TypeDoc doc() {
    return {
        "Simultaneous perturbation stochastic approximation (Spall 1998) for noisy errors: "
        "two evaluations per iteration whatever the dimension.",
        option_docs<Options>(),
        R"({"type": "spsa", "iterations": 1000, "c": 0.05, "seed": 1})"};
  }

  std::string name() const override { return "spsa"; }
  bool stochastic() const override { return true; }
  /// Two evaluations per iteration, after the start's, the gain calibration's
  /// and before the final iterate's.
  void plan_evaluations(long long evaluations) override {
    const long long fixed = 1 + (options_.a == 0 ? 2 * kCalibrationSamples : 0) + 1;
    options_.iterations = static_cast<int>(std::clamp<long long>((evaluations - fixed) / 2, 1, 1'000'000'000));
  }
  std::optional<double> planned_evaluations(const Problem& /*problem*/) const override {
    return 2.0 + (options_.a == 0 ? 2.0 * kCalibrationSamples : 0.0) + 2.0 * options_.iterations;
  }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    const auto n = static_cast<size_t>(problem.dimension());
    Random random(random_seed(options_.seed));
    const ScaledCoordinates scaled(problem);
    const std::vector<double>& lower = scaled.lower;
    const std::vector<double>& upper = scaled.upper;
    std::vector<double> u = scaled.of(x);
    const auto to_x = [&](const std::vector<double>& v, std::vector<double>& out) { scaled.to_x(problem, v, out); };

    double best = std::isnan(summary.initial_error) ? HUGE_VAL : summary.initial_error;
    std::vector<double> best_x = x;
    std::vector<double> delta(n), u_plus(n), u_minus(n), x_plus(n), x_minus(n), gradient(n);
    // One gradient estimate at u with perturbation ck; returns the mean of the two errors.
    const auto estimate = [&](double ck) {
      for (size_t i = 0; i < n; ++i) {
        delta[i] = random.sign();
        u_plus[i] = std::clamp(u[i] + ck * delta[i], lower[i], upper[i]);
        u_minus[i] = std::clamp(u[i] - ck * delta[i], lower[i], upper[i]);
      }
      to_x(u_plus, x_plus);
      to_x(u_minus, x_minus);
      const double y_plus = problem.error(x_plus);
      const double y_minus = problem.error(x_minus);
      for (const auto& [y, point] : {std::pair{y_plus, &x_plus}, std::pair{y_minus, &x_minus}}) {
        if (y < best) {
          best = y;
          best_x = *point;
        }
      }
      const double difference = y_plus - y_minus;
      for (size_t i = 0; i < n; ++i) {
        // Projection can shorten the perturbation: divide by the actual one.
        const double du = u_plus[i] - u_minus[i];
        gradient[i] = du != 0 && std::isfinite(difference) ? difference / du : 0.0;
      }
      return 0.5 * (y_plus + y_minus);
    };

    const double big_a =
        options_.A >= 0 ? options_.A : 0.1 * static_cast<double>(options_.iterations);
    double a = options_.a;
    if (a == 0) {
      // Spall's rule: a_0·mean|ĝ| ≈ the wanted first step (10% of the range).
      const int samples = kCalibrationSamples;
      double magnitude = 0;
      for (int s = 0; s < samples; ++s) {
        estimate(options_.c);
        for (double g : gradient) magnitude += std::abs(g);
      }
      magnitude /= samples * std::max<double>(1.0, static_cast<double>(n));
      a = options_.first_step * std::pow(big_a + 1, options_.alpha) / (magnitude > 0 ? magnitude : 1.0);
      summary.details["calibration_evaluations"] = 2 * samples;
    }

    for (int k = 0; k < options_.iterations; ++k) {
      const double ak = a / std::pow(k + 1 + big_a, options_.alpha);
      const double ck = options_.c / std::pow(k + 1, options_.gamma);
      const double mean_error = estimate(ck);
      for (size_t i = 0; i < n; ++i) u[i] = std::clamp(u[i] - ak * gradient[i], lower[i], upper[i]);
      summary.iterations = k + 1;
      const CallbackResult answer = report_iteration(problem, summary, callback, k, mean_error,
                                                     best, trace_keeps(k, options_.iterations));
      if (stop_requested(answer, summary)) break;
    }
    if (options_.result == "last_iterate") {
      to_x(u, x);
    } else if (summary.termination != Termination::user_abort) {
      std::vector<double> final_x(n);
      to_x(u, final_x);
      if (problem.error(final_x) <= best) best_x = final_x;
      x = best_x;
    }
    end_after_iterations(summary, options_.iterations);
    summary.details["a"] = a;
    summary.details["A"] = big_a;
  }


 private:
  static constexpr int kCalibrationSamples = 4;  ///< gradient estimates that calibrate a
  Options options_;
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::Spsa, "spsa")

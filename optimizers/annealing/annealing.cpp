// "annealing": simulated annealing over mixed variables. Each iteration
// proposes one move and accepts it by the Metropolis rule at the current
// temperature:
//   - change one variable: a continuous one by a Gaussian step of
//     step_fraction × its range (reflected at the bounds), a discrete or
//     choice one to another admissible value drawn uniformly;
//   - or, with probability swap_probability when the problem offers
//     neighbour moves, exchange states with a random neighbouring tuner
//     (accepted on swap_delta, performed by commit_swap).
// Temperature schedules: exponential T0·cooling^k, linear T0·(1 − k/iterations),
// logarithmic T0/log(k + 2). With schedule_iterations longer than iterations
// the schedule spans successive runs of the optimizer — a tuner network runs
// each tuner many times, and its temperature should keep falling. Returns the best point seen since the last
// committed swap (a neighbour already holds the state given away).
//
//   {"type": "annealing", "iterations": 10000, "initial_temperature": 1.0,
//    "cooling": 0.999, "schedule": "exponential", "step_fraction": 0.1,
//    "swap_probability": 0.2, "seed": 1}

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../random.h"
#include "core/strings.h"
#include "core/options.h"
#include "tuning/optimizer.h"

namespace spec2fab {

class Annealing final : public Optimizer {
 public:
  struct Options {
    int iterations = 10000;
    int schedule_iterations = 0;  ///< 0: iterations (each run anneals from T0)
    double initial_temperature = 1.0;
    double cooling = 0.999;  ///< alpha of the exponential schedule
    std::string schedule = "exponential";
    double step_fraction = 0.1;
    double swap_probability = 0.2;
    int seed = 1;

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.iterations, "iterations", Range::at_least(1), "moves proposed (one error evaluation each)");
      d.number(o.schedule_iterations, "schedule_iterations", Range::at_least(0),
               "length of the temperature schedule (0: iterations); longer than iterations, it continues "
               "over successive runs (a tuner run once per sweep cools over the sweeps)");
      d.number(o.initial_temperature, "initial_temperature", Range::above(0), "T0, in units of the error");
      d.number(o.cooling, "cooling", Range::open_closed(0, 1), "alpha of the exponential schedule");
      d.choice(o.schedule, "schedule", {"exponential", "linear", "logarithmic"}, "how the temperature falls");
      d.number(o.step_fraction, "step_fraction", Range::open_closed(0, 1),
               "Gaussian step of a continuous variable, as a fraction of its range");
      d.number(o.swap_probability, "swap_probability", Range::closed(0, 1),
               "chance that a move is a swap with a neighbour (problems with neighbour moves)");
      d.number(o.seed, "seed", Range::at_least(0),
               "picks the random stream (under a schedule, mixed with the run's seed and the tuner's place)");
    }
    bool check(std::string* why) const {
      if (schedule_iterations != 0 && schedule_iterations < iterations) {
        *why = "schedule_iterations: must be 0 or at least iterations";
        return false;
      }
      return true;
    }
    bool IsValid(std::string* why) const { return options_valid(*this, why); }
  };

  explicit Annealing(const Properties& properties)
      : options_(read_options<Options>(properties)) {}

  static TypeDoc doc() {
    return {
        "Simulated annealing over continuous, discrete and choice variables, with optional "
        "state swaps between neighbouring tuners.",
        option_docs<Options>(),
        R"({"type": "annealing", "iterations": 10000, "initial_temperature": 1.0, )"
        R"("cooling": 0.999, "schedule": "exponential", "seed": 1})"};
  }

  std::string name() const override { return "annealing"; }
  bool stochastic() const override { return true; }
  /// One evaluation per move after the start's; the exponential schedule is
  /// stretched to keep the final temperature its options give.
  void plan_evaluations(long long evaluations) override {
    const int iterations = static_cast<int>(std::clamp<long long>(evaluations - 1, 1, 1'000'000'000));
    const double length = static_cast<double>(schedule_length());
    options_.cooling = std::pow(options_.cooling, length / iterations);
    options_.iterations = iterations;
    options_.schedule_iterations = 0;
    scheduled_ = 0;
  }
  std::optional<double> planned_evaluations(const Problem& /*problem*/) const override {
    return options_.iterations + 1.0;
  }
  nlohmann::json saved_state() const override { return scheduled_; }
  void restore(const nlohmann::json& state) override { scheduled_ = state.get<long long>(); }

 protected:
  void run(Problem& problem, std::vector<double>& x, Summary& summary,
           const IterationCallback& callback) override {
    Random random(random_seed(options_.seed));
    const int n = problem.dimension();
    std::vector<int> movable;
    for (int i = 0; i < n; ++i) {
      const VariableDomain& d = problem.domain(i);
      if (d.kind == ParameterKind::continuous ? d.upper > d.lower : d.cardinality() > 1) {
        movable.push_back(i);
      }
    }
    const bool swaps = problem.has(Capability::neighbour_moves) && problem.neighbour_count() > 0 &&
                       options_.swap_probability > 0;
    if (movable.empty() && !swaps) {
      summary.termination = Termination::converged;
      summary.message = "no variable can change and there is no neighbour to swap with";
      return;
    }

    // A NaN start is beaten by anything.
    double error = std::isnan(summary.initial_error) ? HUGE_VAL : summary.initial_error;
    std::vector<double> best_x = x;
    double best = error;
    long long accepted = 0, rejected = 0, swaps_proposed = 0, swaps_accepted = 0;
    double temperature = options_.initial_temperature;
    if (schedule_length() == options_.iterations) scheduled_ = 0;
    const auto metropolis = [&](double delta) {
      return delta <= 0 || random.uniform() < std::exp(-delta / temperature);
    };

    for (int k = 0; k < options_.iterations; ++k) {
      temperature = temperature_at(scheduled_++);
      if (swaps && (movable.empty() || random.uniform() < options_.swap_probability)) {
        ++swaps_proposed;
        const int neighbour = static_cast<int>(random.index(problem.neighbour_count()));
        if (metropolis(problem.swap_delta(x, neighbour))) {
          ++swaps_accepted;
          x = problem.commit_swap(x, neighbour);
          error = problem.error(x);
          best_x = x;
          best = error;
        }
      } else {
        const int i =
            movable[static_cast<size_t>(random.index(static_cast<long long>(movable.size())))];
        const auto u = static_cast<size_t>(i);
        const double old_value = x[u];
        x[u] = propose(problem.domain(i), old_value, random);
        const double candidate = problem.error(x);
        if (metropolis(candidate - error)) {
          ++accepted;
          error = candidate;
          if (error < best) {
            best = error;
            best_x = x;
          }
        } else {
          ++rejected;
          x[u] = old_value;
        }
      }
      summary.iterations = k + 1;
      const CallbackResult answer = report_iteration(problem, summary, callback, k, error, best,
                                                     trace_keeps(k, options_.iterations));
      if (stop_requested(answer, summary)) break;
    }
    x = best_x;
    end_after_iterations(summary, options_.iterations);
    summary.details["accepted"] = accepted;
    summary.details["rejected"] = rejected;
    summary.details["swaps_proposed"] = swaps_proposed;
    summary.details["swaps_accepted"] = swaps_accepted;
    summary.details["final_temperature"] = temperature;
  }


 private:
  long long schedule_length() const {
    return options_.schedule_iterations > 0 ? options_.schedule_iterations : options_.iterations;
  }
  // k counts iterations since the schedule began (over runs, for a long schedule).
  double temperature_at(long long k) const {
    const long long length = schedule_length();
    k = std::min(k, length - 1);
    const double t0 = options_.initial_temperature;
    if (options_.schedule == "linear") {
      return t0 * (1.0 - static_cast<double>(k) / static_cast<double>(length));
    }
    if (options_.schedule == "logarithmic") return t0 / std::log(k + 2.0);
    return t0 * std::pow(options_.cooling, static_cast<double>(k));
  }

  double propose(const VariableDomain& d, double value, Random& random) const {
    if (d.kind != ParameterKind::continuous) {
      // Another admissible value, uniformly: skip over the current index.
      const long long current = d.index_of(value);
      long long j = random.index(d.cardinality() - 1);
      if (j >= current) ++j;
      return d.admissible(j);
    }
    const double range = d.upper - d.lower;
    const double scale =
        options_.step_fraction * (std::isfinite(range) ? range : std::max(1.0, std::abs(value)));
    double y = value + scale * random.normal();
    // Reflect rather than clamp, so that the bounds do not collect samples.
    if (y < d.lower) y = 2 * d.lower - y;
    if (y > d.upper) y = 2 * d.upper - y;
    return std::clamp(y, d.lower, d.upper);
  }

  Options options_;
  long long scheduled_ = 0;  ///< iterations into the temperature schedule
};

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::OptimizerRegistry, spec2fab::Annealing, "annealing")

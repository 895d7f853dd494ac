#pragma once
/// Optimizers, in the manner of Ceres: each has flat `Options` with defaults
/// written in the class, each option declared once (core/options.h: reading,
/// `IsValid(std::string* why)` naming a bad field, and the documentation),
/// and returns a `Summary` (termination, initial/final error, evaluations,
/// iterations, time, a per-iteration trace, brief and full reports).
///
/// An optimizer is one folder under optimizers/ ending in
/// `SPEC2FAB_REGISTER(OptimizerRegistry, MyOptimizer, "my_optimizer")`: a
/// constructor from (const Properties&) that reads its Options, `static
/// TypeDoc doc()`, `requirements()` and `run()`.

#include <cstdint>
#include <functional>
#include <memory>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "tuning/problem.h"

namespace spec2fab {

enum class Termination {
  not_run,    ///< "Solve was not called."
  converged,  ///< a tolerance was met (or, for exact methods, optimality proved)
  max_iterations,
  max_evaluations,
  user_abort,      ///< a callback asked to stop and discard the run's progress
  user_terminate,  ///< a callback asked to stop and keep the best point found
  failure,         ///< the method failed (message says why)
};
std::string to_string(Termination termination);

/// One row of the convergence trace.
struct IterationRecord {
  int iteration = 0;
  long long evaluations = 0;  ///< error() calls so far (gradient calls count as one)
  double error = 0;           ///< error at the current point
  double best_error = 0;      ///< best error so far
  double seconds = 0;         ///< wall time since the start
};

enum class CallbackResult { proceed, abort, terminate };
using IterationCallback = std::function<CallbackResult(const IterationRecord&)>;

struct Summary {
  std::string optimizer;
  Termination termination = Termination::not_run;
  std::string message = "Solve was not called.";
  double initial_error = std::numeric_limits<double>::quiet_NaN();
  double final_error = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> initial_x, final_x;
  long long evaluations = 0;
  int iterations = 0;
  double seconds = 0;
  std::vector<IterationRecord> trace;
  nlohmann::json details =
      nlohmann::json::object();  ///< method-specific figures (e.g. nodes pruned)

  bool usable() const {
    return termination != Termination::not_run && termination != Termination::failure;
  }
  /// One line: optimizer, termination, initial → final error, evaluations, time.
  std::string brief_report() const;
  /// Several lines, including details and the trace's first and last rows.
  std::string full_report() const;
  /// Everything but wall times, which go to timing records (runs must be
  /// byte-identical whatever the machine's speed).
  nlohmann::json to_json() const;
};

class Optimizer {
 public:
  virtual ~Optimizer() = default;
  /// The registered name, e.g. "annealing".
  virtual std::string name() const = 0;
  /// Capabilities a problem must offer.
  virtual std::vector<Capability> requirements() const { return {}; }
  /// Whether runs that differ only in seed may differ (the bench runs these
  /// over many seeds, the others once).
  virtual bool stochastic() const { return false; }
  /// Tells the method that a run will be stopped after `evaluations` error
  /// evaluations (the start's included), as the bench's budget does, so that
  /// a schedule it has (annealing's temperatures, SPSA's gains, an
  /// evaluation limit) spans that budget instead of its own default length.
  /// Methods without a schedule ignore it; the caller still stops the run.
  virtual void plan_evaluations(long long /*evaluations*/) {}
  /// How many error evaluations one run on `problem` makes at most, the
  /// start's included, as its options stand (annealing's iterations + 1,
  /// NLopt's max_evaluations…): what a schedule's estimate counts before it
  /// starts (docs/robustness.md). Nothing when the method cannot say in
  /// advance (branch and bound prunes as it goes).
  virtual std::optional<double> planned_evaluations(const Problem& /*problem*/) const { return std::nullopt; }
  /// A schedule gives every tuner run a seed derived from (run seed, phase,
  /// sweep, tuner), so results never depend on which thread ran what.
  /// Stochastic optimizers draw from random_seed(their "seed" option).
  void set_seed(std::uint64_t schedule_seed) { schedule_seed_ = schedule_seed; }
  /// What the method carries from one run to the next (annealing's place in
  /// a temperature schedule that spans runs): a schedule's checkpoint saves
  /// it, and restore() takes it up in a resumed run.
  virtual nlohmann::json saved_state() const { return nullptr; }
  virtual void restore(const nlohmann::json& /*state*/) {}

  /// Minimises `problem` from `x` (start in, best point out). Refuses, with
  /// std::invalid_argument naming the optimizer and the missing capability,
  /// a problem that lacks a requirement. Never throws for a failed search:
  /// the Summary says so.
  Summary minimize(Problem& problem, std::vector<double>& x,
                   const IterationCallback& callback = {});

 protected:
  /// The seed of a stochastic run. The "seed" option has one meaning: it
  /// picks the random stream. Run alone, the optimizer seeds from it
  /// directly; under a schedule, it is mixed with the schedule's seed for
  /// this tuner run, so every tuner still draws its own stream and changing
  /// the option (or the run's --seed) changes them all.
  std::uint64_t random_seed(int option_seed) const;

  /// The method itself: fills summary.termination/message/iterations/trace/
  /// details and leaves the best point in x. `minimize` counts evaluations,
  /// times the run and records initial/final error around it.
  virtual void run(Problem& problem, std::vector<double>& x, Summary& summary,
                   const IterationCallback& callback) = 0;

 private:
  std::optional<std::uint64_t> schedule_seed_;
};

/// For run(): passes the row for `iteration` — evaluations so far and wall
/// time filled in — to `callback` and, when `keep`, appends it to
/// summary.trace (long runs keep a sample of rows, see trace_keeps). Returns
/// the callback's answer; proceed when there is no callback.
CallbackResult report_iteration(const Problem& problem, Summary& summary,
                                const IterationCallback& callback, int iteration, double error,
                                double best_error, bool keep = true);

/// For run(): when `answer` asks to stop, records user_abort or
/// user_terminate (with a message) in `summary` and returns true.
bool stop_requested(CallbackResult answer, Summary& summary);

/// For run(): a run that went through all its `iterations` without another
/// ending (a tolerance, the callback) ends with max_iterations.
void end_after_iterations(Summary& summary, long long iterations);

/// Whether iteration `iteration` of `iterations` gets a trace row when a run
/// keeps about `rows` evenly spaced rows (always the first and the last).
bool trace_keeps(long long iteration, long long iterations, long long rows = 1000);

using OptimizerRegistry = Registry<Optimizer>;

/// Builds the optimizer described by `properties` (its "type" names it).
std::unique_ptr<Optimizer> build_optimizer(const Properties& properties);

/// Which optimizer a translator's tuners use, built as often as asked (one
/// per tuner): the experiment's own section, read where the user wrote it,
/// or else the translator's documented default. A default is written as a
/// user would write one because it may name an optional module's optimizer
/// (NLopt): a build without it must say which option left it out, which a
/// typed reference could not. Anything else wrong with a default is the
/// translator's bug (std::logic_error), never the user's input; the tests
/// validate every shipped experiment, which builds every default.
class OptimizerChoice {
 public:
  /// `parent`'s object at `key` when it has one ("optimizer" of the
  /// experiment), else `fallback`.
  OptimizerChoice(const Properties& parent, std::string_view key, nlohmann::json fallback);
  /// Checks the choice by building it once (a malformed section is reported
  /// before any work) and returns a new optimizer each call after.
  std::unique_ptr<Optimizer> build() const;
  /// The choice as JSON, the user's section or the default: what a schedule
  /// phase builds (Phase::optimizer) and what labels name.
  const nlohmann::json& spec() const { return spec_; }

 private:
  std::optional<Properties> section_;
  nlohmann::json spec_;
  std::string where_;  ///< the key's JSON path, given or not
};

}  // namespace spec2fab

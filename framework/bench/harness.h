#pragma once
/// The optimizer × problem matrix of `spec2fab bench` (docs/benchmarking.md),
/// after COCO/IOHprofiler (fixed-target runtimes, ECDFs over a ladder of
/// targets, many seeds) and Nevergrad (a fight matrix of win rates).
///
/// Every entrant (a registered optimizer with its options) runs on every
/// registered problem whose capabilities it needs; deterministic ones once,
/// stochastic ones once per seed. Each run gets its own instance of the
/// problem and stops at the budget; every evaluation it makes is logged.
/// Runs go in parallel, and everything but wall times is the same for any
/// thread count.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/benchmark_problem.h"
#include "tuning/optimizer.h"

namespace spec2fab {

/// An optimizer as it enters the matrix: a label and its JSON.
struct Entrant {
  std::string label;         ///< "lbfgs"
  nlohmann::json optimizer;  ///< {"type": "nlopt", "algorithm": "LD_LBFGS"}
};

/// The entrants of `file` ({"entrants": [{"label": ..., "optimizer": {...}}]}),
/// then every registered optimizer no entrant names, at its defaults, so a
/// new optimizer joins the matrix without an edit.
std::vector<Entrant> read_entrants(const std::filesystem::path& file);

/// How long each run may go: evaluations (a multiple of the problem's
/// dimension, or a number) and/or wall seconds; whichever comes first.
struct Budget {
  double per_dimension = 0;   ///< "100d"
  long long evaluations = 0;  ///< "5000"
  double seconds = 0;         ///< "30s" (makes results depend on the machine)
  /// "100d", "5000", "30s" or several joined by commas; throws InputError.
  static Budget parse(const std::string& text);
  /// The evaluation limit for a problem of `dimension` variables (0: none).
  long long evaluations_for(int dimension) const;
  std::string describe() const;
};

struct BenchProgress {
  size_t runs_done = 0, runs = 0;
  size_t pairs_done = 0, pairs = 0;  ///< pairs with every run done, of the pairs that run
};

struct BenchOptions {
  std::vector<std::string> problems;  ///< empty: every registered problem
  std::vector<Entrant> entrants;
  int seeds = 15;  ///< runs of a stochastic entrant per problem
  Budget budget{100, 0, 0};
  int threads = 0;  ///< 0: all cores
  /// Called after each run (from one thread at a time).
  std::function<void(const BenchProgress&)> progress;
};

/// One problem as benchmarked: its facts and start error, or why it could
/// not be built (a module left out of this build).
struct BenchProblem {
  std::string name;
  int function_id = 0;  ///< IOHprofiler's funcId: place among the registered problems
  BenchmarkFacts facts;
  double start_error = 0;
  std::string unavailable;  ///< non-empty: not run, and why
  /// The target ladder: optimum + (start − optimum)·10^−k, k = 1..8.
  std::vector<double> targets;
  long long budget = 0;  ///< evaluations (0: seconds only)
};

/// An (entrant, problem) pair: run, or why not.
struct BenchPair {
  size_t entrant = 0, problem = 0;
  std::string missing;  ///< the capability the problem lacks; empty when run
  bool stochastic = false;
};

/// Everything one run did, evaluation by evaluation.
struct BenchRun {
  size_t pair = 0;
  int seed = 1;
  std::vector<double> errors;  ///< every evaluation's error, the start's first
  long long bound_evaluations = 0;
  double wall_seconds = 0, simulator_seconds = 0;
  /// Wall time at each evaluation's end (seconds since the run began), and
  /// the time spent inside evaluations (simulator and metric) by then.
  std::vector<double> seconds, simulator_seconds_at;
  /// The optimizer's own account of the run (its evaluations, trace).
  Summary summary;
  std::string termination;
  std::vector<double> best_x;

  double best() const;
  /// Evaluations until the best error first reached `target`, or nothing.
  std::optional<long long> hitting_time(double target) const;
};

struct BenchResult {
  std::vector<Entrant> entrants;
  std::vector<BenchProblem> problems;
  std::vector<BenchPair> pairs;
  std::vector<BenchRun> runs;  ///< in (pair, seed) order
  int seeds = 0;
  std::string budget;
  double wall_seconds = 0;
  int threads = 0;
};

/// A capability as the report names it: "gradient", "residuals", "bound",
/// "discrete domain", "neighbour moves".
std::string capability_name(Capability capability);

/// Builds the problems, decides the pairs and runs them.
BenchResult run_bench(const BenchOptions& options, const BenchmarkContext& context);

/// About how many bytes write_bench_report writes for `options`, known
/// before anything runs (`spec2fab bench` refuses when the disk has less
/// free): per problem its plots and its share of report.html, per run its
/// IOHprofiler block and trace, and the page's script and summaries.
long long estimated_bench_report_bytes(const BenchOptions& options);

/// Expected running time to `target` over `runs`: evaluations spent by all
/// runs (to the hit, or their whole length) over the number that hit;
/// nothing when none did.
std::optional<double> expected_running_time(const std::vector<const BenchRun*>& runs,
                                            double target);

/// Writes `folder`/ioh/ (IOHprofiler's JSON format: one folder per entrant,
/// IOHprofiler_f<id>_<problem>.json + data_f<id>_<problem>/*.dat), report.md
/// (matrix, fights, incompatible pairs), report.json, plots/*.png and
/// timing/ (wall and simulator seconds, which vary with the machine).
void write_bench_report(const BenchResult& result, const std::filesystem::path& folder);

}  // namespace spec2fab

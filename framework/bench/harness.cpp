#include "bench/harness.h"

#include "core/interrupt.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/error.h"
#include "core/strings.h"
#include "tuning/optimizer.h"

namespace spec2fab {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// Passes everything to the problem it wraps and logs each evaluation: its
/// error, when it ended, and the time spent inside (the simulator's and
/// metric's). A residual evaluation's error is ½‖r‖², as Problem defines it.
class RecordingProblem final : public Problem {
 public:
  RecordingProblem(Problem& inner, BenchRun& run)
      : inner_(inner), run_(run), start_(Clock::now()) {}

  int dimension() const override { return inner_.dimension(); }
  const VariableDomain& domain(int i) const override { return inner_.domain(i); }
  bool has(Capability capability) const override { return inner_.has(capability); }
  double error(std::span<const double> x) override {
    const auto begin = Clock::now();
    return record(inner_.error(x), begin);
  }
  double error_and_gradient(std::span<const double> x, std::span<double> gradient) override {
    const auto begin = Clock::now();
    return record(inner_.error_and_gradient(x, gradient), begin);
  }
  int residual_count() const override { return inner_.residual_count(); }
  void residuals(std::span<const double> x, std::span<double> residuals,
                 std::span<double> jacobian) override {
    const auto begin = Clock::now();
    inner_.residuals(x, residuals, jacobian);
    double half_square = 0;
    for (double r : residuals) half_square += 0.5 * r * r;
    record(half_square, begin);
  }
  double lower_bound(std::span<const double> x, int assigned) override {
    ++run_.bound_evaluations;
    const auto begin = Clock::now();
    const double bound = inner_.lower_bound(x, assigned);
    run_.simulator_seconds += seconds_since(begin);
    return bound;
  }

 private:
  double record(double error, Clock::time_point begin) {
    run_.simulator_seconds += seconds_since(begin);
    run_.errors.push_back(error);
    run_.seconds.push_back(seconds_since(start_));
    run_.simulator_seconds_at.push_back(run_.simulator_seconds);
    return error;
  }

  Problem& inner_;
  BenchRun& run_;
  Clock::time_point start_;
};

/// What a problem lacks that an optimizer needs, as the report says it.
std::string missing_capability(const Optimizer& optimizer, const BenchmarkFacts& facts) {
  for (Capability needed : optimizer.requirements()) {
    if (std::find(facts.capabilities.begin(), facts.capabilities.end(), needed) ==
        facts.capabilities.end())
      return capability_name(needed);
  }
  return {};
}

std::vector<std::string> comma_separated(const std::string& text) {
  std::vector<std::string> parts;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(',', begin);
    std::string part =
        text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    part.erase(0, part.find_first_not_of(' '));
    part.erase(part.find_last_not_of(' ') + 1);
    parts.push_back(part);
    if (end == std::string::npos) return parts;
    begin = end + 1;
  }
}

double or_infinity(double error) {
  return std::isnan(error) ? std::numeric_limits<double>::infinity() : error;
}

}  // namespace

std::vector<Entrant> read_entrants(const std::filesystem::path& file) {
  std::vector<Entrant> entrants;
  std::set<std::string> named_types;
  if (!file.empty()) {
    const Properties root = Properties::load(file);
    for (const Properties& p : root.objects("entrants")) {
      Entrant entrant{p.get<std::string>("label"), p.raw("optimizer")};
      const Properties optimizer = p.object("optimizer");
      const std::string type = optimizer.get<std::string>("type");
      named_types.insert(type);
      if (!OptimizerRegistry::instance().contains(type) &&
          !left_out_of_build("optimizer", type).empty()) {
        spdlog::info("bench: entrant '{}' left out: {}", entrant.label,
                     left_out_of_build("optimizer", type));
        continue;
      }
      build_optimizer(optimizer);  // a malformed one is reported here, with its place
      for (const Entrant& e : entrants)
        if (e.label == entrant.label) p.fail("label", "'" + entrant.label + "' is used twice");
      entrants.push_back(std::move(entrant));
    }
  }
  for (const std::string& name : OptimizerRegistry::instance().names()) {
    if (!named_types.count(name)) entrants.push_back({name, {{"type", name}}});
  }
  return entrants;
}

Budget Budget::parse(const std::string& text) {
  Budget budget;
  for (const std::string& part : comma_separated(text)) {
    const auto fail = [&] {
      throw InputError("--budget: '" + part +
                       "' is not a budget (e.g. 100d: 100 evaluations per variable; 5000: "
                       "evaluations; 30s: seconds per run; or several joined by commas)");
    };
    if (part.empty()) fail();
    const char unit = part.back();
    const std::string number =
        std::isdigit(static_cast<unsigned char>(unit)) ? part : part.substr(0, part.size() - 1);
    double value = 0;
    try {
      size_t used = 0;
      value = std::stod(number, &used);
      if (used != number.size() || !(value > 0) || !std::isfinite(value)) fail();
    } catch (const std::logic_error&) {
      fail();
    }
    if (unit == 'd')
      budget.per_dimension = value;
    else if (unit == 's')
      budget.seconds = value;
    else if (std::isdigit(static_cast<unsigned char>(unit)))
      budget.evaluations = std::llround(value);
    else
      fail();
  }
  return budget;
}

long long Budget::evaluations_for(int dimension) const {
  long long limit = 0;
  if (per_dimension > 0)
    limit = std::max<long long>(1, std::llround(per_dimension * std::max(1, dimension)));
  if (evaluations > 0) limit = limit > 0 ? std::min(limit, evaluations) : evaluations;
  return limit;
}

std::string Budget::describe() const {
  std::vector<std::string> parts;
  if (per_dimension > 0)
    parts.push_back(fmt::format("{:g} evaluations per variable", per_dimension));
  if (evaluations > 0) parts.push_back(fmt::format("{} evaluations", evaluations));
  if (seconds > 0) parts.push_back(fmt::format("{:g} s per run", seconds));
  return join(parts, ", ");
}

double BenchRun::best() const {
  double best = std::numeric_limits<double>::infinity();
  for (double e : errors) best = std::min(best, or_infinity(e));
  return best;
}

std::optional<long long> BenchRun::hitting_time(double target) const {
  for (size_t k = 0; k < errors.size(); ++k)
    if (or_infinity(errors[k]) <= target) return static_cast<long long>(k + 1);
  return std::nullopt;
}

std::optional<double> expected_running_time(const std::vector<const BenchRun*>& runs,
                                            double target) {
  double spent = 0;
  int hits = 0;
  for (const BenchRun* run : runs) {
    const std::optional<long long> hit = run->hitting_time(target);
    spent += static_cast<double>(hit ? *hit : static_cast<long long>(run->errors.size()));
    hits += hit ? 1 : 0;
  }
  if (hits == 0) return std::nullopt;
  return spent / hits;
}

std::string capability_name(Capability capability) {
  switch (capability) {
    case Capability::gradient:
      return "gradient";
    case Capability::residuals:
      return "residuals";
    case Capability::lower_bound:
      return "bound";
    case Capability::discrete_only:
      return "discrete domain";
    case Capability::neighbour_moves:
      return "neighbour moves";
  }
  return "?";
}

namespace {

using BuiltProblems = std::vector<std::unique_ptr<BenchmarkProblem>>;

/// Each problem asked for, built once: its facts and start error, or why
/// this build cannot run it (a module left out: TetGen for fem_book).
BuiltProblems build_problems(const BenchOptions& options, const BenchmarkContext& context,
                             BenchResult& result) {
  const auto& registry = BenchmarkRegistry::instance();
  const std::vector<std::string> all = registry.names();
  const std::vector<std::string> names = options.problems.empty() ? all : options.problems;
  BuiltProblems built;
  for (const std::string& name : names) {
    BenchProblem problem;
    problem.name = name;
    const auto known = std::find(all.begin(), all.end(), name);
    if (known == all.end()) {
      throw InputError("--problems: unknown benchmark problem '" + name + "'" +
                       did_you_mean(name, all) + " (known: " + join(all) + ")");
    }
    problem.function_id = static_cast<int>(known - all.begin()) + 1;
    try {
      built.push_back(registry.create_named(
          name, Properties::wrap(nlohmann::json::object(), "bench problem " + name),
          "benchmark problem", context));
      problem.facts = built.back()->facts();
      const auto instance = built.back()->instantiate();
      std::vector<double> x = instance->start();
      problem.start_error = instance->problem().error(x);
    } catch (const interrupt::Stopped&) {
      throw;
    } catch (const std::exception& e) {
      // A module this build left out: say so, run the rest.
      if (built.size() > result.problems.size()) built.pop_back();
      built.push_back(nullptr);
      problem.unavailable = e.what();
    }
    problem.budget = options.budget.evaluations_for(problem.facts.dimension);
    result.problems.push_back(std::move(problem));
  }
  return built;
}

std::unique_ptr<Optimizer> build_entrant(const Entrant& entrant) {
  return build_optimizer(Properties::wrap(entrant.optimizer, "entrant " + entrant.label));
}

/// Every (entrant, problem) pair with what the problem lacks for it, then
/// one run slot per seed of each pair that can run, in (pair, seed) order.
void plan_runs(const BenchOptions& options, BenchResult& result) {
  for (size_t p = 0; p < result.problems.size(); ++p) {
    if (!result.problems[p].unavailable.empty()) continue;
    for (size_t e = 0; e < result.entrants.size(); ++e) {
      const auto optimizer = build_entrant(result.entrants[e]);
      BenchPair pair{e, p, missing_capability(*optimizer, result.problems[p].facts),
                     optimizer->stochastic()};
      result.pairs.push_back(pair);
    }
  }
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    const BenchPair& pair = result.pairs[k];
    if (!pair.missing.empty()) continue;
    const int runs = pair.stochastic ? options.seeds : 1;
    for (int seed = 1; seed <= runs; ++seed) {
      BenchRun& run = result.runs.emplace_back();
      run.pair = k;
      run.seed = seed;
    }
  }
}

/// One run: the entrant minimises a fresh instance of the problem within
/// the budget, every evaluation recorded into `run`.
void perform_run(const BenchOptions& options, const BuiltProblems& built, const BenchResult& result,
                 BenchRun& run) {
  const BenchPair& pair = result.pairs[run.pair];
  const BenchProblem& facts = result.problems[pair.problem];
  const auto run_start = Clock::now();
  try {
    const auto instance = built[pair.problem]->instantiate();
    auto optimizer = build_entrant(result.entrants[pair.entrant]);
    if (pair.stochastic) optimizer->set_seed(static_cast<std::uint64_t>(run.seed));
    if (facts.budget > 0) optimizer->plan_evaluations(facts.budget);
    RecordingProblem recording(instance->problem(), run);
    const long long budget = facts.budget;
    const double seconds = options.budget.seconds;
    const IterationCallback stop = [budget, seconds](const IterationRecord& row) {
      if (budget > 0 && row.evaluations >= budget) return CallbackResult::terminate;
      if (seconds > 0 && row.seconds >= seconds) return CallbackResult::terminate;
      return CallbackResult::proceed;
    };
    std::vector<double> x = instance->start();
    run.summary = optimizer->minimize(recording, x, stop);
    const Summary& summary = run.summary;
    // minimize() evaluates the point it returns once more, uncounted.
    if (!run.errors.empty()) {
      run.errors.pop_back();
      run.seconds.pop_back();
      run.simulator_seconds_at.pop_back();
    }
    run.termination = summary.usable() ? to_string(summary.termination)
                                       : to_string(summary.termination) + ": " + summary.message;
    run.best_x = x;
  } catch (const interrupt::Stopped&) {
    throw;  // Ctrl-C: no report of runs cut short
  } catch (const std::exception& e) {
    run.termination = std::string("error: ") + e.what();
  }
  run.wall_seconds = seconds_since(run_start);
}

/// Every run, in parallel (each writes only its own slot), with progress.
void perform_runs(const BenchOptions& options, const BuiltProblems& built, BenchResult& result) {
  std::mutex progress_mutex;
  BenchProgress progress{0, result.runs.size(), 0, 0};
  std::vector<int> runs_left(result.pairs.size(), 0);
  for (const BenchRun& run : result.runs) {
    if (runs_left[run.pair]++ == 0) ++progress.pairs;
  }
  const int threads =
      options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  result.threads = threads;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, result.runs.size(), 1),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t r = range.begin(); r != range.end(); ++r) {
                          BenchRun& run = result.runs[r];
                          perform_run(options, built, result, run);
                          const std::lock_guard lock(progress_mutex);
                          ++progress.runs_done;
                          if (--runs_left[run.pair] == 0) ++progress.pairs_done;
                          if (options.progress) options.progress(progress);
                        }
                      });
  });
}

/// Targets: from the start to the optimum (or, where it is unknown, the
/// best any run found), 10^-1 … 10^-8 of the way.
void set_targets(BenchResult& result) {
  for (size_t p = 0; p < result.problems.size(); ++p) {
    BenchProblem& problem = result.problems[p];
    if (!problem.unavailable.empty()) continue;
    double optimum = std::numeric_limits<double>::infinity();
    if (problem.facts.optimum) {
      optimum = *problem.facts.optimum;
    } else {
      for (const BenchRun& run : result.runs)
        if (result.pairs[run.pair].problem == p) optimum = std::min(optimum, run.best());
      problem.facts.optimum = optimum;
    }
    for (int k = 1; k <= 8; ++k)
      problem.targets.push_back(optimum + (problem.start_error - optimum) * std::pow(10.0, -k));
  }
}

}  // namespace

long long estimated_bench_report_bytes(const BenchOptions& options) {
  const auto problems = static_cast<long long>(
      options.problems.empty() ? BenchmarkRegistry::instance().names().size() : options.problems.size());
  const long long runs = problems * static_cast<long long>(options.entrants.size()) * std::max(options.seeds, 1);
  // Measured on `bench --quick` (5 problems, 57 runs: 1.95 MB, of which the
  // page's script ~0.7 MB, 150 kB of plots a problem, ~5 kB a run in ioh/
  // and report.json, which the page holds again): a little over that.
  return (1LL << 20) + problems * (300LL << 10) + runs * (8LL << 10);
}

BenchResult run_bench(const BenchOptions& options, const BenchmarkContext& context) {
  const auto start = Clock::now();
  BenchResult result;
  result.entrants = options.entrants;
  result.seeds = options.seeds;
  result.budget = options.budget.describe();
  const BuiltProblems built = build_problems(options, context, result);
  plan_runs(options, result);
  perform_runs(options, built, result);
  set_targets(result);
  result.wall_seconds = seconds_since(start);
  return result;
}

}  // namespace spec2fab

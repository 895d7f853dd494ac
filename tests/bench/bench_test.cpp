// The optimizer x problem matrix (framework/bench): the harness's sanity on
// problems whose optimum is known, its ERT against the optimizers' own
// accounts, determinism, and `spec2fab bench --quick` end to end with its
// IOHprofiler logs parsed back.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "bench/harness.h"
#include "build_gates.h"
#include "cli/cli_support.h"
#include "core/error.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kDatasets = SPEC2FAB_DATASETS_DIR;

Entrant entrant(const std::string& label, nlohmann::json optimizer) {
  return {label, std::move(optimizer)};
}

BenchResult bench(std::vector<std::string> problems, std::vector<Entrant> entrants,
                  const std::string& budget, int seeds = 3, int threads = 2) {
  BenchOptions options;
  options.problems = std::move(problems);
  options.entrants = std::move(entrants);
  options.budget = Budget::parse(budget);
  options.seeds = seeds;
  options.threads = threads;
  RunCache cache;
  return run_bench(options, BenchmarkContext{kDatasets, &cache});
}

std::vector<const BenchRun*> runs_of(const BenchResult& result, const std::string& label,
                                     const std::string& problem) {
  std::vector<const BenchRun*> runs;
  for (const BenchRun& run : result.runs) {
    const BenchPair& pair = result.pairs[run.pair];
    if (result.entrants[pair.entrant].label == label &&
        result.problems[pair.problem].name == problem)
      runs.push_back(&run);
  }
  return runs;
}

TEST(BenchBudget, ReadsEvaluationsPerVariableEvaluationsAndSeconds) {
  const Budget b = Budget::parse("100d, 30s");
  EXPECT_EQ(b.evaluations_for(6), 600);
  EXPECT_DOUBLE_EQ(b.seconds, 30);
  EXPECT_EQ(Budget::parse("5000").evaluations_for(6), 5000);
  EXPECT_EQ(Budget::parse("100d,250").evaluations_for(6), 250);  // whichever comes first
  EXPECT_EQ(Budget::parse("30s").evaluations_for(6), 0);
  for (const char* bad : {"", "abc", "10x", "-5d", "0", "1e400"})
    EXPECT_THROW(Budget::parse(bad), InputError) << bad;
}

TEST(BenchSanity, ExhaustiveAndBranchAndBoundReachTheKnownOptimum) {
  // Budgets larger than the search spaces: both methods must finish, and
  // the hidden reference's own error (0) is the optimum they must find.
  const BenchResult result = bench({"albedo_column", "subsurface_stack"},
                                   {entrant("exhaustive", {{"type", "exhaustive"}}),
                                    entrant("branch_and_bound", {{"type", "branch_and_bound"}})},
                                   "100000");
  int runs = 0;
  for (const BenchRun& run : result.runs) {
    const BenchPair& pair = result.pairs[run.pair];
    const BenchProblem& problem = result.problems[pair.problem];
    SCOPED_TRACE(result.entrants[pair.entrant].label + " on " + problem.name);
    EXPECT_EQ(run.summary.termination, Termination::converged) << run.termination;
    EXPECT_EQ(run.best(), 0.0);
    EXPECT_EQ(run.summary.final_error, 0.0);
    ASSERT_TRUE(run.hitting_time(problem.targets.back()));
    if (result.entrants[pair.entrant].label == "exhaustive") {
      EXPECT_EQ(static_cast<double>(run.errors.size()),
                problem.facts.assignments + 1);  // + the start
    }
    ++runs;
  }
  EXPECT_EQ(runs, 3);  // albedo_column has no bound: branch and bound does not run there
  const auto& pairs = result.pairs;
  const auto no_bound = std::find_if(pairs.begin(), pairs.end(),
                                     [&](const BenchPair& p) { return !p.missing.empty(); });
  ASSERT_NE(no_bound, pairs.end());
  EXPECT_EQ(no_bound->missing, "bound");
  EXPECT_EQ(result.problems[no_bound->problem].name, "albedo_column");
  // Branch and bound proves the optimum on fewer leaves than exhaustive search evaluates.
  EXPECT_LT(runs_of(result, "branch_and_bound", "subsurface_stack")[0]->errors.size(),
            runs_of(result, "exhaustive", "subsurface_stack")[0]->errors.size() / 10);
}

// A problem with a goal of its own and a limited term (Make It Stand on the
// crane): its optimum is no hidden assignment but the least carving that
// stands, found by trying all 4,096 as the bench starts. Solid, the crane
// falls (the start pays the penalty); exhaustive search reaches the optimum.
TEST(BenchSanity, TheStandProblemsOptimumIsTheLeastCarvingThatStands) {
  const BenchResult result = bench({"stand_crane"},
                                   {entrant("exhaustive", {{"type", "exhaustive"}}),
                                    entrant("branch_and_bound", {{"type", "branch_and_bound"}})},
                                   "5000", 1);
  ASSERT_EQ(result.problems.size(), 1u);
  const BenchProblem& problem = result.problems.front();
  EXPECT_EQ(problem.facts.assignments, 4096);
  ASSERT_TRUE(problem.facts.optimum);
  EXPECT_GT(*problem.facts.optimum, 0) << "standing needs some carving";
  EXPECT_LT(*problem.facts.optimum, 28.5696) << "grams, no penalty: it stands";
  ASSERT_EQ(result.runs.size(), 2u) << "branch and bound runs: the problem has the mass bound";
  for (const BenchRun& run : result.runs) {
    EXPECT_GT(run.summary.initial_error, 1000) << "solid, it falls: the limited term's penalty";
    EXPECT_DOUBLE_EQ(run.best(), *problem.facts.optimum);
    EXPECT_EQ(run.summary.termination, Termination::converged) << run.termination;
  }
  // The mass bound prunes: the optimum proven on a fraction of the carvings.
  EXPECT_LT(runs_of(result, "branch_and_bound", "stand_crane")[0]->errors.size(),
            runs_of(result, "exhaustive", "stand_crane")[0]->errors.size() / 4);
}

TEST(BenchSanity, ErtEqualsTheOneTheOptimizersSummariesGive) {
  // Annealing makes one evaluation per iteration, so its trace says, from
  // its own count, when its best error first reached a target.
  const BenchResult result =
      bench({"albedo_column"}, {entrant("annealing", {{"type", "annealing"}})}, "40", 8);
  const auto runs = runs_of(result, "annealing", "albedo_column");
  ASSERT_EQ(runs.size(), 8u);
  const BenchProblem& problem = result.problems.front();
  int compared = 0;
  for (double target : problem.targets) {
    double spent = 0;
    int hits = 0;
    for (const BenchRun* run : runs) {
      EXPECT_EQ(static_cast<long long>(run->errors.size()), run->summary.evaluations);
      EXPECT_EQ(run->summary.evaluations, 40);
      // The Summary's best error at each row, against its evaluation count.
      long long hit = 0;
      if (run->summary.initial_error <= target) hit = 1;
      for (const IterationRecord& row : run->summary.trace)
        if (hit == 0 && row.best_error <= target) hit = row.evaluations;
      spent += static_cast<double>(hit > 0 ? hit : run->summary.evaluations);
      hits += hit > 0 ? 1 : 0;
    }
    const auto ert = expected_running_time(runs, target);
    if (hits == 0) {
      EXPECT_FALSE(ert);
      continue;
    }
    ASSERT_TRUE(ert);
    EXPECT_DOUBLE_EQ(*ert, spent / hits);
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

std::map<std::string, std::string> files_under(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = fs::relative(entry.path(), folder).string();
    if (name.rfind("timing/", 0) == 0) continue;  // wall times
    std::ifstream in(entry.path(), std::ios::binary);
    std::string bytes(std::istreambuf_iterator<char>(in), {});
    // report.html's copy of the wall time aside.
    files[name] = name == "report.html" ? spec2fab_cli_test::without_timing_block(std::move(bytes)) : std::move(bytes);
  }
  return files;
}

TEST(BenchSanity, TheSameSeedsGiveTheSameLogsForAnyThreadCount) {
  const std::vector<Entrant> entrants{entrant("annealing", {{"type", "annealing"}}),
                                      entrant("spsa", {{"type", "spsa"}})};
  const fs::path root = fs::temp_directory_path() / ("spec2fab_bench_" + std::to_string(getpid()));
  fs::remove_all(root);
  // fem_book too: two FEM runs at once once corrupted each other's
  // factorisations (Debian's serial OpenBLAS is not thread-safe; see
  // fem/cholmod_factor.cpp).
  std::vector<std::string> problems{"facet_aiming", "subsurface_stack"};
  if (SPEC2FAB_WITH_TETGEN) problems.push_back("fem_book");
  const BenchResult one = bench(problems, entrants, "12d", 3, 1);
  const BenchResult two = bench(problems, entrants, "12d", 3, 2);
  write_bench_report(one, root / "one");
  write_bench_report(two, root / "two");
  const auto a = files_under(root / "one"), b = files_under(root / "two");
  EXPECT_GT(a.size(), 10u);
  EXPECT_EQ(a, b);
  // Different seeds do differ (the streams are not all the same).
  const auto runs = runs_of(one, "annealing", "facet_aiming");
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_NE(runs[0]->errors, runs[1]->errors);
  fs::remove_all(root);
}

TEST(BenchEntrants, EveryRegisteredOptimizerJoinsTheShippedList) {
  const std::vector<Entrant> entrants = read_entrants(kDatasets / "bench/entrants.json");
  for (const std::string& name : OptimizerRegistry::instance().names()) {
    EXPECT_TRUE(std::any_of(entrants.begin(), entrants.end(), [&](const Entrant& e) {
      return e.optimizer.value("type", "") == name;
    })) << name;
  }
}

// A problem registered here, in the test program only, as a user's would be
// in their own file: the harness must run it without an edit, and, its
// optimum unknown, take the best error any run found as the optimum.
class ShiftedSphere final : public BenchmarkProblem {
 public:
  ShiftedSphere(const Properties& /*properties*/, const BenchmarkContext& /*context*/) {}
  static TypeDoc doc() { return {"Sum of (x_i - 0.3)^2 over 3 variables in [-1, 1] (a test problem).", {}, ""}; }
  BenchmarkFacts facts() const override {
    BenchmarkFacts facts;
    facts.dimension = 3;
    facts.simulator = "none";
    return facts;  // optimum left unknown
  }
  std::unique_ptr<BenchmarkInstance> instantiate() const override {
    struct Instance final : BenchmarkInstance {
      FunctionProblem problem_{std::vector<VariableDomain>(3, VariableDomain::continuous(-1, 1)),
                               [](std::span<const double> x) {
                                 double sum = 0;
                                 for (double v : x) sum += (v - 0.3) * (v - 0.3);
                                 return sum;
                               }};
      Problem& problem() override { return problem_; }
      std::vector<double> start() const override { return {-1, -1, -1}; }
    };
    return std::make_unique<Instance>();
  }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::ShiftedSphere, "test_shifted_sphere")

namespace spec2fab {
namespace {

TEST(BenchExtension, AProblemRegisteredElsewhereRunsAndItsOptimumIsTheBestFound) {
  const BenchResult result = bench({"test_shifted_sphere"}, {entrant("annealing", {{"type", "annealing"}})}, "50d", 4);
  ASSERT_EQ(result.problems.size(), 1u);
  const BenchProblem& problem = result.problems.front();
  EXPECT_TRUE(problem.unavailable.empty()) << problem.unavailable;
  EXPECT_DOUBLE_EQ(problem.start_error, 3 * 1.3 * 1.3);
  double best = problem.start_error;
  for (const BenchRun& run : result.runs) best = std::min(best, run.best());
  ASSERT_TRUE(problem.facts.optimum);
  EXPECT_EQ(*problem.facts.optimum, best);
  EXPECT_GT(best, 0.0);  // annealing does not hit 0 exactly on a continuous problem
  // The best run reaches every target of the ladder, its own error being the last.
  EXPECT_EQ(problem.targets.back(), best + (problem.start_error - best) * 1e-8);
  EXPECT_TRUE(std::any_of(result.runs.begin(), result.runs.end(),
                          [&](const BenchRun& run) { return run.hitting_time(problem.targets.back()).has_value(); }));
}

// ---------------------------------------------------------------- the command

using spec2fab_cli_test::run_spec2fab;

/// One .dat file's runs: rows of (evaluation, raw_y) per header-delimited block.
std::vector<std::vector<std::pair<long long, double>>> read_dat(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::pair<long long, double>>> blocks;
  std::string line;
  while (std::getline(in, line)) {
    if (line == "evaluations raw_y") {
      blocks.emplace_back();
      continue;
    }
    std::istringstream row(line);
    long long evaluation = 0;
    double y = 0;
    EXPECT_TRUE(row >> evaluation >> y) << file << ": " << line;
    EXPECT_FALSE(blocks.empty()) << file << ": a row before the first header";
    if (!blocks.empty()) blocks.back().emplace_back(evaluation, y);
  }
  return blocks;
}

TEST(BenchCli, QuickMatrixWritesLogsThatParseAndAddUp) {
  const fs::path out =
      fs::temp_directory_path() / ("spec2fab_bench_quick_" + std::to_string(getpid()));
  fs::remove_all(out);
  const auto result = run_spec2fab("bench --quick --out " + out.string());
  ASSERT_EQ(result.code, 0) << result.out;
  EXPECT_THAT(result.out, HasSubstr("wrote " + out.string()));
  nlohmann::json report;
  std::ifstream(out / "report.json") >> report;
  const int seeds = report["seeds"].get<int>();
  EXPECT_EQ(seeds, 3);
  const size_t entrant_count = read_entrants(kDatasets / "bench/entrants.json").size();

  int problems_run = 0;
  for (const nlohmann::json& problem : report["problems"]) {
    const std::string name = problem["name"].get<std::string>();
    SCOPED_TRACE(name);
    if (problem.contains("unavailable")) {
      // Only a module this build left out may keep a problem from running.
      EXPECT_FALSE(SPEC2FAB_WITH_TETGEN) << problem["unavailable"];
      continue;
    }
    ++problems_run;
    // Every entrant either ran on the problem or is listed with what it needs.
    EXPECT_EQ(problem["entrants"].size() + problem["incompatible"].size(), entrant_count);
    for (const nlohmann::json& stats : problem["entrants"]) {
      const std::string label = stats["entrant"].get<std::string>();
      SCOPED_TRACE(label);
      const auto& runs = stats["run_list"];
      EXPECT_EQ(runs.size(), stats["stochastic"].get<bool>() ? static_cast<size_t>(seeds) : 1u);
      const long long budget = problem["budget"].get<long long>();
      // The IOHprofiler index and data file of this (entrant, problem).
      const std::string stem = "f" + std::to_string(problem["function_id"].get<int>()) + "_" + name;
      const fs::path folder = out / "ioh" / label;
      nlohmann::json index;
      std::ifstream(folder / ("IOHprofiler_" + stem + ".json")) >> index;
      ASSERT_TRUE(index.is_object()) << folder;
      EXPECT_EQ(index["version"], "0.3.23");
      EXPECT_EQ(index["maximization"], false);
      EXPECT_EQ(index["attributes"], nlohmann::json({"evaluations", "raw_y"}));
      const nlohmann::json& scenario = index["scenarios"][0];
      EXPECT_EQ(scenario["dimension"], problem["dimension"]);
      const auto blocks = read_dat(folder / scenario["path"].get<std::string>());
      ASSERT_EQ(blocks.size(), runs.size());
      ASSERT_EQ(scenario["runs"].size(), runs.size());
      for (size_t r = 0; r < runs.size(); ++r) {
        const long long evaluations = runs[r]["evaluations"].get<long long>();
        // The log, the harness's count and the optimizer's Summary agree.
        EXPECT_EQ(evaluations, runs[r]["summary_evaluations"].get<long long>());
        EXPECT_EQ(scenario["runs"][r]["evals"].get<long long>(), evaluations);
        EXPECT_LE(evaluations,
                  budget + 2);  // the last iteration may end just past it (SPSA's pair)
        const auto& rows = blocks[r];
        ASSERT_FALSE(rows.empty());
        EXPECT_EQ(rows.front().first, 1);
        EXPECT_EQ(rows.back().first, evaluations);
        for (size_t k = 1; k < rows.size(); ++k) {
          EXPECT_GT(rows[k].first, rows[k - 1].first);
          // Strict improvements, but for the last evaluation's row.
          if (k + 1 < rows.size()) {
            EXPECT_LT(rows[k].second, rows[k - 1].second);
          }
        }
        double best = rows.front().second;
        for (const auto& row : rows) best = std::min(best, row.second);
        EXPECT_DOUBLE_EQ(best, runs[r]["best_error"].get<double>());
        EXPECT_DOUBLE_EQ(scenario["runs"][r]["best"]["y"].get<double>(), best);
      }
    }
    EXPECT_TRUE(fs::exists(out / "plots" / ("convergence_" + name + ".png")));
    EXPECT_TRUE(fs::exists(out / "plots" / ("ecdf_" + name + ".png")));
    // report.html's copy of the curves: one series per entrant that ran, the
    // convergence with its quartile band where there are several seeds.
    const nlohmann::json& charts = problem["charts"];
    EXPECT_EQ(charts["convergence"]["series"].size(), problem["entrants"].size());
    EXPECT_EQ(charts["ecdf"]["series"].size(), problem["entrants"].size());
    for (size_t e = 0; e < problem["entrants"].size(); ++e) {
      const nlohmann::json& series = charts["convergence"]["series"][e];
      EXPECT_EQ(series.contains("band"), problem["entrants"][e]["runs"].get<int>() > 1);
      EXPECT_TRUE(charts["ecdf"]["series"][e]["steps"].get<bool>());
    }
  }
  // report.html: the page holds report.json as it is.
  const nlohmann::json data =
      spec2fab_cli_test::page_block(spec2fab_cli_test::read(out / "report.html"), "spec2fab-data");
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["report"], report);
  EXPECT_GE(problems_run, 4);
  EXPECT_TRUE(fs::exists(out / "plots" / "fight.png"));
  std::ifstream md(out / "report.md");
  const std::string text(std::istreambuf_iterator<char>(md), {});
  EXPECT_THAT(text, HasSubstr("## Fight matrix"));
  EXPECT_THAT(text, HasSubstr("needs discrete domain"));  // exhaustive on the continuous problems
  if (SPEC2FAB_WITH_NLOPT) {
    EXPECT_THAT(text, HasSubstr("needs gradient"));  // L-BFGS on the discrete ones
  }
  fs::remove_all(out);
}

TEST(BenchCli, UnknownProblemIsOneLineAndExitCodeTwo) {
  const auto result = run_spec2fab("bench --problems fem_boook --out /tmp/spec2fab_never_written");
  EXPECT_EQ(result.code, 2);
  EXPECT_THAT(result.out, HasSubstr("unknown benchmark problem 'fem_boook'"));
  EXPECT_THAT(result.out, HasSubstr("did you mean 'fem_book'"));
  EXPECT_FALSE(fs::exists("/tmp/spec2fab_never_written"));
}

}  // namespace
}  // namespace spec2fab

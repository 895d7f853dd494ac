// What `spec2fab bench` writes: IOHprofiler logs, report.md/json, plots and
// timing. Everything but timing/ depends on evaluations alone, so it is the
// same for any thread count.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include "bench/harness.h"
#include "bench/plot.h"
#include "bench/report_impl.h"
#include "report/html_report.h"
#include "core/file_write.h"
#include "core/strings.h"
#include "tuning/problem.h"

namespace spec2fab {

namespace {

namespace fs = std::filesystem;
using namespace bench_report;

/// A's win rate over B on one problem: over every pair of their runs, 1 for
/// a lower final error, ½ for a tie (within 1e-12 of the start's error).
double win_rate(const std::vector<const BenchRun*>& a, const std::vector<const BenchRun*>& b,
                double scale) {
  double wins = 0;
  for (const BenchRun* x : a) {
    for (const BenchRun* y : b) {
      const double ex = x->best(), ey = y->best();
      if (std::abs(ex - ey) <= 1e-12 * scale || ex == ey)
        wins += 0.5;
      else if (ex < ey)
        wins += 1;
    }
  }
  return wins / static_cast<double>(a.size() * b.size());
}

struct Fights {
  std::vector<std::vector<double>> rate;  ///< [a][b], NaN where they share no problem
  std::vector<double> mean;               ///< a's mean rate over the entrants it met
  std::vector<size_t> order;              ///< entrants, best mean first
};

Fights fight(const BenchResult& result, const std::vector<std::vector<const BenchRun*>>& by_pair) {
  const size_t n = result.entrants.size();
  std::vector<std::vector<double>> sum(n, std::vector<double>(n, 0.0));
  std::vector<std::vector<int>> count(n, std::vector<int>(n, 0));
  std::map<std::pair<size_t, size_t>, size_t> pair_of;  // (entrant, problem) -> pair with runs
  for (size_t k = 0; k < result.pairs.size(); ++k)
    if (!by_pair[k].empty()) pair_of[{result.pairs[k].entrant, result.pairs[k].problem}] = k;
  for (size_t p = 0; p < result.problems.size(); ++p) {
    const double scale = std::max(std::abs(result.problems[p].start_error), 1e-300);
    for (size_t a = 0; a < n; ++a) {
      for (size_t b = 0; b < n; ++b) {
        if (a == b) continue;
        const auto pa = pair_of.find({a, p}), pb = pair_of.find({b, p});
        if (pa == pair_of.end() || pb == pair_of.end()) continue;
        sum[a][b] += win_rate(by_pair[pa->second], by_pair[pb->second], scale);
        ++count[a][b];
      }
    }
  }
  Fights f;
  f.rate.assign(n, std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  f.mean.assign(n, std::numeric_limits<double>::quiet_NaN());
  for (size_t a = 0; a < n; ++a) {
    double total = 0;
    int met = 0;
    for (size_t b = 0; b < n; ++b) {
      if (count[a][b] == 0) continue;
      f.rate[a][b] = sum[a][b] / count[a][b];
      total += f.rate[a][b];
      ++met;
    }
    if (met > 0) f.mean[a] = total / met;
  }
  for (size_t a = 0; a < n; ++a)
    if (!std::isnan(f.mean[a])) f.order.push_back(a);
  std::stable_sort(f.order.begin(), f.order.end(),
                   [&](size_t a, size_t b) { return f.mean[a] > f.mean[b]; });
  return f;
}

// ---------------------------------------------------------------- report

std::string ert_text(const std::vector<const BenchRun*>& runs, double target) {
  const auto ert = expected_running_time(runs, target);
  return ert ? fmt::format("{:.0f}", *ert) : "∞";
}

std::string capabilities_text(const BenchmarkFacts& facts) {
  std::vector<std::string> names;
  for (Capability c : facts.capabilities) names.push_back(capability_name(c));
  if (std::find(facts.capabilities.begin(), facts.capabilities.end(), Capability::discrete_only) ==
      facts.capabilities.end())
    names.push_back("continuous");
  return join(names, ", ");
}

nlohmann::json pair_statistics(const BenchProblem& problem,
                               const std::vector<const BenchRun*>& runs) {
  std::vector<double> finals, used, bounds;
  int successes = 0;
  for (const BenchRun* run : runs) {
    finals.push_back(run->best());
    used.push_back(static_cast<double>(run->errors.size()));
    bounds.push_back(static_cast<double>(run->bound_evaluations));
    if (run->hitting_time(problem.targets.back())) ++successes;
  }
  nlohmann::json ert = nlohmann::json::array();
  for (double target : problem.targets) {
    const auto e = expected_running_time(runs, target);
    ert.push_back(e ? nlohmann::json(*e) : nlohmann::json(nullptr));
  }
  return {{"runs", runs.size()},
          {"final_error",
           {{"q1", quantile(finals, 0.25)},
            {"median", quantile(finals, 0.5)},
            {"q3", quantile(finals, 0.75)}}},
          {"success_rate",
           runs.empty() ? 0.0 : static_cast<double>(successes) / static_cast<double>(runs.size())},
          {"ert", ert},
          {"median_evaluations", quantile(used, 0.5)},
          {"median_bound_calls", quantile(bounds, 0.5)}};
}

/// "At a glance": each entrant's median final relative precision per problem.
void write_glance(std::ostringstream& md, const BenchResult& result, const RunsByPair& by_pair,
                  const Fights& fights) {
  // At a glance: median final relative precision per cell.
  md << "## At a glance\n\nMedian final error as a share of the start's distance to the optimum "
        "(0: optimum "
        "found); entrants by mean win rate (fight matrix below).\n\n| entrant |";
  std::vector<size_t> shown;
  for (size_t p = 0; p < result.problems.size(); ++p) {
    md << " " << result.problems[p].name << " |";
    shown.push_back(p);
  }
  md << "\n|---|";
  for (size_t p = 0; p < shown.size(); ++p) md << "---|";
  md << "\n";
  std::vector<size_t> order = fights.order;
  for (size_t e = 0; e < result.entrants.size(); ++e)
    if (std::find(order.begin(), order.end(), e) == order.end()) order.push_back(e);
  for (size_t e : order) {
    md << "| " << result.entrants[e].label << " |";
    for (size_t p : shown) {
      const BenchProblem& problem = result.problems[p];
      std::string cell = "unavailable";
      for (size_t k = 0; k < result.pairs.size(); ++k) {
        if (result.pairs[k].entrant != e || result.pairs[k].problem != p) continue;
        if (!result.pairs[k].missing.empty()) {
          cell = "needs " + result.pairs[k].missing;
        } else {
          std::vector<double> finals;
          for (const BenchRun* run : by_pair[k])
            finals.push_back(relative_precision(problem, run->best()));
          cell = number(quantile(finals, 0.5));
        }
      }
      md << " " << cell << " |";
    }
    md << "\n";
  }
}

/// Each run of a pair: seed, evaluations, best error, termination and when it
/// hit each target.
nlohmann::json run_records(const BenchProblem& problem, const std::vector<const BenchRun*>& runs) {
  nlohmann::json run_list = nlohmann::json::array();
  for (const BenchRun* run : runs) {
    nlohmann::json hits = nlohmann::json::array();
    for (double target : problem.targets) {
      const auto hit = run->hitting_time(target);
      hits.push_back(hit ? nlohmann::json(*hit) : nlohmann::json(nullptr));
    }
    run_list.push_back({{"seed", run->seed},
                        {"evaluations", run->errors.size()},
                        {"summary_evaluations", run->summary.evaluations},
                        {"bound_evaluations", run->bound_evaluations},
                        {"best_error", run->best()},
                        {"termination", run->termination},
                        {"hitting_times", hits}});
  }
  return run_list;
}

/// A problem's section: what it is (simulator, metric, goal, variables,
/// capabilities), the head of its table; `entry` gets the same figures.
bool write_problem_head(std::ostringstream& md, const BenchProblem& problem,
                        nlohmann::json& entry) {
  const BenchmarkFacts& f = problem.facts;
  md << "- simulator: " << f.simulator << "\n- metric: " << f.metric << "\n- goal: " << f.goal
     << "\n- variables: " << f.variables << " (dimension " << f.dimension;
  if (f.assignments > 0) md << fmt::format(", {:.0f} assignments", f.assignments);
  md << ")\n- offers: " << capabilities_text(f) << "\n"
     << fmt::format("- start error {}, optimum {}, budget {} evaluations\n\n",
                    number(problem.start_error), number(f.optimum.value_or(0)),
                    problem.budget > 0 ? std::to_string(problem.budget) : "unlimited");
  // Bound calls are not evaluations, but they cost time: shown where a problem has a bound.
  const bool bounded = std::find(f.capabilities.begin(), f.capabilities.end(),
                                 Capability::lower_bound) != f.capabilities.end();
  md << "| entrant | runs | final error: median [q1, q3] | success | ERT 1e-2 | ERT 1e-4 | ERT "
        "1e-8 | evaluations "
        "(median) |"
     << (bounded ? " bound calls (median) |" : "") << "\n|---|---|---|---|---|---|---|---|"
     << (bounded ? "---|" : "") << "\n";
  entry.update({{"dimension", f.dimension},
                {"assignments", f.assignments},
                {"start_error", problem.start_error},
                {"optimum", f.optimum.value_or(0)},
                {"targets", problem.targets},
                {"budget", problem.budget}});
  return bounded;
}

/// A problem's table rows, one per entrant that ran it, and the entrants that
/// could not (the capability they need); its plots.
void write_problem_rows(std::ostringstream& md, const BenchResult& result, size_t p,
                        const RunsByPair& by_pair, bool bounded, nlohmann::json& entry,
                        const fs::path& folder) {
  const BenchProblem& problem = result.problems[p];
  nlohmann::json entrants = nlohmann::json::array(), left_out = nlohmann::json::array();
  std::vector<std::string> incompatible;
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    const BenchPair& pair = result.pairs[k];
    if (pair.problem != p) continue;
    const std::string& label = result.entrants[pair.entrant].label;
    if (!pair.missing.empty()) {
      incompatible.push_back(label + " (needs " + pair.missing + ")");
      left_out.push_back({{"entrant", label}, {"missing", pair.missing}});
      continue;
    }
    const auto& runs = by_pair[k];
    nlohmann::json stats = pair_statistics(problem, runs);
    md << fmt::format(
        "| {} | {} | {} [{}, {}] | {}/{} | {} | {} | {} | {:.0f} |", label, runs.size(),
        number(stats["final_error"]["median"]), number(stats["final_error"]["q1"]),
        number(stats["final_error"]["q3"]),
        static_cast<int>(std::lround(stats["success_rate"].get<double>() * runs.size())),
        runs.size(), ert_text(runs, problem.targets[1]), ert_text(runs, problem.targets[3]),
        ert_text(runs, problem.targets.back()), stats["median_evaluations"].get<double>());
    if (bounded) md << fmt::format(" {:.0f} |", stats["median_bound_calls"].get<double>());
    md << "\n";
    stats["entrant"] = label;
    stats["stochastic"] = pair.stochastic;
    stats["run_list"] = run_records(problem, runs);
    entrants.push_back(stats);
  }
  if (!incompatible.empty())
    md << "\nNot run (the problem lacks what they need): " << join(incompatible) << ".\n";
  md << fmt::format("\n![convergence](plots/convergence_{0}.png) ![ECDF](plots/ecdf_{0}.png)\n",
                    file_name(problem.name));
  entry["entrants"] = entrants;
  entry["incompatible"] = left_out;
  entry["charts"] = {
      {"convergence", write_convergence(result, p, by_pair,
                                        folder / "plots" / ("convergence_" + file_name(problem.name) + ".png"))},
      {"ecdf", write_ecdf(result, p, by_pair, folder / "plots" / ("ecdf_" + file_name(problem.name) + ".png"))}};
}

/// The fight matrix: each entrant's win rate against each other, and its plot.
void write_fights(std::ostringstream& md, nlohmann::json& report, const BenchResult& result,
                  const Fights& fights, const fs::path& folder) {
  md << "\n## Fight matrix\n\nRow's win rate against column over the problems both run (a run pair "
        "won: lower "
        "final error; a tie counts half), averaged over those problems.\n\n| | ";
  std::vector<std::string> labels;
  for (size_t e : fights.order) labels.push_back(result.entrants[e].label);
  md << join(labels, " | ") << " | mean |\n|---|";
  for (size_t k = 0; k <= labels.size(); ++k) md << "---|";
  md << "\n";
  std::vector<std::vector<double>> table;
  for (size_t a : fights.order) {
    md << "| " << result.entrants[a].label << " |";
    std::vector<double> row;
    for (size_t b : fights.order) {
      row.push_back(fights.rate[a][b]);
      md << " "
         << (std::isnan(fights.rate[a][b]) ? std::string("–")
                                           : fmt::format("{:.0f}%", 100 * fights.rate[a][b]))
         << " |";
    }
    table.push_back(row);
    md << fmt::format(" {:.0f}% |\n", 100 * fights.mean[a]);
  }
  md << "\n![fight matrix](plots/fight.png)\n";
  if (!fights.order.empty())
    plot::write_heat_map("win rate of row against column", labels, table,
                         folder / "plots" / "fight.png");
  report["fights"] = {{"entrants", labels}, {"win_rate", table}};
}

/// timing/: wall and simulator seconds, which vary with the machine and the load.
void write_timing(const BenchResult& result, const fs::path& folder) {
  nlohmann::json timing = {{"threads", result.threads},
                           {"wall_seconds", result.wall_seconds},
                           {"runs", nlohmann::json::array()}};
  std::string csv = "problem,entrant,seed,evaluation,best_error,wall_seconds,simulator_seconds\n";
  for (const BenchRun& run : result.runs) {
    const BenchPair& pair = result.pairs[run.pair];
    const std::string& problem = result.problems[pair.problem].name;
    const std::string& label = result.entrants[pair.entrant].label;
    timing["runs"].push_back({{"problem", problem},
                              {"entrant", label},
                              {"seed", run.seed},
                              {"evaluations", run.errors.size()},
                              {"wall_seconds", run.wall_seconds},
                              {"simulator_seconds", run.simulator_seconds}});
    double best = std::numeric_limits<double>::infinity();
    for (size_t e = 0; e < run.errors.size(); ++e) {
      if (!(run.errors[e] < best) && e + 1 != run.errors.size()) continue;
      best = std::min(best, run.errors[e]);
      csv += fmt::format("{},{},{},{},{:.17g},{:.6f},{:.6f}\n", problem, label, run.seed, e + 1,
                         best, run.seconds[e], run.simulator_seconds_at[e]);
    }
  }
  write_report_file(folder / "timing" / "timing.json", timing.dump(1) + "\n");
  write_report_file(folder / "timing" / "runs.csv", csv);
}

}  // namespace

void write_bench_report(const BenchResult& result, const fs::path& folder) {
  const auto by_pair = runs_by_pair(result);
  write_ioh(result, by_pair, folder / "ioh");
  const Fights fights = fight(result, by_pair);

  std::ostringstream md;
  md << "# Optimizer × problem matrix\n\n"
     << fmt::format(
            "Budget: {} (the start's evaluation included). Stochastic entrants: {} seeds; "
            "deterministic: one "
            "run. Targets: the optimum plus 10^-1 … 10^-8 of the start's distance to it; "
            "*success* "
            "is "
            "reaching the last. ERT: evaluations spent by all runs (to the hit, or all they "
            "made) "
            "per run "
            "that hit. Logs: ioh/ (IOHprofiler format). Wall and simulator times: timing/.\n\n",
            result.budget, result.seeds);

  write_glance(md, result, by_pair, fights);
  nlohmann::json report = {
      {"budget", result.budget}, {"seeds", result.seeds}, {"problems", nlohmann::json::array()}};
  for (size_t p = 0; p < result.problems.size(); ++p) {
    const BenchProblem& problem = result.problems[p];
    md << "\n## " << problem.name << "\n\n";
    nlohmann::json entry = {{"name", problem.name}, {"function_id", problem.function_id}};
    if (!problem.unavailable.empty()) {
      md << "Not run in this build: " << problem.unavailable << "\n";
      entry["unavailable"] = problem.unavailable;
    } else {
      const bool bounded = write_problem_head(md, problem, entry);
      write_problem_rows(md, result, p, by_pair, bounded, entry, folder);
    }
    report["problems"].push_back(entry);
  }
  write_fights(md, report, result, fights, folder);
  write_report_file(folder / "report.md", md.str());
  write_report_file(folder / "report.json", report.dump(1) + "\n");
  write_timing(result, folder);
  write_bench_report_html(folder);
}

}  // namespace spec2fab

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
#include "core/file_write.h"
#include "bench/plot.h"
#include "core/strings.h"
#include "tuning/problem.h"

namespace spec2fab {

namespace {

namespace fs = std::filesystem;

constexpr int kLadder = 8;  // targets 1e-1 .. 1e-8 of the start's distance to the optimum

void write_report_file(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  write_file(file, text);
}

std::string number(double v) {
  if (!std::isfinite(v)) return v > 0 ? "inf" : "nan";
  return fmt::format("{:.3g}", v);
}

/// Linear interpolation between order statistics (R's type 7).
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double h = q * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<size_t>(std::floor(h));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  const double a = values[lo], b = values[hi];
  if (a == b) return a;  // also keeps inf − inf out
  return a + (h - static_cast<double>(lo)) * (b - a);
}

/// A safe name for files.
std::string file_name(std::string text) {
  for (char& c : text)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return text;
}

/// A value IOHanalyzer's readers take whole: none of , " ' : | ; \ in it.
std::string ioh_text(std::string text) {
  for (char& c : text)
    if (std::string_view(",\"':|;\\").find(c) != std::string_view::npos) c = ' ';
  return text;
}

/// The runs of each pair, in seed order.
std::vector<std::vector<const BenchRun*>> runs_by_pair(const BenchResult& result) {
  std::vector<std::vector<const BenchRun*>> out(result.pairs.size());
  for (const BenchRun& run : result.runs) out[run.pair].push_back(&run);
  return out;
}

double relative_precision(const BenchProblem& problem, double error) {
  const double optimum = problem.facts.optimum.value_or(0);
  const double gap = problem.start_error - optimum;
  return gap > 0 ? std::max(0.0, error - optimum) / gap : 0.0;
}

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

// ---------------------------------------------------------------- IOHprofiler

/// IOHprofiler's JSON flavour (IOHexperimenter >= 0.3.3): per entrant a
/// folder, per problem an index file and one .dat with a block per run —
/// a row at the first evaluation, at every strict improvement and at the
/// last evaluation.
void write_ioh(const BenchResult& result, const std::vector<std::vector<const BenchRun*>>& by_pair,
               const fs::path& root) {
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    const BenchPair& pair = result.pairs[k];
    if (by_pair[k].empty()) continue;
    const BenchProblem& problem = result.problems[pair.problem];
    const Entrant& entrant = result.entrants[pair.entrant];
    const std::string stem = fmt::format("f{}_{}", problem.function_id, file_name(problem.name));
    const std::string dat = fmt::format("data_{}/IOHprofiler_f{}_DIM{}.dat", stem,
                                        problem.function_id, problem.facts.dimension);
    std::string rows;
    nlohmann::json runs = nlohmann::json::array();
    for (const BenchRun* run : by_pair[k]) {
      if (run->errors.empty()) continue;  // an instance that failed to build: nothing evaluated
      rows += "evaluations raw_y\n";
      double best = std::numeric_limits<double>::infinity();
      long long best_at = 1;
      for (size_t e = 0; e < run->errors.size(); ++e) {
        const double y =
            std::isfinite(run->errors[e]) ? run->errors[e] : std::numeric_limits<double>::max();
        const bool last = e + 1 == run->errors.size();
        if (y < best || e == 0) {
          best = y;
          best_at = static_cast<long long>(e + 1);
          rows += fmt::format("{} {:.17g}\n", e + 1, y);
        } else if (last) {
          rows += fmt::format("{} {:.17g}\n", e + 1, y);
        }
      }
      runs.push_back({{"instance", run->seed},
                      {"evals", run->errors.size()},
                      {"best", {{"evals", best_at}, {"y", best}, {"x", run->best_x}}}});
    }
    if (runs.empty()) continue;
    const fs::path folder = root / file_name(entrant.label);
    write_report_file(folder / dat, rows);
    std::string info;
    for (const auto& [key, value] : entrant.optimizer.items())
      info += (info.empty() ? "" : " ") + key + "=" +
              (value.is_string() ? value.get<std::string>() : value.dump());
    const nlohmann::json index = {
        {"version", "0.3.23"},
        {"suite", "Spec2Fab"},
        {"function_id", problem.function_id},
        {"function_name", problem.name},
        {"maximization", false},
        {"algorithm", {{"name", entrant.label}, {"info", ioh_text(info)}}},
        {"attributes", {"evaluations", "raw_y"}},
        {"scenarios", {{{"dimension", problem.facts.dimension}, {"path", dat}, {"runs", runs}}}}};
    write_report_file(folder / ("IOHprofiler_" + stem + ".json"), index.dump(1, '\t') + "\n");
  }
}

// ---------------------------------------------------------------- plots

/// Fixed-budget convergence: best-so-far relative precision against
/// evaluations, median over runs with the quartiles as a band.
void write_convergence(const BenchResult& result, size_t p,
                       const std::vector<std::vector<const BenchRun*>>& by_pair,
                       const fs::path& file) {
  const BenchProblem& problem = result.problems[p];
  long long longest = 1;
  for (size_t k = 0; k < result.pairs.size(); ++k)
    if (result.pairs[k].problem == p)
      for (const BenchRun* run : by_pair[k])
        longest = std::max<long long>(longest, static_cast<long long>(run->errors.size()));
  constexpr double kFloor = 1e-10;
  std::vector<long long> grid;
  for (double t = 0; t <= std::log10(static_cast<double>(longest)) + 1e-9; t += 0.05) {
    const auto e = static_cast<long long>(std::llround(std::pow(10.0, t)));
    if (grid.empty() || e != grid.back()) grid.push_back(e);
  }
  if (grid.back() != longest) grid.push_back(longest);
  std::vector<plot::Series> series;
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    if (result.pairs[k].problem != p || by_pair[k].empty()) continue;
    plot::Series one{result.entrants[result.pairs[k].entrant].label, {}, {}, false};
    const bool band = by_pair[k].size() > 1;
    // Best so far per run at each grid point (a run that ended keeps its best).
    std::vector<std::vector<double>> best(by_pair[k].size());
    for (size_t r = 0; r < by_pair[k].size(); ++r) {
      const BenchRun& run = *by_pair[k][r];
      double b = std::numeric_limits<double>::infinity();
      size_t e = 0;
      for (long long g : grid) {
        while (e < run.errors.size() && static_cast<long long>(e) < g)
          b = std::min(b, run.errors[e++]);
        best[r].push_back(std::max(kFloor, relative_precision(problem, b)));
      }
    }
    for (size_t g = 0; g < grid.size(); ++g) {
      std::vector<double> at;
      for (const auto& b : best) at.push_back(b[g]);
      one.points.push_back({static_cast<double>(grid[g]), quantile(at, 0.5)});
      if (band) one.band.push_back({quantile(at, 0.25), quantile(at, 0.75)});
    }
    series.push_back(std::move(one));
  }
  plot::Axes axes{fmt::format("{}: best error so far (median, quartile bands)", problem.name),
                  "evaluations",
                  "(error - optimum) / (start - optimum); 0 drawn at 1e-10",
                  1,
                  static_cast<double>(longest),
                  kFloor,
                  2,
                  true,
                  true};
  plot::write_chart(axes, series, file);
}

/// Runtime ECDF: the share of (run, target) pairs of the ladder reached
/// within x evaluations.
void write_ecdf(const BenchResult& result, size_t p,
                const std::vector<std::vector<const BenchRun*>>& by_pair, const fs::path& file) {
  const BenchProblem& problem = result.problems[p];
  long long longest = 1;
  std::vector<plot::Series> series;
  for (size_t k = 0; k < result.pairs.size(); ++k) {
    if (result.pairs[k].problem != p || by_pair[k].empty()) continue;
    std::vector<long long> hits;
    size_t total = 0;
    for (const BenchRun* run : by_pair[k]) {
      longest = std::max<long long>(longest, static_cast<long long>(run->errors.size()));
      for (double target : problem.targets) {
        ++total;
        if (const auto hit = run->hitting_time(target)) hits.push_back(*hit);
      }
    }
    std::sort(hits.begin(), hits.end());
    plot::Series one{result.entrants[result.pairs[k].entrant].label, {{1.0, 0.0}}, {}, true};
    for (size_t h = 0; h < hits.size(); ++h) {
      if (h + 1 < hits.size() && hits[h + 1] == hits[h]) continue;
      one.points.push_back(
          {static_cast<double>(hits[h]), static_cast<double>(h + 1) / static_cast<double>(total)});
    }
    series.push_back(std::move(one));
  }
  for (plot::Series& one : series)
    one.points.push_back({static_cast<double>(longest), one.points.back()[1]});
  plot::Axes axes{fmt::format("{}: runtime ECDF over {} targets (1e-1 .. 1e-8 of the start's gap)",
                              problem.name, kLadder),
                  "evaluations",
                  "share of (run, target) reached",
                  1,
                  static_cast<double>(longest),
                  0,
                  1,
                  true,
                  false};
  plot::write_chart(axes, series, file);
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
            "run. Targets: the optimum plus 10^-1 … 10^-8 of the start's distance to it; *success* "
            "is "
            "reaching the last. ERT: evaluations spent by all runs (to the hit, or all they made) "
            "per run "
            "that hit. Logs: ioh/ (IOHprofiler format). Wall and simulator times: timing/.\n\n",
            result.budget, result.seeds);

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

  nlohmann::json report = {
      {"budget", result.budget}, {"seeds", result.seeds}, {"problems", nlohmann::json::array()}};
  for (size_t p = 0; p < result.problems.size(); ++p) {
    const BenchProblem& problem = result.problems[p];
    const BenchmarkFacts& f = problem.facts;
    md << "\n## " << problem.name << "\n\n";
    nlohmann::json entry = {{"name", problem.name}, {"function_id", problem.function_id}};
    if (!problem.unavailable.empty()) {
      md << "Not run in this build: " << problem.unavailable << "\n";
      entry["unavailable"] = problem.unavailable;
      report["problems"].push_back(entry);
      continue;
    }
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
      stats["entrant"] = label;
      stats["stochastic"] = pair.stochastic;
      stats["run_list"] = run_list;
      entrants.push_back(stats);
    }
    if (!incompatible.empty())
      md << "\nNot run (the problem lacks what they need): " << join(incompatible) << ".\n";
    md << fmt::format("\n![convergence](plots/convergence_{0}.png) ![ECDF](plots/ecdf_{0}.png)\n",
                      file_name(problem.name));
    entry["entrants"] = entrants;
    entry["incompatible"] = left_out;
    report["problems"].push_back(entry);
    write_convergence(result, p, by_pair,
                      folder / "plots" / ("convergence_" + file_name(problem.name) + ".png"));
    write_ecdf(result, p, by_pair, folder / "plots" / ("ecdf_" + file_name(problem.name) + ".png"));
  }

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
  write_report_file(folder / "report.md", md.str());
  write_report_file(folder / "report.json", report.dump(1) + "\n");

  // Wall and simulator seconds: these vary with the machine and the load.
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

}  // namespace spec2fab

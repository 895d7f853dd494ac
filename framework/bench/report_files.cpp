// The bench report's files besides report.md/json: IOHprofiler logs and
// the plots (convergence with quartile bands, runtime ECDFs).

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench/plot.h"
#include "bench/report_impl.h"
#include "core/file_write.h"
#include "core/strings.h"
#include "tuning/problem.h"

namespace spec2fab::bench_report {

namespace fs = std::filesystem;

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
nlohmann::json write_convergence(const BenchResult& result, size_t p,
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
  return plot::chart_json(axes, series);
}

/// Runtime ECDF: the share of (run, target) pairs of the ladder reached
/// within x evaluations.
nlohmann::json write_ecdf(const BenchResult& result, size_t p,
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
  return plot::chart_json(axes, series);
}

}  // namespace spec2fab::bench_report

#pragma once
// What the bench report's writers share (report.cpp: report.md/json;
// report_files.cpp: the IOHprofiler logs and the plots). Internal to bench/.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/harness.h"

namespace spec2fab::bench_report {

inline constexpr int kLadder = 8;  ///< targets 1e-1 .. 1e-8 of the start's distance to the optimum

/// The runs of each pair, in seed order.
using RunsByPair = std::vector<std::vector<const BenchRun*>>;
RunsByPair runs_by_pair(const BenchResult& result);

void write_report_file(const std::filesystem::path& file, const std::string& text);
/// "1.23e-05", "inf", "nan".
std::string number(double v);
/// Linear interpolation between order statistics (R's type 7).
double quantile(std::vector<double> values, double q);
/// A safe name for files.
std::string file_name(std::string text);
/// A value IOHanalyzer's readers take whole: none of , " ' : | ; \ in it.
std::string ioh_text(std::string text);
/// The error's share of the start's distance to the optimum (0 at it).
double relative_precision(const BenchProblem& problem, double error);

/// ioh/: IOHprofiler's format, which IOHanalyzer reads as it is.
void write_ioh(const BenchResult& result, const RunsByPair& by_pair,
               const std::filesystem::path& root);
/// Problem p's convergence plot (median and quartile band of the best so far);
/// returns the chart as data (plot::chart_json) for report.html.
nlohmann::json write_convergence(const BenchResult& result, size_t p, const RunsByPair& by_pair,
                       const std::filesystem::path& file);
/// Problem p's runtime ECDF over the target ladder; returns it as data.
nlohmann::json write_ecdf(const BenchResult& result, size_t p, const RunsByPair& by_pair,
                const std::filesystem::path& file);

}  // namespace spec2fab::bench_report

#pragma once
/// Small charts for the bench report: log-scaled axes with decade ticks,
/// lines, quartile bands, a legend, and a heat-map table (OpenCV, PNG).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace spec2fab::plot {

/// One series: points (x, y) in data units, and optionally a band below and
/// above each point (quartiles).
struct Series {
  std::string label;
  std::vector<std::array<double, 2>> points;
  std::vector<std::array<double, 2>> band;  ///< (low, high) per point; empty: none
  bool steps = false;                       ///< draw as a staircase (ECDFs)
};

struct Axes {
  std::string title, x_label, y_label;
  double x_min = 1, x_max = 10, y_min = 0, y_max = 1;
  bool log_x = true, log_y = false;
};

/// Writes a line chart of `series` on `axes` into `file` (PNG).
void write_chart(const Axes& axes, const std::vector<Series>& series,
                 const std::filesystem::path& file);

/// The same chart as data, for report.html's interactive copy (report.json
/// "charts"): the axes' fields and each series' label, points, band, steps.
nlohmann::json chart_json(const Axes& axes, const std::vector<Series>& series);

/// Writes a square table of values in [0, 1] as a heat map (rows won against
/// columns); NaN cells are left blank.
void write_heat_map(const std::string& title, const std::vector<std::string>& labels,
                    const std::vector<std::vector<double>>& values,
                    const std::filesystem::path& file);

}  // namespace spec2fab::plot

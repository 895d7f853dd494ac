#include "tuning/convergence_plot.h"
#include "core/image_write.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace spec2fab {

void write_convergence_plot(const RunRecord& record, size_t tuner_count,
                            const std::filesystem::path& file) {
  // (evaluations so far, total error) after each tuner run, in schedule order.
  std::vector<double> latest(tuner_count, 0.0);
  std::vector<bool> seen(tuner_count, false);
  for (const TunerRun& run : record.runs) {
    if (!seen[run.tuner]) latest[run.tuner] = run.summary.initial_error;
    seen[run.tuner] = true;
  }
  double total = 0;
  for (double e : latest) total += e;
  std::vector<cv::Point2d> curve{{0, total}};
  std::vector<double> phase_starts;
  double evaluations = 0;
  size_t phase = record.runs.empty() ? 0 : record.runs.front().phase;
  for (const TunerRun& run : record.runs) {
    if (run.phase != phase) phase_starts.push_back(evaluations);
    phase = run.phase;
    // Within a run, its trace's best error so far: one run of 20,000
    // evaluations that converged in 40 is no straight line from start to end.
    for (const IterationRecord& row : run.summary.trace) {
      if (std::isfinite(row.best_error) && row.evaluations <= run.summary.evaluations) {
        curve.push_back({evaluations + static_cast<double>(row.evaluations), total - latest[run.tuner] + row.best_error});
      }
    }
    evaluations += static_cast<double>(run.summary.evaluations);
    total += run.summary.final_error - latest[run.tuner];
    latest[run.tuner] = run.summary.final_error;
    curve.push_back({evaluations, total});
  }

  constexpr int kWidth = 800, kHeight = 500, kLeft = 90, kRight = 20, kTop = 40, kBottom = 60;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  double max_error = 0, min_error = HUGE_VAL;
  for (const auto& p : curve) {
    max_error = std::max(max_error, p.y);
    if (p.y > 0) min_error = std::min(min_error, p.y);
  }
  if (max_error <= 0) max_error = 1;
  // Errors over more than two decades, all above 0, on a log scale.
  const bool log_scale = min_error < HUGE_VAL && max_error / min_error > 100 &&
                         std::all_of(curve.begin(), curve.end(), [](const cv::Point2d& p) { return p.y > 0; });
  const double low = log_scale ? std::log10(min_error) : 0, high = log_scale ? std::log10(max_error) : max_error;
  const double max_evaluations = std::max(evaluations, 1.0);
  auto to_pixel = [&](double x, double y) {
    const double level = log_scale ? (std::log10(y) - low) / std::max(high - low, 1e-12) : y / max_error;
    return cv::Point(kLeft + static_cast<int>(std::lround(x / max_evaluations * (kWidth - kLeft - kRight))),
                     kHeight - kBottom - static_cast<int>(std::lround(level * (kHeight - kTop - kBottom))));
  };
  const cv::Scalar axis(60, 60, 60), grey(200, 200, 200), line(180, 90, 20);
  const double bottom = log_scale ? min_error : 0;
  for (double start : phase_starts) {
    cv::line(image, to_pixel(start, bottom), to_pixel(start, max_error), grey, 1, cv::LINE_AA);
  }
  cv::line(image, to_pixel(0, bottom), to_pixel(max_evaluations, bottom), axis, 1);
  cv::line(image, to_pixel(0, bottom), to_pixel(0, max_error), axis, 1);
  std::vector<cv::Point> points;
  for (const auto& p : curve) points.push_back(to_pixel(p.x, p.y));
  cv::polylines(image, points, false, line, 2, cv::LINE_AA);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(image, log_scale ? "sum of tuner errors vs. evaluations (log scale)" : "sum of tuner errors vs. evaluations",
              {kLeft, 25}, font, 0.6, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.4g}", max_error), {5, kTop + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, log_scale ? fmt::format("{:.4g}", min_error) : std::string("0"),
              {log_scale ? 5 : kLeft - 20, kHeight - kBottom + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.0f} evaluations", max_evaluations),
              {kWidth - kRight - 170, kHeight - kBottom + 25}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("final {:.4g}", total), {kLeft + 10, kHeight - 15}, font, 0.5,
              line, 1, cv::LINE_AA);
  write_image(file, image);
}

void write_optimizer_comparison_plot(const std::vector<LabelledRun>& runs, const std::filesystem::path& file) {
  double max_evaluations = 1, low = HUGE_VAL, high = 0;
  for (const LabelledRun& run : runs) {
    max_evaluations = std::max(max_evaluations, static_cast<double>(run.summary->evaluations));
    for (const IterationRecord& row : run.summary->trace) {
      if (row.best_error > 0) low = std::min(low, row.best_error);
      high = std::max(high, row.best_error);
    }
    if (run.summary->initial_error > 0) high = std::max(high, run.summary->initial_error);
  }
  if (!(high > 0)) high = 1;
  if (!(low < high)) low = high / 10;
  const double log_low = std::floor(std::log10(low) * 10) / 10, log_high = std::ceil(std::log10(high) * 10) / 10;

  constexpr int kWidth = 800, kHeight = 500, kLeft = 90, kRight = 20, kTop = 40, kBottom = 60;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_pixel = [&](double evaluations, double error) {
    const double y = (std::log10(std::max(error, low)) - log_low) / std::max(1e-9, log_high - log_low);
    return cv::Point(kLeft + static_cast<int>(std::lround(evaluations / max_evaluations * (kWidth - kLeft - kRight))),
                     kHeight - kBottom - static_cast<int>(std::lround(y * (kHeight - kTop - kBottom))));
  };
  const cv::Scalar axis(60, 60, 60);
  const cv::Scalar colours[] = {{180, 90, 20}, {40, 40, 200}, {40, 150, 40}, {150, 40, 150}};
  cv::line(image, to_pixel(0, low), to_pixel(max_evaluations, low), axis, 1);
  cv::line(image, to_pixel(0, low), to_pixel(0, high), axis, 1);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  for (size_t r = 0; r < runs.size(); ++r) {
    const Summary& s = *runs[r].summary;
    const cv::Scalar colour = colours[r % std::size(colours)];
    std::vector<cv::Point> points{to_pixel(0, s.initial_error)};
    for (const IterationRecord& row : s.trace)
      points.push_back(to_pixel(static_cast<double>(row.evaluations), row.best_error));
    points.push_back(to_pixel(static_cast<double>(s.evaluations), s.final_error));
    cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
    cv::putText(image, fmt::format("{}: {:.4g} after {} evaluations", runs[r].label, s.final_error, s.evaluations),
                {kLeft + 250, kTop + 120 + 22 * static_cast<int>(r)}, font, 0.5, colour, 1, cv::LINE_AA);
  }
  cv::putText(image, "best error vs. evaluations (log scale)", {kLeft, 25}, font, 0.6, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.3g}", std::pow(10.0, log_high)), {5, kTop + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.3g}", std::pow(10.0, log_low)), {5, kHeight - kBottom + 5}, font, 0.45, axis, 1,
              cv::LINE_AA);
  cv::putText(image, fmt::format("{:.0f} evaluations", max_evaluations), {kWidth - kRight - 170, kHeight - kBottom + 25},
              font, 0.45, axis, 1, cv::LINE_AA);
  write_image(file, image);
}

}  // namespace spec2fab

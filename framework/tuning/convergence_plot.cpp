#include "tuning/convergence_plot.h"

#include <algorithm>
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
    evaluations += static_cast<double>(run.summary.evaluations);
    total += run.summary.final_error - latest[run.tuner];
    latest[run.tuner] = run.summary.final_error;
    curve.push_back({evaluations, total});
  }

  constexpr int kWidth = 800, kHeight = 500, kLeft = 90, kRight = 20, kTop = 40, kBottom = 60;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  double max_error = 0;
  for (const auto& p : curve) max_error = std::max(max_error, p.y);
  if (max_error <= 0) max_error = 1;
  const double max_evaluations = std::max(evaluations, 1.0);
  auto to_pixel = [&](double x, double y) {
    return cv::Point(kLeft + static_cast<int>(std::lround(x / max_evaluations * (kWidth - kLeft - kRight))),
                     kHeight - kBottom -
                         static_cast<int>(std::lround(y / max_error * (kHeight - kTop - kBottom))));
  };
  const cv::Scalar axis(60, 60, 60), grey(200, 200, 200), line(180, 90, 20);
  for (double start : phase_starts) {
    cv::line(image, to_pixel(start, 0), to_pixel(start, max_error), grey, 1, cv::LINE_AA);
  }
  cv::line(image, to_pixel(0, 0), to_pixel(max_evaluations, 0), axis, 1);
  cv::line(image, to_pixel(0, 0), to_pixel(0, max_error), axis, 1);
  std::vector<cv::Point> points;
  for (const auto& p : curve) points.push_back(to_pixel(p.x, p.y));
  cv::polylines(image, points, false, line, 2, cv::LINE_AA);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(image, "sum of tuner errors vs. evaluations", {kLeft, 25}, font, 0.6, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.4g}", max_error), {5, kTop + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, "0", {kLeft - 20, kHeight - kBottom + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("{:.0f} evaluations", max_evaluations),
              {kWidth - kRight - 170, kHeight - kBottom + 25}, font, 0.45, axis, 1, cv::LINE_AA);
  cv::putText(image, fmt::format("final {:.4g}", total), {kLeft + 10, kHeight - 15}, font, 0.5,
              line, 1, cv::LINE_AA);
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
}

}  // namespace spec2fab

#include "bench/plot.h"
#include "core/image_write.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace spec2fab::plot {

namespace {

constexpr int kWidth = 900, kHeight = 580, kLeft = 80, kRight = 200, kTop = 65, kBottom = 60;
const auto kFont = cv::FONT_HERSHEY_SIMPLEX;
const cv::Scalar kInk(50, 50, 50), kGrid(225, 225, 225);

/// Tableau's ten colours (BGR), then darker repeats.
cv::Scalar colour(size_t k) {
  static const std::array<cv::Scalar, 10> palette{
      cv::Scalar(180, 119, 31),  cv::Scalar(14, 127, 255),  cv::Scalar(44, 160, 44),
      cv::Scalar(40, 39, 214),   cv::Scalar(189, 103, 148), cv::Scalar(75, 86, 140),
      cv::Scalar(194, 119, 227), cv::Scalar(127, 127, 127), cv::Scalar(34, 189, 188),
      cv::Scalar(207, 190, 23)};
  const cv::Scalar c = palette[k % palette.size()];
  return k < palette.size() ? c : c * 0.6;
}

struct Frame {
  const Axes& axes;
  double map(double v, double lo, double hi, bool log) const {
    if (log)
      return (std::log10(std::max(v, lo)) - std::log10(lo)) / (std::log10(hi) - std::log10(lo));
    return (v - lo) / (hi - lo);
  }
  cv::Point at(double x, double y) const {
    const double u = std::clamp(map(x, axes.x_min, axes.x_max, axes.log_x), 0.0, 1.0);
    const double v = std::clamp(map(y, axes.y_min, axes.y_max, axes.log_y), 0.0, 1.0);
    return {kLeft + static_cast<int>(std::lround(u * (kWidth - kLeft - kRight))),
            kHeight - kBottom - static_cast<int>(std::lround(v * (kHeight - kTop - kBottom)))};
  }
};

/// Tick values: decades on a log axis, fifths on a linear one.
std::vector<double> ticks(double lo, double hi, bool log) {
  std::vector<double> out;
  if (log) {
    for (double e = std::ceil(std::log10(lo) - 1e-9); e <= std::floor(std::log10(hi) + 1e-9);
         e += 1)
      out.push_back(std::pow(10.0, e));
    // Many decades: label every other one.
    if (out.size() > 10) {
      std::vector<double> thinned;
      for (size_t k = 0; k < out.size(); k += 2) thinned.push_back(out[k]);
      out = thinned;
    }
  } else {
    for (int k = 0; k <= 5; ++k) out.push_back(lo + (hi - lo) * k / 5);
  }
  return out;
}

std::string tick_label(double v, bool log) {
  if (log) return fmt::format("1e{}", static_cast<int>(std::lround(std::log10(v))));
  return fmt::format("{:.3g}", v);
}

void write_png(const cv::Mat& image, const std::filesystem::path& file) {
  std::filesystem::create_directories(file.parent_path());
  write_image(file, image);
}

}  // namespace

void write_chart(const Axes& axes, const std::vector<Series>& series,
                 const std::filesystem::path& file) {
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const Frame frame{axes};
  for (double t : ticks(axes.x_min, axes.x_max, axes.log_x)) {
    cv::line(image, frame.at(t, axes.y_min), frame.at(t, axes.y_max), kGrid, 1);
    const std::string text = tick_label(t, axes.log_x);
    cv::putText(image, text, frame.at(t, axes.y_min) + cv::Point(-12, 20), kFont, 0.42, kInk, 1,
                cv::LINE_AA);
  }
  for (double t : ticks(axes.y_min, axes.y_max, axes.log_y)) {
    cv::line(image, frame.at(axes.x_min, t), frame.at(axes.x_max, t), kGrid, 1);
    cv::putText(image, tick_label(t, axes.log_y), frame.at(axes.x_min, t) + cv::Point(-62, 5),
                kFont, 0.42, kInk, 1, cv::LINE_AA);
  }
  cv::rectangle(image, frame.at(axes.x_min, axes.y_max), frame.at(axes.x_max, axes.y_min), kInk, 1);
  cv::putText(image, axes.title, {8, 24}, kFont, 0.6, kInk, 1, cv::LINE_AA);
  cv::putText(image, axes.x_label, {kLeft + (kWidth - kLeft - kRight) / 2 - 80, kHeight - 18},
              kFont, 0.48, kInk, 1, cv::LINE_AA);
  cv::putText(image, axes.y_label, {8, kTop - 14}, kFont, 0.45, kInk, 1, cv::LINE_AA);

  // Bands first, blended, so that every line stays visible over them.
  for (size_t s = 0; s < series.size(); ++s) {
    const Series& one = series[s];
    if (one.band.empty()) continue;
    std::vector<cv::Point> outline;
    for (size_t k = 0; k < one.points.size(); ++k)
      outline.push_back(frame.at(one.points[k][0], one.band[k][1]));
    for (size_t k = one.points.size(); k-- > 0;)
      outline.push_back(frame.at(one.points[k][0], one.band[k][0]));
    cv::Mat layer = image.clone();
    cv::fillPoly(layer, std::vector<std::vector<cv::Point>>{outline}, colour(s), cv::LINE_AA);
    cv::addWeighted(layer, 0.18, image, 0.82, 0, image);
  }
  for (size_t s = 0; s < series.size(); ++s) {
    const Series& one = series[s];
    std::vector<cv::Point> line;
    for (size_t k = 0; k < one.points.size(); ++k) {
      const cv::Point p = frame.at(one.points[k][0], one.points[k][1]);
      if (one.steps && !line.empty()) line.push_back({p.x, line.back().y});
      line.push_back(p);
    }
    if (line.size() == 1) cv::circle(image, line.front(), 4, colour(s), cv::FILLED, cv::LINE_AA);
    cv::polylines(image, line, false, colour(s), 2, cv::LINE_AA);
    const cv::Point key(kWidth - kRight + 15, kTop + 12 + 22 * static_cast<int>(s));
    cv::line(image, key, key + cv::Point(24, 0), colour(s), 3, cv::LINE_AA);
    cv::putText(image, one.label, key + cv::Point(32, 5), kFont, 0.45, kInk, 1, cv::LINE_AA);
  }
  write_png(image, file);
}

void write_heat_map(const std::string& title, const std::vector<std::string>& labels,
                    const std::vector<std::vector<double>>& values,
                    const std::filesystem::path& file) {
  const int n = static_cast<int>(labels.size());
  constexpr int kCell = 64, kLabel = 150, kHead = 60;
  cv::Mat image(kHead + kLabel + n * kCell + 20, kLabel + n * kCell + 20, CV_8UC3,
                cv::Scalar(255, 255, 255));
  cv::putText(image, title, {10, 28}, kFont, 0.55, kInk, 1, cv::LINE_AA);
  for (int i = 0; i < n; ++i) {
    cv::putText(image, labels[static_cast<size_t>(i)],
                {8, kHead + kLabel + i * kCell + kCell / 2 + 5}, kFont, 0.45, kInk, 1, cv::LINE_AA);
    // Column labels written upwards: text rotated by drawing into a strip.
    cv::Mat strip(kCell, kLabel, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(strip, labels[static_cast<size_t>(i)], {4, kCell / 2 + 5}, kFont, 0.45, kInk, 1,
                cv::LINE_AA);
    cv::Mat upright;
    cv::rotate(strip, upright, cv::ROTATE_90_COUNTERCLOCKWISE);
    upright.copyTo(image(cv::Rect(kLabel + i * kCell, kHead, kCell, kLabel)));
    for (int j = 0; j < n; ++j) {
      const double v = values[static_cast<size_t>(i)][static_cast<size_t>(j)];
      const cv::Rect cell(kLabel + j * kCell, kHead + kLabel + i * kCell, kCell, kCell);
      if (std::isnan(v)) {
        cv::rectangle(image, cell, kGrid, 1);
        continue;
      }
      // Red (loses) through white to blue (wins).
      const double w = std::clamp(v, 0.0, 1.0);
      const cv::Scalar fill =
          w >= 0.5 ? cv::Scalar(255, 255 - 2 * (w - 0.5) * 150, 255 - 2 * (w - 0.5) * 200)
                   : cv::Scalar(255 - 2 * (0.5 - w) * 200, 255 - 2 * (0.5 - w) * 150, 255);
      cv::rectangle(image, cell, fill, cv::FILLED);
      cv::rectangle(image, cell, kGrid, 1);
      cv::putText(image, fmt::format("{:.0f}%", 100 * v), {cell.x + 12, cell.y + kCell / 2 + 5},
                  kFont, 0.45, kInk, 1, cv::LINE_AA);
    }
  }
  write_png(image, file);
}

nlohmann::json chart_json(const Axes& axes, const std::vector<Series>& series) {
  nlohmann::json list = nlohmann::json::array();
  for (const Series& one : series) {
    nlohmann::json entry = {{"label", one.label}, {"points", one.points}, {"steps", one.steps}};
    if (!one.band.empty()) entry["band"] = one.band;
    list.push_back(std::move(entry));
  }
  return {{"title", axes.title}, {"x_label", axes.x_label}, {"y_label", axes.y_label}, {"x_min", axes.x_min},
          {"x_max", axes.x_max}, {"y_min", axes.y_min}, {"y_max", axes.y_max}, {"log_x", axes.log_x},
          {"log_y", axes.log_y}, {"series", std::move(list)}};
}

}  // namespace spec2fab::plot

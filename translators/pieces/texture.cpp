#include "texture.h"

#include <algorithm>
#include <numeric>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/colour.h"
#include "core/parameter.h"
#include "core/properties.h"
#include "core/strings.h"
#include "reducer/reducer_tree.h"
#include "spec/experiment.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// The point of the convex hull of `gamut` closest to `target` (linear RGB),
/// by Frank–Wolfe iterations with exact line search. Error diffusion can
/// only reproduce, on average, colours inside this hull (mixtures of
/// printable stacks); a goal colour outside it would wind residuals up.
Rgb project_onto_hull(const std::vector<Rgb>& gamut, const Rgb& target) {
  auto dot = [](const Rgb& a, const Rgb& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  auto sub = [](const Rgb& a, const Rgb& b) { return Rgb{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  Rgb x = gamut.front();
  for (const Rgb& c : gamut) {
    if (dot(sub(c, target), sub(c, target)) < dot(sub(x, target), sub(x, target))) x = c;
  }
  for (int iteration = 0; iteration < 500; ++iteration) {
    const Rgb gradient = sub(x, target);
    const Rgb* best = &gamut.front();
    double lowest = dot(gradient, *best);
    for (const Rgb& c : gamut) {
      const double value = dot(gradient, c);
      if (value < lowest) lowest = value, best = &c;
    }
    const Rgb direction = sub(*best, x);
    const double gap = -dot(gradient, direction);
    if (gap < 1e-12) break;
    const double step = std::min(1.0, gap / std::max(dot(direction, direction), 1e-300));
    for (int c = 0; c < 3; ++c) x[c] += step * direction[c];
  }
  return x;
}

}  // namespace

GoalImage load_goal_image(const Properties& goal, const std::string& key, std::array<int, 2>& columns) {
  const std::filesystem::path file = goal.existing_file(key);
  cv::Mat image = cv::imread(file.string(), cv::IMREAD_COLOR);
  if (image.empty()) goal.fail(key, "cannot read image " + file.string());
  if (columns[0] == 0) columns = {image.cols, image.rows};
  cv::Mat resized;
  cv::resize(image, resized, cv::Size(columns[0], columns[1]), 0, 0, cv::INTER_AREA);
  GoalImage out{columns[0], columns[1], {}};
  out.pixels.reserve(static_cast<size_t>(columns[0]) * static_cast<size_t>(columns[1]));
  for (int y = 0; y < resized.rows; ++y) {
    for (int x = 0; x < resized.cols; ++x) {
      const cv::Vec3b bgr = resized.at<cv::Vec3b>(y, x);
      out.pixels.push_back({srgb_to_linear(bgr[2] / 255.0), srgb_to_linear(bgr[1] / 255.0),
                            srgb_to_linear(bgr[0] / 255.0)});
    }
  }
  return out;
}

/// Mean ΔE00 between two images after a Gaussian low-pass in linear RGB (what
/// the eye sees from a distance: the measure error diffusion improves).
double low_pass_delta_e(const GoalImage& goal, const std::vector<Rgb>& achieved, double sigma) {
  auto to_mat = [&](const std::vector<Rgb>& pixels) {
    cv::Mat m(goal.height, goal.width, CV_64FC3);
    for (int y = 0; y < goal.height; ++y) {
      for (int x = 0; x < goal.width; ++x) {
        const Rgb& p = pixels[static_cast<size_t>(y * goal.width + x)];
        m.at<cv::Vec3d>(y, x) = cv::Vec3d(p[0], p[1], p[2]);
      }
    }
    cv::Mat blurred;
    cv::GaussianBlur(m, blurred, cv::Size(0, 0), sigma, sigma, cv::BORDER_REFLECT);
    return blurred;
  };
  const cv::Mat a = to_mat(goal.pixels), b = to_mat(achieved);
  double sum = 0;
  for (int y = 0; y < goal.height; ++y) {
    for (int x = 0; x < goal.width; ++x) {
      const cv::Vec3d p = a.at<cv::Vec3d>(y, x), q = b.at<cv::Vec3d>(y, x);
      sum += ciede2000(linear_rgb_to_lab({p[0], p[1], p[2]}), linear_rgb_to_lab({q[0], q[1], q[2]}));
    }
  }
  return sum / static_cast<double>(goal.pixels.size());
}

nlohmann::json delta_e_statistics(const std::vector<Rgb>& goal, const std::vector<Rgb>& achieved) {
  std::vector<double> d;
  for (size_t i = 0; i < goal.size(); ++i) {
    d.push_back(ciede2000(linear_rgb_to_lab(goal[i]), linear_rgb_to_lab(achieved[i])));
  }
  std::vector<double> sorted = d;
  std::sort(sorted.begin(), sorted.end());
  double mean = 0;
  for (double x : d) mean += x;
  mean /= static_cast<double>(std::max<size_t>(d.size(), 1));
  const auto p95 = sorted[static_cast<size_t>(std::ceil(0.95 * static_cast<double>(sorted.size()))) - 1];
  return {{"mean", mean}, {"p95", p95}, {"max", sorted.back()}};
}


/// Every stack a column can be printed with, simulated (the tuner's search space enumerated).
std::vector<Rgb> printable_colours(Tuner& tuner) {
  std::vector<Parameter*> axes;
  long long count = 1;
  for (const auto& e : tuner.search_space().entries()) {
    axes.push_back(e.parameter);
    count *= e.parameter->cardinality();
  }
  std::vector<Rgb> out;
  std::vector<double> x(axes.size());
  for (long long index = 0; index < count; ++index) {
    long long rest = index;
    for (size_t a = 0; a < axes.size(); ++a) {
      x[a] = axes[a]->admissible(rest % axes[a]->cardinality());
      rest /= axes[a]->cardinality();
    }
    tuner.error_at(x);
    out.push_back(static_cast<const AlbedoObservation&>(tuner.simulated()).rgb);
  }
  return out;
}

/// A goal colour diffusion can reproduce on average: its projection onto the
/// hull of the printable colours when that is within ΔE00 1 of it, else the printable colour nearest to it
/// in ΔE00 (a projection in linear RGB would turn dark out-of-gamut colours,
/// close in RGB, into perceptually distant ones).
Rgb gamut_map(const std::vector<Rgb>& gamut, const Rgb& pixel) {
  const Rgb projected = project_onto_hull(gamut, pixel);
  const Lab lab = linear_rgb_to_lab(pixel);
  // Inside, or outside by no more than 8-bit rounding of the goal image.
  if (ciede2000(lab, linear_rgb_to_lab(projected)) < 1.0) return projected;
  const Rgb* best = &gamut.front();
  double lowest = ciede2000(lab, linear_rgb_to_lab(*best));
  for (const Rgb& c : gamut) {
    const double d = ciede2000(lab, linear_rgb_to_lab(c));
    if (d < lowest) lowest = d, best = &c;
  }
  return *best;
}

void write_colour_panels(const std::vector<const std::vector<Rgb>*>& panels, int width, int height,
                         const std::filesystem::path& file, bool highest_v_on_top) {
  const int scale = std::max(1, 256 / std::max(width, height));
  const int w = width * scale, h = height * scale, gap = 8;
  const int count = static_cast<int>(panels.size());
  cv::Mat image(h, count * w + (count - 1) * gap, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int p = 0; p < count; ++p) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int row = highest_v_on_top ? height - 1 - y / scale : y / scale;
        const Rgb& c = (*panels[static_cast<size_t>(p)])[static_cast<size_t>(row * width + x / scale)];
        image.at<cv::Vec3b>(y, p * (w + gap) + x) =
            cv::Vec3b(linear_to_srgb8(c[2]), linear_to_srgb8(c[1]), linear_to_srgb8(c[0]));
      }
    }
  }
  if (!cv::imwrite(file.string(), image)) throw std::runtime_error("cannot write " + file.string());
}

TextureOptions::TextureOptions(TextureKeys renamed, std::vector<std::string> inks_by_default)
    : keys(std::move(renamed)), default_inks(std::move(inks_by_default)) {
  if (!default_inks.empty()) default_inks_text = "[" + join(default_inks) + "]";
}

TexturePiece::TexturePiece(const Properties& goal, const Experiment& experiment, TextureOptions o,
                           const std::string& ground, const char* ground_key) {
  read_options_into(o, goal);
  const MaterialPalette& palette = experiment.palette();
  if (ground_key) palette.id(ground, goal.where(ground_key));
  const PrinterProfile& printer = experiment.printer();
  columns_ = o.columns;
  image_ = load_goal_image(goal, o.keys.image, columns_);
  top_row_at_highest_v_ = o.top_row_at_highest_v;
  if (top_row_at_highest_v_) {
    std::vector<Rgb> rows_from_bottom;
    for (int row = columns_[1] - 1; row >= 0; --row)
      rows_from_bottom.insert(rows_from_bottom.end(), image_.pixels.begin() + static_cast<std::ptrdiff_t>(row) * columns_[0],
                              image_.pixels.begin() + static_cast<std::ptrdiff_t>(row + 1) * columns_[0]);
    image_.pixels = std::move(rows_from_bottom);
  }
  if (o.inks) {
    inks_ = *o.inks;
    for (const std::string& ink : inks_) palette.id(ink, goal.where("inks"));
  } else if (!o.default_inks.empty()) {
    inks_ = o.default_inks;
  } else {
    for (const std::string& m : printer.model_materials) {
      if (m != ground && palette.material(palette.id(m, goal.where())).kind != "transparent") inks_.push_back(m);
    }
  }
  if (inks_.empty()) goal.fail("inks", "no ink to print the texture with");
  step_mm_ = std::isnan(o.layer_step_mm) ? printer.layer_mm : o.layer_step_mm;
  if (o.max_ink_mm.per_ink) {
    max_ink_mm_ = o.max_ink_mm.mm;
    if (max_ink_mm_.size() != inks_.size()) goal.fail("max_ink_mm", "give one thickness per ink, or one for all");
    for (double m : max_ink_mm_) require_in(goal, "max_ink_mm", m, Range::closed(step_mm_, 10));
    ink_mm_ = std::accumulate(max_ink_mm_.begin(), max_ink_mm_.end(), 0.0);
  } else {
    const double each = o.max_ink_mm.mm.empty() ? 5 * step_mm_ : o.max_ink_mm.mm.front();
    require_in(goal, "max_ink_mm", each, Range::closed(step_mm_, 10));
    max_ink_mm_.assign(inks_.size(), each);
    ink_mm_ = static_cast<double>(inks_.size()) * each;
  }
  metric_ = o.metric;
  diffusion_ = o.error_diffusion;
  gamut_map_ = o.gamut_map.value_or(diffusion_);
  low_pass_sigma_ = o.low_pass_sigma_px;
  optimizer_ = experiment.section_or(o.keys.optimizer, {{"type", "exhaustive"}});
}

std::vector<PropertyDoc> TexturePiece::docs(const TextureOptions& options) {
  std::vector<PropertyDoc> rows = prefixed(option_docs(options), "goal.");
  rows.push_back({options.keys.optimizer, "optimizer", "{\"type\": \"exhaustive\"}", "each column's optimizer"});
  return rows;
}

nlohmann::json TexturePiece::ink_layers() const {
  nlohmann::json layers = nlohmann::json::array();
  for (size_t k = 0; k < inks_.size(); ++k)
    layers.push_back({{"material", inks_[k]},
                      {"thickness_mm", {{"value", 0.0}, {"min", 0.0}, {"max", max_ink_mm_[k]}, {"step", step_mm_}}}});
  return layers;
}

Phase TexturePiece::add_tuners(TunerNetwork& network, ReducerTree& tree,
                               const std::function<ReducerNode&(int column)>& stack, const Experiment& experiment) {
  const PartContext context{experiment.palette(), &experiment.cache()};
  // Below the thickest stack, one more step: what the inks lie on.
  const double depth_mm = ink_mm_ + step_mm_;
  auto make_tuner = [&](int i, int j, const Rgb& target) {
    const nlohmann::json parts = {
        {"simulator", {{"type", "albedo"}, {"depth_mm", depth_mm}, {"step_mm", step_mm_ / 8}}},
        {"metric", {{"type", metric_}}},
        {"goal", {{"type", "albedo"}, {"linear_rgb", target}}},
        {"optimizer", optimizer_}};
    auto tuner = build_tuner(Properties::wrap(parts, experiment.file().string() + " (texture tuner)"),
                             fmt::format("column_{}_{}", i, j), context);
    tuner->set_node(tree, stack(i + columns_[0] * j));
    return tuner;
  };
  // Error diffusion and the grid count tuners from 0: the texture comes first.
  if (network.size() != 0) throw std::logic_error("TexturePiece::add_tuners: the texture's tuners must come first");
  first_tuner_ = 0;
  gamut_ = printable_colours(*make_tuner(0, 0, {0.5, 0.5, 0.5}));
  for (int j = 0; j < columns_[1]; ++j) {
    for (int i = 0; i < columns_[0]; ++i) {
      const Rgb& pixel = image_.pixels[static_cast<size_t>(j * columns_[0] + i)];
      Rgb target = gamut_map_ ? gamut_map(gamut_, pixel) : pixel;
      // The goal type accepts [0, 1]; the hull lies inside up to rounding.
      for (double& c : target) c = std::clamp(c, 0.0, 1.0);
      network.add(make_tuner(i, j, target));
    }
  }
  network.connect_grid(columns_[0], columns_[1], 4);
  Phase phase;
  phase.name = diffusion_ ? "error_diffusion" : "nearest";
  phase.tuners = tuners();
  phase.mode = diffusion_ ? Phase::Mode::serial : Phase::Mode::parallel;
  // Albedos lie in [0, 1]; clamping the diffused targets there keeps
  // out-of-gamut regions (deep ocean blue) from winding residuals up.
  if (diffusion_) phase.coupling = std::make_shared<ErrorDiffusion>(columns_[0], std::pair{0.0, 1.0});
  return phase;
}

std::vector<size_t> TexturePiece::tuners() const {
  std::vector<size_t> out(static_cast<size_t>(column_count()));
  std::iota(out.begin(), out.end(), first_tuner_);
  return out;
}

std::vector<Rgb> TexturePiece::achieved(TunerNetwork& network) const {
  std::vector<Rgb> out;
  for (size_t t : tuners()) {
    Tuner& tuner = network.tuner(t);
    tuner.error();  // simulates at the current parameters
    out.push_back(static_cast<const AlbedoObservation&>(tuner.simulated()).rgb);
  }
  return out;
}

std::vector<Rgb> TexturePiece::nearest_only(TunerNetwork& network) const {
  std::vector<std::vector<double>> chosen;
  for (size_t t : tuners()) chosen.push_back(network.tuner(t).search_space().values());
  for (size_t t : tuners()) {
    Tuner& tuner = network.tuner(t);
    const Rgb& pixel = image_.pixels[t - first_tuner_];
    std::copy(pixel.begin(), pixel.end(), tuner.effective_target().values().begin());
    tuner.tune();
  }
  std::vector<Rgb> nearest = achieved(network);
  for (size_t t : tuners()) network.tuner(t).error_at(chosen[t - first_tuner_]);
  return nearest;
}

nlohmann::json TexturePiece::report(const std::vector<Rgb>& achieved) const {
  return {{"columns", columns_},
          {"inks", inks_},
          {"metric", metric_},
          {"error_diffusion", diffusion_},
          {"gamut_map", gamut_map_},
          {"printable_stacks", gamut_.size()},
          {"delta_e00", delta_e_statistics(image_.pixels, achieved)},
          {"low_pass_sigma_px", low_pass_sigma_},
          {"low_pass_delta_e00", low_pass_delta_e(image_, achieved, low_pass_sigma_)}};
}

}  // namespace spec2fab

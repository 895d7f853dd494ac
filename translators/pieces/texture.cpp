#include "texture.h"
#include "core/image_write.h"

#include <algorithm>
#include <numeric>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "albedo/albedo_lookup.h"
#include "albedo/albedo_parts.h"
#include "core/colour.h"
#include "core/parameter.h"
#include "core/properties.h"
#include "core/strings.h"
#include "geometry/solid.h"
#include "materials/printer_profile.h"
#include "reducer/node.h"
#include "reducer/reducer_tree.h"
#include "spec/experiment.h"
#include "tuning/image_file.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// The goal's "metric" (a choice of the two).
ColourMetric colour_metric(const std::string& name) {
  return name == "rgb_mse" ? ColourMetric::rgb_mse : ColourMetric::ciede2000;
}

// What the lookup costs per column, measured on this 2-core machine (Release,
// 2 threads) over the 512 x 512 photograph runs of benchmarks/RESULTS.md
// ("Appearance at photograph scale"): the estimate printed before it runs.
constexpr double kLookupMicrosecondsPerColumn = 9.0;
constexpr double kLookupBytesPerColumn = 300.0;

double lookup_seconds(long long columns) { return 1e-6 * kLookupMicrosecondsPerColumn * static_cast<double>(columns); }
double lookup_megabytes(long long columns) { return 1e-6 * kLookupBytesPerColumn * static_cast<double>(columns); }

}  // namespace

PrintableStacks printable_stacks(Tuner& tuner) {
  std::vector<Parameter*> axes;
  long long count = 1;
  for (const auto& e : tuner.search_space().entries()) {
    axes.push_back(e.parameter);
    count *= e.parameter->cardinality();
  }
  PrintableStacks out;
  std::vector<double> x(axes.size());
  for (long long index = 0; index < count; ++index) {
    long long rest = index;
    for (size_t a = 0; a < axes.size(); ++a) {
      x[a] = axes[a]->admissible(rest % axes[a]->cardinality());
      rest /= axes[a]->cardinality();
    }
    tuner.error_at(x);
    out.values.push_back(x);
    out.colours.push_back(static_cast<const AlbedoObservation&>(tuner.simulated()).rgb);
  }
  return out;
}

void write_colour_panels(const std::vector<const std::vector<Rgb>*>& panels, int width, int height,
                         const std::filesystem::path& file, bool highest_v_on_top) {
  // Small textures are scaled up to about 256 px, each column a block;
  // large ones shrink to 768 px by averaging in linear light, as the eye
  // averages a halftone from a distance.
  constexpr int kLargest = 768;
  const int longest = std::max(width, height);
  const double scale = longest > kLargest ? static_cast<double>(kLargest) / longest
                                          : static_cast<double>(std::max(1, 256 / longest));
  const int w = std::max(1, static_cast<int>(std::lround(width * scale)));
  const int h = std::max(1, static_cast<int>(std::lround(height * scale)));
  const int gap = 8;
  const int count = static_cast<int>(panels.size());
  cv::Mat image(h, count * w + (count - 1) * gap, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int p = 0; p < count; ++p) {
    cv::Mat linear(height, width, CV_32FC3);
    for (int y = 0; y < height; ++y) {
      const int row = highest_v_on_top ? height - 1 - y : y;
      for (int x = 0; x < width; ++x) {
        const Rgb& c = (*panels[static_cast<size_t>(p)])[static_cast<size_t>(row) * static_cast<size_t>(width) +
                                                           static_cast<size_t>(x)];
        linear.at<cv::Vec3f>(y, x) = cv::Vec3f(static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2]));
      }
    }
    cv::Mat resized;
    cv::resize(linear, resized, cv::Size(w, h), 0, 0, scale < 1 ? cv::INTER_AREA : cv::INTER_NEAREST);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const cv::Vec3f c = resized.at<cv::Vec3f>(y, x);
        image.at<cv::Vec3b>(y, p * (w + gap) + x) = cv::Vec3b(linear_to_srgb8(c[2]), linear_to_srgb8(c[1]), linear_to_srgb8(c[0]));
      }
  }
  write_image(file, image);
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
  read_columns(goal, experiment, o);
  read_inks(goal, experiment, o, ground);
  metric_ = o.metric;
  diffusion_ = o.error_diffusion;
  gamut_map_ = o.gamut_map.value_or(diffusion_);
  low_pass_sigma_ = o.low_pass_sigma_px;
  optimizer_.emplace(experiment.root(), o.keys.optimizer, nlohmann::json{{"type", "exhaustive"}});
  if (diffuse_in_lab_ && metric_ != "ciede2000")
    goal.fail("diffusion_space", "lab needs metric ciede2000 (the lookup searches CIELAB then)");

  map_into_printable_gamut(goal, experiment, ground);
}

void TexturePiece::read_columns(const Properties& goal, const Experiment& experiment, const TextureOptions& o) {
  const PrinterProfile& printer = experiment.printer();
  columns_ = o.columns;
  lookup_ = o.lookup();
  diffuse_in_lab_ = o.diffusion_space == "lab";
  if (lookup_ && columns_[0] == 0) columns_ = printer_resolution_columns(experiment.solid(), printer);
  if (lookup_ && static_cast<double>(column_count()) > o.max_columns)
    goal.fail(goal.has(o.keys.columns) ? o.keys.columns : "max_columns",
              fmt::format("{} x {} columns ({:.3g}) would take ~{:.0f} s and ~{:.0f} MB, more than max_columns "
                          "({:.3g}) allows; raise goal.max_columns to go ahead, or give fewer columns",
                          columns_[0], columns_[1], static_cast<double>(column_count()),
                          lookup_seconds(column_count()), lookup_megabytes(column_count()), o.max_columns));
  image_ = load_goal_image(goal, o.keys.image, columns_, experiment.limits());
  if (!lookup_ && column_count() > kMostTunedColumns)  // the image's own size, known only now
    goal.fail(o.keys.image, fmt::format("{} x {} pixels, so as many columns: more than a million for tuners "
                                        "(give fewer {})", columns_[0], columns_[1], o.keys.columns));
  top_row_at_highest_v_ = o.top_row_at_highest_v;
  if (top_row_at_highest_v_) {
    std::vector<Rgb> rows_from_bottom;
    for (int row = columns_[1] - 1; row >= 0; --row)
      rows_from_bottom.insert(rows_from_bottom.end(), image_.pixels.begin() + static_cast<std::ptrdiff_t>(row) * columns_[0],
                              image_.pixels.begin() + static_cast<std::ptrdiff_t>(row + 1) * columns_[0]);
    image_.pixels = std::move(rows_from_bottom);
  }
}

void TexturePiece::read_inks(const Properties& goal, const Experiment& experiment, const TextureOptions& o,
                             const std::string& ground) {
  const MaterialPalette& palette = experiment.palette();
  const PrinterProfile& printer = experiment.printer();
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
  const double thickest = *std::max_element(max_ink_mm_.begin(), max_ink_mm_.end());
  shell_depth_ = stratum_depth(ink_mm_ + step_mm_, goal.where(o.inks ? "inks" : "max_ink_mm"),
                               fmt::format("{} inks of up to {:g} mm and a step of {}", inks_.size(), thickest, ground));
}

void TexturePiece::map_into_printable_gamut(const Properties& goal, const Experiment& experiment,
                                            const std::string& ground) {
  const MaterialPalette& palette = experiment.palette();
  // Every printable stack simulated once, on a stack of its own: the
  // lookup's table, the gamut, and what a column tuner searches.
  LayeredOptions printable;
  printable.layers = ink_layers(palette);
  printable.fill.parameter = fixed_material(palette, ground, goal.where());
  const NodePtr stack = make_layered(std::move(printable));
  std::unique_ptr<Tuner> tuner = column_tuner(experiment, "printable_stacks", {0.5, 0.5, 0.5});
  tuner->set_node(*stack);
  stacks_ = printable_stacks(*tuner);
  lookup_table_ = std::make_shared<const AlbedoLookup>(
      stacks_.colours, colour_metric(metric_));
  gamut_ = std::make_shared<const PrintableGamut>(stacks_.colours);
  mapped_.resize(image_.pixels.size());
  outside_.resize(image_.pixels.size());
  std::vector<char> outside(image_.pixels.size());  // vector<bool> is not safe to write in parallel
  tbb::parallel_for(tbb::blocked_range<size_t>(0, image_.pixels.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p < r.end(); ++p) {
      const GamutMapped m = map_into_gamut(*gamut_, *lookup_table_, image_.pixels[p]);
      mapped_[p] = m.colour;
      outside[p] = m.outside;
    }
  });
  for (size_t p = 0; p < outside.size(); ++p) outside_[p] = outside[p] != 0;
}

std::unique_ptr<Tuner> TexturePiece::column_tuner(const Experiment& experiment, const std::string& name,
                                                  const Rgb& target) const {
  // Below the thickest stack, one more step: what the inks lie on.
  AlbedoSimulatorOptions albedo;
  albedo.depth_mm = ink_mm_ + step_mm_;
  albedo.step_mm = step_mm_ / 8;
  return make_tuner(name, make_albedo_simulator(albedo, experiment.part_context()),
                    make_colour_metric(colour_metric(metric_)),
                    make_albedo_goal(target), optimizer_->build());
}

std::vector<PropertyDoc> TexturePiece::docs(const TextureOptions& options) {
  std::vector<PropertyDoc> rows = prefixed(option_docs(options), "goal.");
  rows.push_back({options.keys.optimizer, "optimizer", "{\"type\": \"exhaustive\"}", "each column's optimizer"});
  return rows;
}

std::vector<LayeredOptions::Layer> TexturePiece::ink_layers(const MaterialPalette& palette) const {
  std::vector<LayeredOptions::Layer> layers(inks_.size());
  for (size_t k = 0; k < inks_.size(); ++k) {
    layers[k].material.parameter = fixed_material(palette, inks_[k], "inks");
    layers[k].thickness_mm = free_steps(0, 0, max_ink_mm_[k], step_mm_);
  }
  return layers;
}

Phase TexturePiece::add_tuners(TunerNetwork& network, ReducerTree& tree,
                               const std::function<ReducerNode&(int column)>& stack, const Experiment& experiment) {
  if (lookup_) throw std::logic_error("TexturePiece::add_tuners: method lookup has no tuners");
  // Error diffusion and the grid count tuners from 0: the texture comes first.
  if (network.size() != 0) throw std::logic_error("TexturePiece::add_tuners: the texture's tuners must come first");
  first_tuner_ = 0;
  for (int j = 0; j < columns_[1]; ++j) {
    for (int i = 0; i < columns_[0]; ++i) {
      const size_t k = static_cast<size_t>(j * columns_[0] + i);
      Rgb target = gamut_map_ ? mapped_[k] : image_.pixels[k];
      // The goal type accepts [0, 1]; the hull lies inside up to rounding.
      for (double& c : target) c = std::clamp(c, 0.0, 1.0);
      std::unique_ptr<Tuner> tuner = column_tuner(experiment, fmt::format("column_{}_{}", i, j), target);
      tuner->set_node(tree, stack(i + columns_[0] * j));
      network.add(std::move(tuner));
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
  std::vector<size_t> out(lookup_ ? 0 : static_cast<size_t>(column_count()));
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

std::unique_ptr<StackGridNode> TexturePiece::stack_grid(const MaterialPalette& palette,
                                                       const std::string& ground) const {
  StackGridOptions o;
  o.count = columns_;
  o.inks = inks_;
  o.stacks = stacks_.values;
  o.fill = ground;
  return std::make_unique<StackGridNode>(std::move(o), palette, "texture stack grid");
}

std::vector<std::uint32_t> TexturePiece::choose_stacks(bool diffuse) const {
  const AlbedoLookup& lookup = *lookup_table_;
  const size_t count = image_.pixels.size();
  std::vector<std::uint32_t> stacks(count);
  if (!diffuse) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t p = r.begin(); p < r.end(); ++p)
        stacks[p] = static_cast<std::uint32_t>(lookup.nearest(lookup.point(image_.pixels[p])));
    });
    return stacks;
  }
  // Serpentine Floyd–Steinberg: each column picks the stack perceptually
  // nearest (the lookup's metric: ΔE00 by default) to its gamut-mapped goal
  // plus the residuals passed to it. Residuals are passed on in linear RGB
  // by default, where neighbouring columns' light averages as the eye
  // averages it, or in CIELAB (diffusion_space); benchmarks/RESULTS.md
  // compares the two (CIELAB needs the ΔE00 metric: the lookup's own
  // space). Targets are clamped to the range (linear: [0, 1]; CIELAB: the
  // stacks' extent): a residual that no stack can absorb would otherwise
  // grow along the row.
  using Point = std::array<double, 3>;
  const int width = columns_[0], height = columns_[1];
  std::vector<Point> row_error(static_cast<size_t>(width) + 2), next_error(static_cast<size_t>(width) + 2);
  const std::array<std::array<double, 2>, 3> range =
      diffuse_in_lab_ ? lookup.extent() : std::array<std::array<double, 2>, 3>{{{0, 1}, {0, 1}, {0, 1}}};
  auto to_space = [&](const Rgb& c) { return diffuse_in_lab_ ? lookup.point(c) : c; };
  for (int y = 0; y < height; ++y) {
    std::fill(next_error.begin(), next_error.end(), Point{0, 0, 0});
    const bool forward = y % 2 == 0;
    const int step = forward ? 1 : -1;
    for (int n = 0; n < width; ++n) {
      const int x = forward ? n : width - 1 - n;
      const size_t p = static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
      Point target = to_space(gamut_map_ ? mapped_[p] : image_.pixels[p]);
      const Point& carried = row_error[static_cast<size_t>(x) + 1];
      for (int c = 0; c < 3; ++c) target[c] = std::clamp(target[c] + carried[c], range[c][0], range[c][1]);
      const size_t s = lookup.nearest(diffuse_in_lab_ ? target : lookup.point(target));
      stacks[p] = static_cast<std::uint32_t>(s);
      const Point& chosen = diffuse_in_lab_ ? lookup.stack_point(s) : lookup.colour(s);
      Point residual;
      for (int c = 0; c < 3; ++c) residual[c] = target[c] - chosen[c];
      // Weights 7 ahead, 3 behind-below, 5 below, 1 ahead-below, over the neighbours present.
      const bool ahead = x + step >= 0 && x + step < width, behind = x - step >= 0 && x - step < width;
      const bool below = y + 1 < height;
      const double total = (ahead ? 7 : 0) + (below ? 5 + (behind ? 3 : 0) + (ahead ? 1 : 0) : 0);
      if (total == 0) continue;
      auto pass = [&](std::vector<Point>& row, int column, double weight) {
        Point& e = row[static_cast<size_t>(column) + 1];
        for (int c = 0; c < 3; ++c) e[c] += residual[c] * weight / total;
      };
      if (ahead) pass(row_error, x + step, 7);
      if (below) {
        pass(next_error, x, 5);
        if (behind) pass(next_error, x - step, 3);
        if (ahead) pass(next_error, x + step, 1);
      }
    }
    std::swap(row_error, next_error);
  }
  return stacks;
}

std::vector<Rgb> TexturePiece::colours_of(const std::vector<std::uint32_t>& stacks) const {
  std::vector<Rgb> out(stacks.size());
  for (size_t p = 0; p < stacks.size(); ++p) out[p] = stacks_.colours[stacks[p]];
  return out;
}

LookupEstimate TexturePiece::lookup_estimate() const {
  const long long columns = column_count();
  return {columns, stacks_.colours.size(), lookup_seconds(columns), lookup_megabytes(columns)};
}

TextureReport TexturePiece::report(const std::vector<Rgb>& achieved) const {
  std::vector<bool> inside(outside_.size());
  for (size_t p = 0; p < inside.size(); ++p) inside[p] = !outside_[p];
  const long long out_of_gamut = std::count(outside_.begin(), outside_.end(), true);
  std::vector<double> distance;
  for (size_t p = 0; p < outside_.size(); ++p)
    if (outside_[p]) distance.push_back(ciede2000(linear_rgb_to_lab(image_.pixels[p]), linear_rgb_to_lab(mapped_[p])));
  const GamutReport gamut{
      stacks_.colours.size(), gamut_->vertex_count(), out_of_gamut,
      static_cast<double>(out_of_gamut) / static_cast<double>(std::max<size_t>(outside_.size(), 1)),
      distance.empty() ? 0.0
                       : std::accumulate(distance.begin(), distance.end(), 0.0) / static_cast<double>(distance.size())};
  const DeltaEByGamut delta{delta_e_statistics(image_.pixels, achieved),
                            delta_e_statistics(image_.pixels, achieved, inside),
                            delta_e_statistics(image_.pixels, achieved, outside_)};
  return {columns_,
          lookup_ ? "lookup" : "tuners",
          inks_,
          metric_,
          diffusion_,
          gamut_map_,
          stacks_.colours.size(),
          gamut,
          delta,
          low_pass_sigma_,
          low_pass_delta_e(image_, achieved, low_pass_sigma_)};
}

}  // namespace spec2fab

#pragma once
/// The texture piece: a picture printed with ink stacks in columns, one
/// albedo tuner per column — what the albedo translator is, and what
/// caustics_texture (and any translator that wants a picture on its print)
/// composes. Its options, tuners, phase and report are written once here;
/// below it, the pieces it is made of: the goal image resampled to the
/// columns, the printable gamut, gamut mapping for error diffusion, and the
/// ΔE00 figures reported.

#include <array>
#include <functional>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "materials/material.h"
#include "tuning/schedule.h"

namespace spec2fab {

class Experiment;
class Properties;
class ReducerNode;
class ReducerTree;
class Tuner;

/// Linear RGB pixels of a goal image, resampled to the column grid by area.
struct GoalImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  ///< row-major, row 0 at v = 0
};

/// Reads the goal image file under `key`; `columns` {0, 0} takes the image's own size.
GoalImage load_goal_image(const Properties& goal, const std::string& key, std::array<int, 2>& columns);

/// Mean ΔE00 between two images after a Gaussian low-pass in linear RGB (what
/// the eye sees from a distance: the measure error diffusion improves).
double low_pass_delta_e(const GoalImage& goal, const std::vector<Rgb>& achieved, double sigma);

/// {"mean", "p95", "max"} ΔE00 between goal and achieved colours.
nlohmann::json delta_e_statistics(const std::vector<Rgb>& goal, const std::vector<Rgb>& achieved);

/// Every stack a column can be printed with, simulated: the tuner's (discrete)
/// search space enumerated. Leaves the tuner at its last stack.
std::vector<Rgb> printable_colours(Tuner& tuner);

/// A goal colour error diffusion can reproduce on average, given the
/// printable colours `gamut` (see the definition).
Rgb gamut_map(const std::vector<Rgb>& gamut, const Rgb& pixel);

/// Column images side by side (each width × height linear RGB, row 0 at
/// v = 0 drawn on top), scaled up to about 256 px: goal | achieved | ….
void write_colour_panels(const std::vector<const std::vector<Rgb>*>& panels, int width, int height,
                         const std::filesystem::path& file);

/// Where a translator's goal keeps the texture's keys that differ between
/// translators: albedo's picture is "image", caustics_texture's "texture"
/// (its "image" is the caustic).
struct TextureKeys {
  std::string image = "image";
  std::string columns = "columns";
  std::string metric = "metric";
  std::string optimizer = "optimizer";  ///< top level of the experiment: each column's optimizer
};

class TexturePiece {
 public:
  /// Reads the texture's options from `goal`. The inks default to
  /// `default_inks`, or when that is empty to the printer's materials but
  /// `ground` and clear ones.
  TexturePiece(const Properties& goal, const Experiment& experiment, const TextureKeys& keys,
               std::vector<std::string> default_inks, const std::string& ground);
  /// The options' rows for a translator's TypeDoc.
  static std::vector<PropertyDoc> docs(const TextureKeys& keys, const std::string& default_inks);

  std::array<int, 2> columns() const { return columns_; }
  int column_count() const { return columns_[0] * columns_[1]; }
  const std::vector<std::string>& inks() const { return inks_; }
  const std::string& metric() const { return metric_; }
  const GoalImage& image() const { return image_; }
  bool diffusion() const { return diffusion_; }
  double step_mm() const { return step_mm_; }
  /// The thickest stack: every ink at its thickest.
  double ink_mm() const { return ink_mm_; }
  /// The Layered node's "layers": one per ink, from the surface down, each
  /// 0 to its thickest on the layer step.
  nlohmann::json ink_layers() const;

  /// One albedo tuner per column ("column_i_j", bound to `stack(i + nu·j)`
  /// of `tree`, the ink stack under the surface point), its goal the
  /// column's pixel (gamut-mapped when asked), added to `network` and
  /// connected as a 4-neighbour grid; they must be the network's first.
  /// Returns the phase that tunes them:
  /// serial with error diffusion, or parallel, each column on its own.
  Phase add_tuners(TunerNetwork& network, ReducerTree& tree, const std::function<ReducerNode&(int column)>& stack,
                   const Experiment& experiment);
  /// The tuners add_tuners added, in column order.
  std::vector<size_t> tuners() const;
  /// Simulated albedo of every column at its current stack.
  std::vector<Rgb> achieved(TunerNetwork& network) const;
  /// The baseline diffusion is measured against: each column's nearest stack
  /// to its own pixel. Leaves every column at the stack it had.
  std::vector<Rgb> nearest_only(TunerNetwork& network) const;
  /// result.json: columns, inks, metric, error_diffusion, gamut_map,
  /// printable_stacks, delta_e00, low_pass_sigma_px, low_pass_delta_e00.
  nlohmann::json report(const std::vector<Rgb>& achieved) const;

 private:
  std::array<int, 2> columns_{0, 0};
  GoalImage image_;
  std::vector<std::string> inks_;
  std::vector<double> max_ink_mm_;
  double step_mm_ = 0.027, ink_mm_ = 0, low_pass_sigma_ = 1.5;
  std::string metric_;
  bool diffusion_ = true, gamut_map_ = true;
  nlohmann::json optimizer_;
  std::vector<Rgb> gamut_;  ///< albedo of every printable stack
  size_t first_tuner_ = 0;
};

}  // namespace spec2fab

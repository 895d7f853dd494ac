#pragma once
/// The texture piece: a picture printed with ink stacks in columns, one
/// albedo tuner per column — what the albedo translator is, and what
/// caustics_texture (and any translator that wants a picture on its print)
/// composes. Its options, tuners, phase and report are written once here;
/// below it, the pieces it is made of: the goal image resampled to the
/// columns, the printable gamut, gamut mapping for error diffusion, and the
/// ΔE00 figures reported.

#include <array>
#include <filesystem>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/options.h"
#include "core/registry.h"
#include "core/report.h"
#include "materials/material.h"
#include "reducer/nodes/nodes.h"
#include "reducer/nodes/stack_grid.h"
#include "spec/surface_columns.h"
#include "tuning/optimizer.h"
#include "tuning/schedule.h"

namespace spec2fab {

class Experiment;
struct PrinterProfile;
class Properties;
class Solid;
struct Mesh;
class RunFolder;
class AlbedoLookup;
class PrintableGamut;
class ReducerNode;
class ReducerTree;
class Tuner;

/// Linear RGB pixels of a goal image, resampled to the column grid by area.
struct GoalImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  ///< row-major, row 0 at v = 0
};

/// Reads the goal image file under `key`, decodes sRGB to linear and then
/// resamples it to `columns` (by area when shrinking, bilinearly when
/// enlarging); `columns` {0, 0} takes the image's own size.
GoalImage load_goal_image(const Properties& goal, const std::string& key, std::array<int, 2>& columns,
                          const Limits& limits);

/// Columns over the surface's (u, v) ∈ [0, 1]² about one printer voxel wide
/// (the coarser lateral axis): the mean length of the surface per unit u
/// and per unit v, weighted by area, over the voxel.
std::array<int, 2> printer_resolution_columns(const Solid& solid, const PrinterProfile& printer);

/// Mean ΔE00 between two images after a Gaussian low-pass in linear RGB (what
/// the eye sees from a distance: the measure error diffusion improves).
double low_pass_delta_e(const GoalImage& goal, const std::vector<Rgb>& achieved, double sigma);

/// ΔE00 between goal and achieved colours over some pixels (result.json).
struct DeltaE {
  std::size_t pixels = 0;
  std::optional<double> mean, p95, max;  ///< absent over no pixels
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.pixels, "pixels", "pixels compared");
    f(s.mean, "mean", "mean ΔE00");
    f(s.p95, "p95", "95th percentile");
    f(s.max, "max", "largest");
  }
};

/// Over all pixels, and over those whose goal is in or out of the gamut.
struct DeltaEByGamut {
  DeltaE all;
  DeltaE in_gamut, out_of_gamut;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.all, "", "over all pixels");
    f(s.in_gamut, "in_gamut", "over pixels whose goal is printable");
    f(s.out_of_gamut, "out_of_gamut", "over pixels whose goal lies outside the printable gamut");
  }
};

/// ΔE00 between goal and achieved colours over the pixels `where` marks
/// (all when empty).
DeltaE delta_e_statistics(const std::vector<Rgb>& goal, const std::vector<Rgb>& achieved,
                          const std::vector<bool>& where = {});

/// The goal's share outside the printable gamut.
struct GamutReport {
  std::size_t printable_stacks = 0, hull_vertices = 0;
  long long goal_pixels_outside = 0;
  double goal_fraction_outside = 0, mean_delta_e00_outside_to_gamut = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.printable_stacks, "printable_stacks", "stacks the inks can print");
    f(s.hull_vertices, "hull_vertices", "vertices of their colours' convex hull (in Lab)");
    f(s.goal_pixels_outside, "goal_pixels_outside", "goal pixels outside it");
    f(s.goal_fraction_outside, "goal_fraction_outside", "their share");
    f(s.mean_delta_e00_outside_to_gamut, "mean_delta_e00_outside_to_gamut",
      "mean ΔE00 from those pixels to where the gamut map moved them");
  }
};

/// What the lookup costs.
struct LookupEstimate {
  long long columns = 0;
  std::size_t printable_stacks = 0;
  double seconds = 0, megabytes = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.columns, "columns", "columns looked up");
    f(s.printable_stacks, "printable_stacks", "stacks each is chosen from");
    f(s.seconds, "seconds", "estimated time");
    f(s.megabytes, "megabytes", "estimated memory");
  }
};

/// A texture's figures in result.json (TexturePiece::report).
struct TextureReport {
  std::array<int, 2> columns{};
  std::string method;
  std::vector<std::string> inks;
  std::string metric;
  bool error_diffusion = false, gamut_map = false;
  std::size_t printable_stacks = 0;
  GamutReport gamut;
  DeltaEByGamut delta_e00;
  double low_pass_sigma_px = 0, low_pass_delta_e00 = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.columns, "columns", "columns along u and v");
    f(s.method, "method", "tuners, or lookup");
    f(s.inks, "inks", "the inks, from the surface down");
    f(s.metric, "metric", "the colour metric");
    f(s.error_diffusion, "error_diffusion", "whether errors were diffused to neighbouring columns");
    f(s.gamut_map, "gamut_map", "whether goals were moved into the printable gamut");
    f(s.printable_stacks, "printable_stacks", "stacks the inks can print");
    f(s.gamut, "gamut", "the goal against the printable gamut");
    f(s.delta_e00, "delta_e00", "ΔE00 between goal and achieved");
    f(s.low_pass_sigma_px, "low_pass_sigma_px", "blur of the low-pass error, in columns");
    f(s.low_pass_delta_e00, "low_pass_delta_e00", "mean ΔE00 after the blur (what the eye sees from afar)");
  }
};

/// Every stack a column can be printed with: the values of the tuner's
/// (discrete) search space, first axis fastest, and each one's simulated
/// colour. Leaves the tuner at its last stack.
struct PrintableStacks {
  std::vector<std::vector<double>> values;
  std::vector<Rgb> colours;
};
PrintableStacks printable_stacks(Tuner& tuner);

/// Column images side by side (each width × height linear RGB, row 0 at
/// v = 0 drawn on top, or at the bottom with `highest_v_on_top`), scaled up
/// to about 256 px: goal | achieved | ….
void write_colour_panels(const std::vector<const std::vector<Rgb>*>& panels, int width, int height,
                         const std::filesystem::path& file, bool highest_v_on_top = false);

/// Where a translator's goal keeps the texture's keys that differ between
/// translators: albedo's picture is "image", caustics_texture's "texture"
/// (its "image" is the caustic).
struct TextureKeys {
  std::string image = "image";
  std::string columns = "columns";
  std::string metric = "metric";
  std::string optimizer = "optimizer";  ///< top level of the experiment: each column's optimizer
};

/// "max_ink_mm": one thickness for every ink, or one each (a bright
/// texture needs a thicker white than its colours do).
struct InkThickness {
  std::vector<double> mm;  ///< empty: 5 layer steps each
  bool per_ink = false;
  template <class Context>
  void read(const Properties& goal, const char* name, const Context&) {
    if (!goal.has(name)) return;
    per_ink = goal.peek(name).is_array();
    mm = per_ink ? goal.get<std::vector<double>>(name) : std::vector<double>{goal.get<double>(name)};
  }
  std::string type_text() const { return "number or array of numbers (mm)"; }
  std::string default_text() const { return "5 layer steps"; }
};

/// The texture's goal keys, declared once; a translator renames some
/// (`keys`) and gives its own default inks.
struct TextureOptions {
  TextureKeys keys;
  std::vector<std::string> default_inks;  ///< empty: the printer's materials but the ground and clear ones
  std::string default_inks_text = "the printer's materials but the backing and clear ones";

  std::filesystem::path image;
  std::array<int, 2> columns{0, 0};
  std::optional<std::vector<std::string>> inks;
  double layer_step_mm = kUnset;
  InkThickness max_ink_mm;
  std::string metric = "ciede2000";
  bool error_diffusion = true;
  std::optional<bool> gamut_map;
  double low_pass_sigma_px = 1.5;
  /// Offered by a translator whose tree can hold a stack grid (albedo).
  bool offers_lookup = false;
  std::string method = "lookup";
  std::string diffusion_space = "linear";
  double max_columns = 16e6;
  /// Set by a translator, not read: the picture's top row goes to the
  /// highest v, so that it reads right seen from +w looking down on (u, v)
  /// (row 0 at v = 0 reads right from −w, through the part).
  bool top_row_at_highest_v = false;

  TextureOptions() = default;
  TextureOptions(TextureKeys renamed, std::vector<std::string> inks_by_default);

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.file(o.image, o.keys.image.c_str(), "the picture (sRGB PNG/JPEG), row 0 at v = 0");
    if (o.offers_lookup) {
      d.choice(o.method, "method", {"lookup", "tuners"},
               "lookup: every column's stack from the printable stacks' precomputed colours (k-d tree, error "
               "diffusion in CIELAB), at photograph scale; tuners: one albedo tuner per column on the paper's "
               "network (any optimizer; exhaustive search is the reference)");
      d.number(o.columns, o.keys.columns.c_str(), Range::at_least(1),
               "columns over (u, v); the image is resampled onto them",
               Default{"lookup: one per printer voxel of the surface; tuners: the image's size"});
      d.choice(o.diffusion_space, "diffusion_space", {"linear", "lab"},
               "lookup: where residuals are passed on — linear RGB (light, as the eye averages it) or CIELAB");
      d.number(o.max_columns, "max_columns", Range::at_least(1),
               "refuse a lookup over more columns (the estimate of time and memory is printed first)");
    } else {
      d.number(o.columns, o.keys.columns.c_str(), Range::at_least(1),
               "columns over (u, v); the image is resampled onto them", Default{"the image's size"});
    }
    d.value(o.inks, "inks", "one layer each, in this order from the surface down",
            Default{o.default_inks_text.c_str()});
    d.number(o.layer_step_mm, "layer_step_mm", Range::closed(1e-3, 10), "thickness step of each ink layer",
             Default{"the printer's layer"});
    d.custom(o.max_ink_mm, "max_ink_mm", "thickest layer, one for all inks or one per ink (at least one step)");
    d.choice(o.metric, o.keys.metric.c_str(), {"ciede2000", "rgb_mse"}, "the albedo metric");
    d.value(o.error_diffusion, "error_diffusion",
            "diffuse residuals (serial raster); false: nearest stack per column, in parallel");
    d.value(o.gamut_map, "gamut_map",
            "first move each goal colour into the convex hull of the printable stacks' colours (what diffusion can "
            "mix)",
            Default{"= error_diffusion"});
    d.number(o.low_pass_sigma_px, "low_pass_sigma_px", Range::closed(0.1, 100),
             "blur (in columns) of the low-pass error in result.json");
  }
  bool lookup() const { return offers_lookup && method == "lookup"; }
  bool check(std::string* why) const {
    if (lookup() || static_cast<long long>(columns[0]) * columns[1] <= kMostTunedColumns) return true;
    *why = keys.columns + ": more than a million columns" + (offers_lookup ? " for tuners (method lookup takes more)" : "");
    return false;
  }
};

class TexturePiece {
 public:
  /// Reads the texture's options from `goal` (`options` holds their names
  /// and default inks); `ground` is what the inks lie on, checked against
  /// the palette at `ground_key` of the goal when one is given.
  TexturePiece(const Properties& goal, const Experiment& experiment, TextureOptions options,
               const std::string& ground, const char* ground_key = nullptr);
  /// The options' rows for a translator's TypeDoc, the optimizer's included.
  static std::vector<PropertyDoc> docs(const TextureOptions& options);

  std::array<int, 2> columns() const { return columns_; }
  long long column_count() const { return static_cast<long long>(columns_[0]) * columns_[1]; }
  const std::vector<std::string>& inks() const { return inks_; }
  const std::string& metric() const { return metric_; }
  /// The goal, in column order (column row 0 at v = 0).
  const GoalImage& image() const { return image_; }
  /// Column images (goal, achieved, …) side by side, drawn as the picture reads.
  void write_preview(const std::vector<const std::vector<Rgb>*>& panels, const std::filesystem::path& file) const {
    write_colour_panels(panels, columns_[0], columns_[1], file, top_row_at_highest_v_);
  }
  /// The look for report.html's 3D view: the solid's mesh with its surface
  /// coordinates (preview/look.obj: the mesh's own, or the solid's
  /// projection at each corner when it projects) and the colours `achieved` in them
  /// (preview/look.png, at most 1024 px a side). Nothing for a mesh of more
  /// than 200,000 triangles (the page's limit).
  void write_look(const std::vector<Rgb>& achieved, const Solid& solid, const RunFolder& folder) const;
  bool diffusion() const { return diffusion_; }
  double step_mm() const { return step_mm_; }
  /// The thickest stack: every ink at its thickest.
  double ink_mm() const { return ink_mm_; }
  /// The stratum that holds the thickest stack and one step of ground under
  /// it (ink_mm() + step_mm(), checked when the inks are read).
  const Parameter& shell_depth() const { return shell_depth_; }
  /// The Layered node's layers: one per ink, from the surface down, each
  /// 0 to its thickest on the layer step.
  std::vector<LayeredOptions::Layer> ink_layers(const MaterialPalette& palette) const;

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

  /// Method "lookup": no tuners; the stack grid node (reducer/nodes/stack_grid.h)
  /// holds every column, `ground` below the inks.
  bool lookup() const { return lookup_; }
  std::unique_ptr<StackGridNode> stack_grid(const MaterialPalette& palette, const std::string& ground) const;
  /// Every column's stack from the lookup: error diffusion in the lookup's
  /// space (serpentine Floyd–Steinberg) over gamut-mapped goals when
  /// `diffuse`, else each column's nearest stack to its own pixel.
  std::vector<std::uint32_t> choose_stacks(bool diffuse) const;
  /// The simulated colour of each column's stack.
  std::vector<Rgb> colours_of(const std::vector<std::uint32_t>& stacks) const;
  /// What the lookup will cost, as the log line printed before it and the
  /// figures result.json keeps.
  LookupEstimate lookup_estimate() const;
  /// Simulated albedo of every column at its current stack.
  std::vector<Rgb> achieved(TunerNetwork& network) const;
  /// The baseline diffusion is measured against: each column's nearest stack
  /// to its own pixel. Leaves every column at the stack it had.
  std::vector<Rgb> nearest_only(TunerNetwork& network) const;
  /// The figures result.json keeps of the texture `achieved`.
  TextureReport report(const std::vector<Rgb>& achieved) const;
  /// The printable stacks' simulated colours (stack k as in stack_grid).
  const std::vector<Rgb>& printable_colours() const { return stacks_.colours; }

 private:
  /// The columns (the goal image's pixels, or the printer's resolution for
  /// the lookup) and the goal image, in column order.
  void read_columns(const Properties& goal, const Experiment& experiment, const TextureOptions& o);
  /// The inks (given, the translator's, or the printer's opaque model
  /// materials but the ground) and each one's thickest layer.
  void read_inks(const Properties& goal, const Experiment& experiment, const TextureOptions& o,
                 const std::string& ground);
  /// Every printable stack simulated once (the lookup's table, the gamut,
  /// what a column tuner searches), and each goal pixel moved into the gamut.
  void map_into_printable_gamut(const Properties& goal, const Experiment& experiment, const std::string& ground);
  /// A column's albedo tuner, its goal `target`, not yet bound to a node.
  std::unique_ptr<Tuner> column_tuner(const Experiment& experiment, const std::string& name, const Rgb& target) const;

  std::array<int, 2> columns_{0, 0};
  GoalImage image_;
  bool top_row_at_highest_v_ = false;
  std::vector<std::string> inks_;
  std::vector<double> max_ink_mm_;
  double step_mm_ = 0.027, ink_mm_ = 0, low_pass_sigma_ = 1.5;
  Parameter shell_depth_ = StratumOptions{}.depth_mm;
  std::string metric_;
  bool diffusion_ = true, gamut_map_ = true, lookup_ = false, diffuse_in_lab_ = false;
  std::optional<OptimizerChoice> optimizer_;
  PrintableStacks stacks_;  ///< every printable stack and its albedo
  std::shared_ptr<const AlbedoLookup> lookup_table_;
  std::shared_ptr<const PrintableGamut> gamut_;
  std::vector<Rgb> mapped_;     ///< each column's goal moved into the gamut
  std::vector<bool> outside_;   ///< whether the column's goal lies outside it
  size_t first_tuner_ = 0;
};

}  // namespace spec2fab

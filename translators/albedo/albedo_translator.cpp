// The albedo translator (paper §7.1, Fig. 7): a print whose surface colour
// matches a goal image. Stratum (shell) → Column (one column per image pixel
// over the surface's (u, v)) → Layered (one layer per ink, thicknesses on the
// printer's layer step, over the backing material). One tuner per column
// picks the stack whose simulated albedo is closest to its pixel; the tuners
// sit on a 4-neighbour network and, in a serial raster schedule, pass their
// colour residual on with Floyd–Steinberg weights (error diffusion), as the
// paper did. The albedo simulator tabulates every stacking once.

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/colour.h"
#include "texture_goal.h"
#include "reducer/reducer_tree.h"
#include "spec/surface_columns.h"
#include "spec/translator.h"
#include "spec/tree_outputs.h"
#include "spec/tuning_outputs.h"
#include "tuning/schedule.h"

namespace spec2fab {
namespace {

class AlbedoTranslator final : public Translator {
 public:
  AlbedoTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    const MaterialPalette& palette = experiment.palette();
    const PrinterProfile& printer = experiment.printer();
    columns_ = goal.get<std::array<int, 2>>("columns", {0, 0});
    if (columns_[0] < 0 || columns_[1] < 0 || (columns_[0] == 0) != (columns_[1] == 0)) {
      goal.fail("columns", "give two positive counts, or leave out for the image's size");
    }
    image_ = load_goal_image(goal, "image", columns_);
    const std::string backing = goal.get<std::string>("backing", "VeroWhitePlus");
    palette.id(backing, goal.where("backing"));
    std::vector<std::string> inks;
    if (goal.has("inks")) {
      inks = goal.get<std::vector<std::string>>("inks");
      for (const std::string& ink : inks) palette.id(ink, goal.where("inks"));
    } else {
      for (const std::string& m : printer.model_materials) {
        if (m != backing && palette.material(palette.id(m, goal.where())).kind != "transparent") inks.push_back(m);
      }
    }
    if (inks.empty()) goal.fail("inks", "no ink besides the backing");
    const double step = goal.get_in_range("layer_step_mm", printer.layer_mm, 1e-3, 10);
    const double max_ink = goal.get_in_range("max_ink_mm", 5 * step, 0, 10);
    const double shell = static_cast<double>(inks.size()) * max_ink + step;
    metric_ = goal.get<std::string>("metric", "ciede2000");
    diffusion_ = goal.get<bool>("error_diffusion", true);
    low_pass_sigma_ = goal.get_in_range("low_pass_sigma_px", 1.5, 0.1, 100);

    nlohmann::json layers = nlohmann::json::array();
    for (const std::string& ink : inks) {
      layers.push_back({{"material", ink},
                        {"thickness_mm", {{"value", 0.0}, {"min", 0.0}, {"max", max_ink}, {"step", step}}}});
    }
    tree_ = build_surface_column_tree(experiment, shell, columns_, std::move(layers), backing, "albedo");
    outputs_ = TreeOutputOptions::read(goal, experiment, *tree_);

    const nlohmann::json optimizer =
        experiment.optimizer_or(nlohmann::json{{"type", "exhaustive"}});
    const PartContext context{palette, &experiment.cache()};
    auto make_tuner = [&](int i, int j, const Rgb& target) {
      const nlohmann::json parts = {
          {"simulator", {{"type", "albedo"}, {"depth_mm", shell}, {"step_mm", step / 8}}},
          {"metric", {{"type", metric_}}},
          {"goal", {{"type", "albedo"}, {"linear_rgb", target}}},
          {"optimizer", optimizer}};
      auto tuner = build_tuner(Properties::wrap(parts, experiment.file().string() + " (tuner)"),
                               fmt::format("column_{}_{}", i, j), context);
      tuner->set_node(*tree_, tree_->node("shell/" + std::to_string(i + columns_[0] * j)));
      return tuner;
    };
    gamut_ = printable_colours(*make_tuner(0, 0, {0.5, 0.5, 0.5}));
    gamut_map_ = goal.get<bool>("gamut_map", diffusion_);
    for (int j = 0; j < columns_[1]; ++j) {
      for (int i = 0; i < columns_[0]; ++i) {
        const Rgb& pixel = image_.pixels[static_cast<size_t>(j * columns_[0] + i)];
        Rgb target = gamut_map_ ? gamut_map(gamut_, pixel) : pixel;
        // The goal type accepts [0, 1]; the hull lies inside up to rounding.
        for (double& c : target) c = std::clamp(c, 0.0, 1.0);
        network_.add(make_tuner(i, j, target));
      }
    }
    network_.connect_grid(columns_[0], columns_[1], 4);
    Phase phase;
    phase.name = diffusion_ ? "error_diffusion" : "nearest";
    phase.mode = diffusion_ ? Phase::Mode::serial : Phase::Mode::parallel;
    // Albedos lie in [0, 1]; clamping the diffused targets there keeps
    // out-of-gamut regions (deep ocean blue) from winding residuals up.
    if (diffusion_) phase.coupling = std::make_shared<ErrorDiffusion>(columns_[0], std::pair{0.0, 1.0});
    schedule_.add(std::move(phase));
    inks_ = inks;
  }

  std::string summary() const override {
    return fmt::format(
        "albedo: {} x {} columns over the surface, each {} ink layer(s) ({}) over the backing; "
        "one tuner per column ({}), {}",
        columns_[0], columns_[1], inks_.size(), fmt::join(inks_, ", "), metric_,
        diffusion_ ? "errors diffused in raster order" : "nearest stack per column");
  }

  const ReducerTree& tree() const override { return *tree_; }

  void run(RunContext& context) override {
    const RunRecord record = schedule_.run(network_, context.seed);
    std::vector<Rgb> achieved = simulated_albedos();
    // The baseline: each column's nearest stack alone, without diffusion.
    std::vector<std::vector<double>> chosen;
    for (size_t t = 0; t < network_.size(); ++t) chosen.push_back(network_.tuner(t).search_space().values());
    std::vector<Rgb> nearest;
    if (diffusion_) {
      for (size_t t = 0; t < network_.size(); ++t) {
        Tuner& tuner = network_.tuner(t);
        const Rgb& pixel = image_.pixels[t];
        std::copy(pixel.begin(), pixel.end(), tuner.effective_target().values().begin());
        tuner.tune();
      }
      nearest = simulated_albedos();
      for (size_t t = 0; t < network_.size(); ++t) network_.tuner(t).error_at(chosen[t]);
    } else {
      nearest = achieved;
    }
    tree_->evaluate();

    context.result["albedo"] = {
        {"columns", columns_},
        {"inks", inks_},
        {"metric", metric_},
        {"error_diffusion", diffusion_},
        {"gamut_map", gamut_map_},
        {"printable_stacks", gamut_.size()},
        {"delta_e00", delta_e_statistics(image_.pixels, achieved)},
        {"delta_e00_nearest_only", delta_e_statistics(image_.pixels, nearest)},
        {"low_pass_sigma_px", low_pass_sigma_},
        {"low_pass_delta_e00", low_pass_delta_e(image_, achieved, low_pass_sigma_)},
        {"low_pass_delta_e00_nearest_only", low_pass_delta_e(image_, nearest, low_pass_sigma_)}};
    write_tuning_outputs(record, network_, context);
    write_colour_panels({&image_.pixels, &achieved, &nearest}, columns_[0], columns_[1],
                        context.folder.path("preview/goal_vs_achieved.png"));
    context.result["files"] = {{"previews", {"preview/convergence.png", "preview/goal_vs_achieved.png"}}};
    write_tree_outputs(*tree_, outputs_, context);
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Spatially varying albedo (paper Fig. 7): a goal image over the surface's (u, v); "
        "Stratum -> Column (one per pixel) -> Layered (one layer per ink over the backing), one "
        "tuner per column with error diffusion over a 4-neighbour network.",
        {{"goal.image", "file", "required", "goal colours (sRGB PNG/JPEG), row 0 at v = 0"},
         {"goal.columns", "[nu, nv]", "the image's size", "columns over (u, v); the image is resampled by area"},
         {"goal.inks", "[materials]", "printer materials but backing and clear", "one layer each, in this order from the surface"},
         {"goal.backing", "material", "VeroWhitePlus", "below the inks and in the core"},
         {"goal.layer_step_mm", "number (mm)", "the printer's layer", "thickness step of each ink layer"},
         {"goal.max_ink_mm", "number (mm)", "5 steps", "thickest layer of one ink"},
         {"goal.metric", "name", "ciede2000", "ciede2000 or rgb_mse"},
         {"goal.error_diffusion", "bool", "true", "diffuse residuals (serial raster); false: nearest stack per column, in parallel"},
         {"goal.gamut_map", "bool", "= error_diffusion", "first move each goal colour into the convex hull of the printable stacks' colours (what diffusion can mix)"},
         {"goal.low_pass_sigma_px", "number", "1.5", "blur (in columns) of the low-pass error in result.json"},
         {"optimizer", "object", "{\"type\": \"exhaustive\"}", "each column's optimizer"}},
        R"({"translator": "albedo", "goal": {"image": "../images/earth_96x48.png"}})"};
    for (PropertyDoc& d : TreeOutputOptions::docs()) doc.properties.push_back(std::move(d));
    return doc;
  }

 private:
  std::vector<Rgb> simulated_albedos() {
    std::vector<Rgb> out;
    for (size_t t = 0; t < network_.size(); ++t) {
      Tuner& tuner = network_.tuner(t);
      tuner.error();  // simulates at the current parameters
      out.push_back(static_cast<const AlbedoObservation&>(tuner.simulated()).rgb);
    }
    return out;
  }

  std::array<int, 2> columns_{0, 0};
  GoalImage image_;
  std::vector<std::string> inks_;
  std::string metric_;
  bool diffusion_ = true;
  bool gamut_map_ = true;
  std::vector<Rgb> gamut_;  ///< albedo of every printable stack
  double low_pass_sigma_ = 1.5;
  std::unique_ptr<ReducerTree> tree_;
  TreeOutputOptions outputs_;
  TunerNetwork network_;
  Schedule schedule_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::AlbedoTranslator, "albedo")

// The subsurface translator (paper §7.2, Fig. 8, after Hašan et al. 2010):
// a print whose translucency — the radial reflectance profile R(r) at each
// surface point — matches goal profiles. The same tree as the albedo
// translator: Stratum (shell) → Column (one per goal point over the
// surface's (u, v)) → Layered, here with four layers of tunable material and
// thickness over a backing. One tuner per column, independent, run in
// parallel; each searches its stacks by branch and bound with the profile
// bound of subsurface/stack_bound.h. The goal: a chessboard of two measured
// media (Jensen et al. 2001), one profile per column.

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "spec/report_fields.h"
#include "core/colour.h"
#include "core/image_write.h"
#include "core/distance.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/surface_columns.h"
#include "spec/tuning_translator.h"
#include "subsurface/stack_bound.h"
#include "subsurface/subsurface_parts.h"
#include "tuning/schedule.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// One layer of a column's tuned stack.
struct StackLayer {
  std::string material;
  double thickness_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.material, "material", "its material");
    f(s.thickness_mm, "thickness_mm", "its thickness");
  }
};

/// A column's tuned stack, from the surface down.
struct ColumnStack {
  std::string tuner;
  std::vector<StackLayer> layers;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.tuner, "tuner", "the column's tuner");
    f(s.layers, "layers", "its layers, from the surface down");
  }
};

/// How much of the exhaustive search branch and bound spared.
struct BranchAndBoundCounts {
  double exhaustive_candidates_per_column = 0;
  long long leaves_evaluated_total = 0;
  Spread fraction_of_exhaustive;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.exhaustive_candidates_per_column, "exhaustive_candidates_per_column", "stacks an exhaustive search tries");
    f(s.leaves_evaluated_total, "leaves_evaluated_total", "stacks branch and bound simulated, all columns");
    f(s.fraction_of_exhaustive, "fraction_of_exhaustive", "per column, their share of the exhaustive search");
  }
};

/// result.json "subsurface".
struct SubsurfaceReport {
  std::array<int, 2> columns{}, squares{};
  std::vector<std::string> media;
  int layers = 0;
  std::vector<std::string> materials;
  std::vector<double> thickness_mm;
  std::string backing;
  double profile_radius_mm = 0;
  int profile_samples = 0;
  Spread profile_rms_per_mm2, profile_relative_rms, profile_l2;
  BranchAndBoundCounts branch_and_bound;
  std::vector<ColumnStack> stacks;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.columns, "columns", "columns along u and v");
    f(s.squares, "squares", "chessboard squares along u and v");
    f(s.media, "media", "the two measured media");
    f(s.layers, "layers", "layers per column");
    f(s.materials, "materials", "the materials a layer chooses from");
    f(s.thickness_mm, "thickness_mm", "the thicknesses a layer chooses from");
    f(s.backing, "backing", "the material under the layers");
    f(s.profile_radius_mm, "profile_radius_mm", "radius of the reflectance profiles");
    f(s.profile_samples, "profile_samples", "their samples");
    f(s.profile_rms_per_mm2, "profile_rms_per_mm2", "per column, RMS of achieved minus goal profile");
    f(s.profile_relative_rms, "profile_relative_rms", "that relative to the goal's RMS");
    f(s.profile_l2, "profile_l2", "per column, the tuner's final error");
    f(s.branch_and_bound, "branch_and_bound", "the search's savings");
    f(s.stacks, "stacks", "each column's tuned stack");
  }
};

class SubsurfaceTranslator final : public TuningTranslator {
 public:
  // "media": the chessboard's two media.
  struct ChessboardMedia {
    std::vector<MeasuredMedium> media;
    template <class Context>
    void read(const Properties& goal, const char* name, const Context&) {
      const nlohmann::json& given = goal.peek(name);
      if (!given.is_array() || given.size() != 2) goal.fail(name, "give the chessboard's two media");
      for (size_t i = 0; i < 2; ++i) {
        const std::string where = goal.where(name) + "/" + std::to_string(i);
        if (given[i].is_string()) media.push_back(medium_named(given[i].get<std::string>(), where));
        else media.push_back(read_medium_coefficients(goal.element_object(name, i), "medium"));
      }
    }
    std::string type_text() const { return "[medium, medium]"; }
    std::string default_text() const { return "required"; }
  };

  struct Options {
    ChessboardMedia media;
    std::array<int, 2> columns{10, 10}, squares{0, 0};
    int layers = 4;
    std::optional<std::vector<std::string>> materials;
    std::vector<int> thickness_steps{5, 10, 20, 40};
    double layer_step_mm = kUnset;
    std::string backing = "VeroWhitePlus";
    ProfileGrid grid;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.custom(o.media, "media", std::string("the chessboard's two media, each ").append(kMediumMeaning).c_str());
      d.number(o.columns, "columns", Range::at_least(1), "columns (goal profiles) over (u, v)");
      d.number(o.squares, "squares", Range::at_least(1), "chessboard squares over (u, v)", Default{"= columns"});
      d.number(o.layers, "layers", Range::closed(1, 8), "layers per column");
      d.value(o.materials, "materials", "what each layer may be", Default{"the printer's model materials"});
      d.number(o.thickness_steps, "thickness_steps", Range::at_least(1),
               "what each layer's thickness may be, in layer steps");
      d.number(o.layer_step_mm, "layer_step_mm", Range::closed(1e-3, 10), "the thickness step",
               Default{"the printer's layer"});
      d.value(o.backing, "backing", "material below the layers and in the core");
      ProfileGrid::declare(d, o.grid);
    }
    bool check(std::string* why) const {
      // Unchecked, a count past 16 million reached the Column node, which
      // refuses it as the translator's bug (an internal error).
      if (static_cast<long long>(columns[0]) * columns[1] > kMostTunedColumns)
        *why = fmt::format("columns: {} x {} is more than a million columns, each a tuner of its own", columns[0], columns[1]);
      else if (thickness_steps.empty()) *why = "thickness_steps: no thickness to choose from";
      else if (materials && materials->empty()) *why = "materials: no material to stack";
      else return true;
      return false;
    }
  };

  SubsurfaceTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    const MaterialPalette& palette = experiment.palette();
    const PrinterProfile& printer = experiment.printer();
    Options o = read_options<Options>(goal);
    columns_ = o.columns;
    squares_ = o.squares[0] == 0 ? columns_ : o.squares;
    media_ = std::move(o.media.media);
    grid_ = o.grid;
    layer_count_ = o.layers;
    backing_ = o.backing;
    palette.id(backing_, goal.where("backing"));
    materials_ = o.materials.value_or(printer.model_materials);
    for (const std::string& m : materials_) palette.id(m, goal.where("materials"));
    step_mm_ = std::isnan(o.layer_step_mm) ? printer.layer_mm : o.layer_step_mm;
    thickness_steps_ = o.thickness_steps;
    std::sort(thickness_steps_.begin(), thickness_steps_.end());
    const double thickest = thickness_steps_.back() * step_mm_;
    const double shell = layer_count_ * thickest + step_mm_;
    // The columns hang in a stratum (at most 1000 mm deep).
    const Parameter shell_depth = stratum_depth(
        shell, goal.where("thickness_steps"),
        fmt::format("{} layers of up to {:g} mm and a step of {}", layer_count_, thickest, backing_));

    // The tree: the albedo translator's, with material and thickness free in every layer.
    std::vector<double> thicknesses;
    for (int s : thickness_steps_) thicknesses.push_back(s * step_mm_);
    std::vector<LayeredOptions::Layer> layers(static_cast<size_t>(layer_count_));
    for (LayeredOptions::Layer& layer : layers) {
      layer.material.parameter = material_choice(palette, materials_.front(), materials_, goal.where("materials"));
      layer.thickness_mm = number_choice(thicknesses.front(), thicknesses);
    }
    SurfaceColumnTree surface_tree =
        surface_column_tree(shell_depth, columns_, std::move(layers), fixed_material(palette, backing_, goal.where("backing")),
                            experiment.limits());
    set_tree(std::move(surface_tree.root), goal, experiment);

    SubsurfaceSimulatorOptions simulator;
    simulator.grid = grid_;
    simulator.depth_mm = shell;
    simulator.step_mm = step_mm_;
    model_ = LayerStackModel::shared(palette, grid_.basis(&experiment.cache()), step_mm_, &experiment.cache());
    std::vector<LayerOptions> options(static_cast<size_t>(layer_count_));
    for (LayerOptions& o : options) {
      for (const std::string& m : materials_) o.materials.push_back(palette.id(m, goal.where("materials")));
      o.steps = thickness_steps_;
    }
    bound_ = std::make_shared<StackBound>(model_, options, palette.id(backing_, goal.where("backing")));
    const OptimizerChoice optimizer(experiment.root(), "optimizer",
                                    {{"type", "branch_and_bound"}, {"value_order", "best_bound_first"}});
    const PartContext context = experiment.part_context();
    for (int j = 0; j < columns_[1]; ++j) {
      for (int i = 0; i < columns_[0]; ++i) {
        auto tuner = make_tuner(fmt::format("column_{}_{}", i, j), make_subsurface_simulator(simulator, context),
                                make_profile_l2(),
                                make_radial_profile_goal(media_[square_medium(i, j)], grid_, &experiment.cache()),
                                optimizer.build());
        tuner->set_origin(goal.where());
        tuner->set_node(*tree_, surface_tree.column(static_cast<size_t>(i + columns_[0] * j)));
        tuner->set_lower_bound([bound = bound_](std::span<const double> x, int assigned, const Observation& target) {
          return bound->lower_bound(x, assigned, static_cast<const RadialProfileObservation&>(target));
        });
        network_.add(std::move(tuner));
      }
    }
    Phase phase;
    phase.name = "independent_columns";
    phase.mode = Phase::Mode::parallel;
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    return fmt::format(
        "subsurface: {} x {} columns over the surface, a chessboard of {} and {}; each column {} "
        "layer(s) of {} material(s) x {} thickness(es) over {}; independent tuners (profile_l2)",
        columns_[0], columns_[1], media_[0].name, media_[1].name, layer_count_, materials_.size(),
        thickness_steps_.size(), backing_);
  }

  void report(const RunRecord& record, RunContext& context) override {
    const double candidates =
        std::pow(static_cast<double>(materials_.size() * thickness_steps_.size()), layer_count_);
    std::vector<double> column_rms, relative_rms, fractions, errors;
    long long leaves = 0;
    for (const TunerRun& run : record.runs) {
      const double evaluated = run.summary.details.value("leaves_evaluated", static_cast<double>(run.summary.evaluations));
      fractions.push_back(evaluated / candidates);
      leaves += static_cast<long long>(evaluated);
    }
    SubsurfaceReport report;
    for (size_t t = 0; t < network_.size(); ++t) {
      Tuner& tuner = network_.tuner(t);
      errors.push_back(tuner.error());
      const auto& simulated = static_cast<const RadialProfileObservation&>(tuner.simulated());
      const auto& target = static_cast<const RadialProfileObservation&>(tuner.goal().target());
      const std::vector<double> s = simulated.samples(), g = target.samples();
      column_rms.push_back(rms_difference(s, g));
      relative_rms.push_back(column_rms.back() / root_mean_square(g));
      report.stacks.push_back(stack_of(tuner));
    }
    report.columns = columns_;
    report.squares = squares_;
    report.media = {media_[0].name, media_[1].name};
    report.layers = layer_count_;
    report.materials = materials_;
    report.thickness_mm = thickness_list();
    report.backing = backing_;
    report.profile_radius_mm = grid_.radius_mm;
    report.profile_samples = grid_.samples;
    report.profile_rms_per_mm2 = Spread::of(column_rms);
    report.profile_relative_rms = Spread::of(relative_rms);
    report.profile_l2 = Spread::of(errors);
    report.branch_and_bound = {candidates, leaves, Spread::of(fractions)};
    context.report.add("subsurface", report);
    write_profiles(context.folder.path("preview/profiles.png"));
    write_appearance(context.folder.path("preview/appearance.png"));
    for (const char* file : {"preview/convergence.png", "preview/profiles.png", "preview/appearance.png"})
      context.report.files.previews.push_back(file);
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Heterogeneous subsurface scattering (paper Fig. 8): goal reflectance profiles at surface "
        "points, a chessboard of two measured media; Stratum -> Column (one per goal point) -> "
        "Layered (layers of tunable material and thickness over a backing), one independent "
        "tuner per column (branch and bound with a profile bound), run in parallel.",
        prefixed(option_docs<Options>(), "goal."),
        R"({"translator": "subsurface", "goal": {"media": ["marble", "skimmilk"]}})"};
    doc.properties.push_back(
        {"optimizer", "optimizer", "branch_and_bound, best_bound_first", "each column's optimizer"});
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  size_t square_medium(int i, int j) const {
    // In 64 bits: "squares" may be any count, and i · squares overflow an int.
    const long long si = static_cast<long long>(i) * squares_[0] / columns_[0];
    const long long sj = static_cast<long long>(j) * squares_[1] / columns_[1];
    return static_cast<size_t>((si + sj) % 2);
  }

  std::vector<double> thickness_list() const {
    std::vector<double> out;
    for (int s : thickness_steps_) out.push_back(s * step_mm_);
    return out;
  }

  ColumnStack stack_of(Tuner& tuner) const {
    ColumnStack stack{tuner.name(), {}};
    const std::vector<double> x = tuner.search_space().values();
    for (size_t l = 0; 2 * l + 1 < x.size(); ++l)
      stack.layers.push_back({tree_->palette().name(static_cast<MaterialId>(std::lround(x[2 * l]))), x[2 * l + 1]});
    return stack;
  }

  /// Goal (thin) vs achieved (thick) R(r)·r — the flux per unit radius — for
  /// one column of each medium, RGB, on a log scale.
  void write_profiles(const std::filesystem::path& file) {
    constexpr int kPanelW = 520, kH = 420, kLeft = 70, kBottom = 50, kTop = 40, kRight = 20;
    cv::Mat image(kH, 2 * kPanelW, CV_8UC3, cv::Scalar(255, 255, 255));
    const auto font = cv::FONT_HERSHEY_SIMPLEX;
    const cv::Scalar colours[3] = {{40, 40, 220}, {40, 160, 40}, {220, 80, 40}};
    const double r_max = grid_.radius_mm / 2;
    for (size_t medium = 0; medium < 2; ++medium) {
      size_t t = 0;
      while (t < network_.size() && square_medium(static_cast<int>(t) % columns_[0],
                                                  static_cast<int>(t) / columns_[0]) != medium) ++t;
      if (t == network_.size()) continue;
      Tuner& tuner = network_.tuner(t);
      tuner.error();
      const auto& sim = static_cast<const RadialProfileObservation&>(tuner.simulated());
      const auto& goal = static_cast<const RadialProfileObservation&>(tuner.goal().target());
      const std::vector<double> s = sim.samples(), g = goal.samples();
      const std::span<const double> radii = sim.basis->radii();
      const int x0 = static_cast<int>(medium) * kPanelW;
      const double log_hi = 0.5, log_lo = -4.5;  // log10(R r), 1/mm
      auto to_pixel = [&](double r, double value) {
        const double y = std::clamp(std::log10(std::max(value, 1e-12)), log_lo, log_hi);
        return cv::Point(x0 + kLeft + static_cast<int>(r / r_max * (kPanelW - kLeft - kRight)),
                         kTop + static_cast<int>((log_hi - y) / (log_hi - log_lo) * (kH - kTop - kBottom)));
      };
      cv::rectangle(image, {x0 + kLeft, kTop}, {x0 + kPanelW - kRight, kH - kBottom}, {120, 120, 120});
      for (int c = 0; c < 3; ++c) {
        std::vector<cv::Point> goal_line, sim_line;
        for (size_t i = 0; i < radii.size() && radii[i] <= r_max; ++i) {
          goal_line.push_back(to_pixel(radii[i], g[3 * i + static_cast<size_t>(c)] * radii[i]));
          sim_line.push_back(to_pixel(radii[i], s[3 * i + static_cast<size_t>(c)] * radii[i]));
        }
        cv::polylines(image, goal_line, false, colours[c], 1, cv::LINE_AA);
        cv::polylines(image, sim_line, false, colours[c], 3, cv::LINE_AA);
      }
      cv::putText(image, fmt::format("{}: goal (thin) vs achieved (thick), {}", media_[medium].name, tuner.name()),
                  {x0 + 10, 25}, font, 0.45, {40, 40, 40}, 1, cv::LINE_AA);
      cv::putText(image, fmt::format("r (mm), 0 .. {:g}", r_max), {x0 + kLeft, kH - 15}, font, 0.45,
                  {40, 40, 40}, 1, cv::LINE_AA);
      cv::putText(image, "log10 R(r) r (1/mm)", {x0 + kLeft + 8, kTop + 18}, font, 0.4, {40, 40, 40}, 1,
                  cv::LINE_AA);
    }
    write_image(file, image);
  }

  /// The board as the eye sees it from afar: each column's total diffuse
  /// reflectance (the profile integrated over the disc) as a colour, goal
  /// beside achieved.
  void write_appearance(const std::filesystem::path& file) {
    const int scale = std::max(1, 240 / std::max(columns_[0], columns_[1]));
    const int w = columns_[0] * scale, h = columns_[1] * scale, gap = 10;
    cv::Mat image(h, 2 * w + gap, CV_8UC3, cv::Scalar(255, 255, 255));
    for (int j = 0; j < columns_[1]; ++j) {
      for (int i = 0; i < columns_[0]; ++i) {
        Tuner& tuner = network_.tuner(static_cast<size_t>(i + columns_[0] * j));
        tuner.error();
        const std::array panels{&static_cast<const RadialProfileObservation&>(tuner.goal().target()),
                                &static_cast<const RadialProfileObservation&>(tuner.simulated())};
        for (int p = 0; p < 2; ++p) {
          Rgb rgb{};
          for (int c = 0; c < 3; ++c) rgb[static_cast<size_t>(c)] = panels[p]->basis->integrate(panels[p]->coefficients, 3, c);
          const cv::Vec3b colour(linear_to_srgb8(rgb[2]), linear_to_srgb8(rgb[1]), linear_to_srgb8(rgb[0]));
          image(cv::Rect(p * (w + gap) + i * scale, j * scale, scale, scale)).setTo(colour);
        }
      }
    }
    write_image(file, image);
  }

  std::array<int, 2> columns_{10, 10}, squares_{10, 10};
  std::vector<MeasuredMedium> media_;
  ProfileGrid grid_;
  int layer_count_ = 4;
  std::string backing_;
  std::vector<std::string> materials_;
  double step_mm_ = 0.027;
  std::vector<int> thickness_steps_;
  std::shared_ptr<LayerStackModel> model_;
  std::shared_ptr<StackBound> bound_;
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(subsurface, "subsurface", section_docs<SubsurfaceReport>("subsurface."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::SubsurfaceTranslator, "subsurface")

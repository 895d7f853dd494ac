// The smooth-caustics translator (paper §7.3, Fig. 9 right, after Finckh et
// al. 2010): a clear slab whose top is a B-spline height surface, tuned so
// that collimated light through it casts a goal image on a receiver below.
// The tree is one B-spline node over the solid's footprint (clear below,
// void above); one tuner — the caustic simulator, image MSE against the
// goal picture — tunes every control height: by default with L-BFGS on the
// tracer's derivative, which beats the paper's SPSA by two orders of
// magnitude in time (benchmarks/RESULTS.md); SPSA can run alongside for
// comparison ("compare_optimizers").

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "caustic_translation.h"
#include "caustics/caustic_parts.h"
#include "core/distance.h"
#include "fabrication/material_surfaces.h"
#include "geometry/mesh_io.h"
#include "reducer/reducer_tree.h"
#include "spec/translator.h"
#include "spec/tree_outputs.h"
#include "spec/tuning_outputs.h"
#include "tuning/convergence_plot.h"
#include "tuning/schedule.h"

namespace spec2fab {
namespace {

class SmoothCausticsTranslator final : public Translator {
 public:
  SmoothCausticsTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    const MaterialPalette& palette = experiment.palette();
    const Bounds bounds = experiment.solid().bounds();
    const Vec3 size = bounds.size();
    control_ = goal.get<std::array<int, 2>>("control", {60, 60});
    if (control_[0] < 2 || control_[1] < 2 || control_[0] * control_[1] > 1'000'000)
      goal.fail("control", "expected [na, nb], at least 2 each");
    settings_ = CausticGoalSettings::read(goal, experiment);
    const double low = goal.get_in_range("min_height_mm", 0.25 * size.z(), 1e-3, size.z());
    const double start = goal.get_in_range("start_height_mm", 0.75 * size.z(), low, size.z());
    const int per_span = static_cast<int>(goal.get_in_range("vertices_per_span", 3, 1, 16));
    const std::array<int, 2> vertices{per_span * (control_[0] - 1) + 1, per_span * (control_[1] - 1) + 1};

    const nlohmann::json tree = {
        {"type", "bspline"},
        {"axis", "z"},
        {"control", control_},
        {"heights_mm", {{"value", bounds.lower.z() + start}, {"min", bounds.lower.z() + low}, {"max", bounds.upper.z()}}},
        {"domain", {bounds.lower.x(), bounds.lower.y(), bounds.upper.x(), bounds.upper.y()}},
        {"below", {{"type", "layered"}, {"material", settings_.material}}},
        {"above", {{"type", "layered"}, {"material", "void"}}}};
    tree_ = std::make_unique<ReducerTree>(
        Properties::wrap(tree, experiment.file().string() + " (smooth caustics tree)"), palette);
    tree_->bind(experiment.solid(), experiment.geometry_spec().field_voxel_mm);
    outputs_ = TreeOutputOptions::read(goal, experiment, *tree_);

    const nlohmann::json simulator = settings_.simulator(vertices);
    slab_ = CausticSlabConfig::read(Properties::wrap(simulator, experiment.file().string() + " (simulator)"));
    const nlohmann::json optimizer =
        experiment.optimizer_or({{"type", "nlopt"}, {"algorithm", "LD_LBFGS"}, {"max_evaluations", 1000}});
    const nlohmann::json parts = {{"simulator", simulator},
                                  {"metric", {{"type", "image_mse"}}},
                                  {"goal", settings_.image_goal()},
                                  {"optimizer", optimizer}};
    // Other optimizers run from the same flat start before the main one, for
    // the comparison the paper's SPSA invites (preview/optimizer_comparison.png).
    if (experiment.root().has("compare_optimizers")) {
      for (const Properties& p : experiment.root().objects("compare_optimizers")) {
        auto built = build_optimizer(p);  // first: it names a malformed type properly
        compared_.push_back({optimizer_label(p.value()), std::move(built)});
      }
    }
    auto tuner = build_tuner(Properties::wrap(parts, experiment.file().string() + " (tuner)"), "surface",
                             PartContext{palette, &experiment.cache()});
    main_label_ = optimizer_label(optimizer);
    tuner->set_node(*tree_, tree_->root());
    network_.add(std::move(tuner));
    Phase phase;
    phase.name = "surface";
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    std::string compared;
    for (const auto& [label, optimizer] : compared_) compared += (compared.empty() ? "; compared with " : ", ") + label;
    return fmt::format(
        "smooth caustics: a {} slab, top a {} x {} B-spline; collimated light casts the goal "
        "image {} mm below on a {:g} x {:g} mm receiver ({} x {} px); one tuner (caustics, "
        "image_mse, {}{})",
        settings_.material, control_[0], control_[1], settings_.distance_mm, settings_.receiver_mm[0],
        settings_.receiver_mm[1], settings_.image[0], settings_.image[1],
        main_label_, compared);
  }

  const ReducerTree& tree() const override { return *tree_; }

  void run(RunContext& context) override {
    Tuner& tuner = network_.tuner(0);
    tuner.error();
    const auto& target = static_cast<const ImageObservation&>(tuner.goal().target());
    const std::vector<double> initial = static_cast<const ImageObservation&>(tuner.simulated()).pixels;

    const std::vector<double> start = tuner.search_space().values();
    std::vector<Summary> compared;
    for (auto& [label, optimizer] : compared_) {
      spdlog::info("comparison: {} from the flat start", label);
      optimizer->set_seed(context.seed);
      std::vector<double> x = start;
      compared.push_back(optimizer->minimize(tuner.problem(), x));
      spdlog::info("  {}", compared.back().brief_report());
      tuner.error_at(start);
    }
    const RunRecord record = schedule_.run(network_, context.seed);
    tree_->evaluate();
    tuner.error();
    const auto& achieved = static_cast<const ImageObservation&>(tuner.simulated());
    nlohmann::json report = settings_.image_report(achieved.pixels, initial, target);
    report["control"] = control_;
    context.result["caustics"] = report;
    write_tuning_outputs(record, network_, context);
    if (!compared.empty()) report_comparison(record.runs.front().summary, compared, context);
    write_caustic_panels({target.pixels, achieved.pixels}, target.width, target.height,
                         context.folder.path("preview/goal_vs_simulated.png"));
    write_height_map(network_.tuner(0).search_space().values(), control_[0], control_[1],
                     context.folder.path("preview/height_map.png"));
    context.result["files"] = {
        {"previews", {"preview/convergence.png", "preview/goal_vs_simulated.png", "preview/height_map.png"}}};
    if (!compared.empty()) context.result["files"]["previews"].push_back("preview/optimizer_comparison.png");
    context.result["caustics"]["surface_stl"] = write_surface_stl(achieved, context);
    context.result["files"]["surface"] = "print/surface.stl";
    write_tree_outputs(*tree_, outputs_, context);
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Smooth caustics (paper Fig. 9, after Finckh et al. 2010): a clear slab over the solid's "
        "footprint whose top is a B-spline height surface, tuned so that collimated light from "
        "above casts the goal image on a receiver below. One tuner: the caustics simulator, "
        "image_mse against the goal picture, L-BFGS on the tracer's derivative unless `optimizer` "
        "says otherwise (the paper's SPSA: {\"type\": \"spsa\", \"c\": 0.002, \"first_step\": 0.01}). "
        "Writes the smooth slab as print/surface.stl besides the voxel outputs.",
        {{"goal.control", "[na, nb]", "[60, 60]", "B-spline control points"},
         {"goal.min_height_mm", "number (mm)", "1/4 of the solid's height", "lowest the top may go"},
         {"goal.start_height_mm", "number (mm)", "3/4 of the solid's height", "the flat start"},
         {"goal.vertices_per_span", "integer", "3", "mesh vertices per control span"},
         {"optimizer", "object", "nlopt LD_LBFGS, 1000 evaluations", "the surface's optimizer"},
         {"compare_optimizers", "array of optimizers", "none",
          "also run each from the same start first; reports and plots them against the main one"}},
        R"({"translator": "smooth_caustics", "goal": {"image": "ring.png", "distance_mm": 200}})"};
    for (PropertyDoc& d : CausticGoalSettings::docs()) doc.properties.push_back(std::move(d));
    for (PropertyDoc& d : TreeOutputOptions::docs()) doc.properties.push_back(std::move(d));
    return doc;
  }

 private:
  /// print/surface.stl: the tuned slab as one smooth closed mesh — the
  /// simulator's own triangles — for printers that take a surface (the
  /// per-material STLs come from print voxels, whose 27 µm terraces would
  /// scatter the light). Read back and traced, it must cast what the
  /// simulator cast; the difference is reported.
  nlohmann::json write_surface_stl(const ImageObservation& simulated, RunContext& context) const {
    const auto& surface = dynamic_cast<const HeightSurface&>(tree_->root());
    const std::filesystem::path file = context.folder.path("print/surface.stl");
    const Mesh slab = caustic_slab_mesh(slab_.setup, surface, slab_.origin_mm);
    write_stl(slab, file);
    Mesh loaded = load_mesh(file);
    const Eigen::Vector3d offset = slab_offset(slab_.setup, slab_.origin_mm);
    for (Vec3& v : loaded.vertices) v -= offset;
    CausticTracer tracer(slab_.setup, std::move(loaded.vertices), std::move(loaded.triangles));
    std::vector<double> traced(simulated.pixels.size());
    tracer.render(traced);
    const double rms = root_mean_square(simulated.pixels);
    return {{"file", "print/surface.stl"},
            {"triangles", slab.triangles.size()},
            {"traced_relative_rmse_vs_simulated", rms_difference(traced, simulated.pixels) / rms}};
  }

  /// result.json "optimizers" (errors, evaluations), timing.json the wall
  /// times and when each run first reached every other run's final error,
  /// and the comparison plot.
  void report_comparison(const Summary& main, const std::vector<Summary>& compared, RunContext& context) const {
    std::vector<LabelledRun> runs{{main_label_, &main}};
    for (size_t k = 0; k < compared.size(); ++k) runs.push_back({compared_[k].first, &compared[k]});
    nlohmann::json summaries = nlohmann::json::array(), times = nlohmann::json::array();
    for (const LabelledRun& run : runs) {
      summaries.push_back({{"optimizer", run.label},
                           {"initial_error", run.summary->initial_error},
                           {"final_error", run.summary->final_error},
                           {"evaluations", run.summary->evaluations}});
      nlohmann::json reached = nlohmann::json::object();
      for (const LabelledRun& other : runs) {
        if (&other == &run) continue;
        // First trace row at or below the other run's final error.
        const auto row = std::find_if(run.summary->trace.begin(), run.summary->trace.end(),
                                      [&](const IterationRecord& r) { return r.best_error <= other.summary->final_error; });
        reached[other.label] = row == run.summary->trace.end() ? nlohmann::json(nullptr) : nlohmann::json(row->seconds);
      }
      times.push_back({{"optimizer", run.label},
                       {"seconds", run.summary->seconds},
                       {"seconds_to_reach_final_error_of", reached}});
    }
    context.result["caustics"]["optimizers"] = summaries;
    if (context.timing) (*context.timing)["optimizers"] = times;
    write_optimizer_comparison_plot(runs, context.folder.path("preview/optimizer_comparison.png"));
  }

  std::array<int, 2> control_{60, 60};
  CausticGoalSettings settings_;
  std::string main_label_;
  CausticSlabConfig slab_;
  std::vector<std::pair<std::string, std::unique_ptr<Optimizer>>> compared_;
  std::unique_ptr<ReducerTree> tree_;
  TreeOutputOptions outputs_;
  TunerNetwork network_;
  Schedule schedule_;
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::SmoothCausticsTranslator, "smooth_caustics")

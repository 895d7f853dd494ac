// The smooth-caustics translator (paper §7.3, Fig. 9 right, after Finckh et
// al. 2010): a clear slab whose top is a B-spline height surface, shaped so
// that collimated light through it casts a goal image on a receiver below
// (or, goal.surface "mirror", a print coated as a mirror whose top reflects
// the light to a receiver above).
// The tree is one B-spline node over the solid's footprint (clear below,
// void above); one tuner — the caustic simulator, image MSE against the
// goal picture — tunes every control height. The surface starts where
// optimal transport puts it (caustics/caustic_start.h; goal.start "flat"
// for the paper's flat start) and is refined by L-BFGS on the derivative
// of the noise-free smooth estimator (goal.estimator); SPSA, as the paper
// tuned it, can run alongside for comparison ("compare_optimizers").
// benchmarks/RESULTS.md has what each piece contributes.

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "spec/report_fields.h"
#include "caustic_translation.h"
#include "caustics/caustic_parts.h"
#include "caustics/caustic_slab.h"
#include "caustics/caustic_start.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"
#include "tuning/convergence_plot.h"

namespace spec2fab {
namespace {

/// One optimizer's run in the comparison (goal.compare_optimizers).
struct OptimizerOutcome {
  std::string optimizer;
  double initial_error = 0, final_error = 0;
  long long evaluations = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.optimizer, "optimizer", "the optimizer (type and algorithm)");
    f(s.initial_error, "initial_error", "error at the start");
    f(s.final_error, "final_error", "error at its end");
    f(s.evaluations, "evaluations", "error evaluations it spent");
  }
};

/// result.json "caustics".
struct SmoothCausticsReport {
  CausticImageReport image;
  std::array<int, 2> control{};
  std::optional<TransportStartReport> start;
  SlopeLimits slope_limit;
  std::optional<std::vector<OptimizerOutcome>> optimizers;
  std::optional<SurfaceStlReport> surface_stl;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.image, "", "the cast image");
    f(s.control, "control", "B-spline control points of the face");
    f(s.start, "start", "the start from optimal transport (goal.start transport)");
    f(s.slope_limit, "slope_limit", "the slope limit held");
    f(s.optimizers, "optimizers", "the optimizers compared from the same start");
    f(s.surface_stl, "surface_stl", "print/surface.stl checked (output.stl)");
  }
};

class SmoothCausticsTranslator final : public TuningTranslator {
 public:
  /// Its own goal keys; the caustic piece declares the rest.
  struct Options {
    double min_height_mm = kUnset, start_height_mm = kUnset;
    std::string start = "transport", estimator = "smooth";
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.min_height_mm, "min_height_mm", Range::above(0), "lowest the top may go",
               Default{"1/4 of the solid's height"});
      d.number(o.start_height_mm, "start_height_mm", Range::above(0), "the start's mean height",
               Default{"3/4 of the solid's height"});
      d.choice(o.start, "start", {"transport", "flat"},
               "where the optimizer starts: the surface optimal transport gives (caustics/caustic_start.h), or flat");
      d.choice(o.estimator, "estimator", {"smooth", "facets", "rays"},
               "the caustics simulator's image while tuning (print/surface.stl is traced with rays either way)");
    }
  };

  SmoothCausticsTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    const Bounds bounds = experiment.solid().bounds();
    const Vec3 size = bounds.size();
    surface_ = CausticSurfaceSettings::read(goal);
    settings_ = CausticGoalSettings::read(goal, experiment);
    settings_.require_light_past_mirror_receiver(goal);
    const Options options = read_options<Options>(goal);
    transport_start_ = options.start == "transport";
    const double low = std::isnan(options.min_height_mm) ? 0.25 * size.z() : options.min_height_mm;
    require_in(goal, "min_height_mm", low, Range::closed(1e-3, size.z()));
    const double start = std::isnan(options.start_height_mm) ? 0.75 * size.z() : options.start_height_mm;
    require_in(goal, "start_height_mm", start, Range::closed(low, size.z()));
    const MaterialPalette& palette = experiment.palette();
    set_tree(surface_.node("z", {bounds.lower.z() + start, bounds.lower.z() + low, bounds.upper.z()}, bounds,
                           fixed_material(palette, settings_.material, goal.where("material")), palette),
             goal, experiment);

    CausticSlabConfig::Options slab = settings_.slab_options(surface_.vertices());
    slab.estimator = options.estimator;
    slab_ = CausticGoalSettings::slab_config(goal, slab, experiment.limits());
    if (surface_.print_mesh == "cells") {
      if (!transport_start_) goal.fail("print_mesh", "\"cells\" meshes the start's transport: needs start \"transport\"");
      if (slab_.setup.mirror || slab_.setup.disc_aperture || slab_.setup.point_light)
        goal.fail("print_mesh", "\"cells\": a lens under collimated light through its whole footprint only");
    }
    // The goal image first: its problems are the user's to fix before an
    // optimizer this build lacks.
    auto image_goal = settings_.image_goal(goal, experiment.limits());
    const OptimizerChoice optimizer(experiment.root(), "optimizer",
                                    {{"type", "nlopt"}, {"algorithm", "LD_LBFGS"}, {"max_evaluations", 1000}});
    // Other optimizers run from the same flat start before the main one, for
    // the comparison the paper's SPSA invites (preview/optimizer_comparison.png).
    if (experiment.root().has("compare_optimizers")) {
      for (const Properties& p : experiment.root().objects("compare_optimizers")) {
        auto built = build_optimizer(p);  // first: it names a malformed type properly
        compared_.push_back({optimizer_label(p.value()), std::move(built)});
      }
    }
    auto tuner = make_tuner("surface", make_caustic_simulator(slab_), make_image_mse(), std::move(image_goal),
                            optimizer.build());
    tuner->set_origin(goal.where());
    main_label_ = optimizer_label(optimizer.spec());
    tuner->set_node(*tree_, tree_->root());
    network_.add(std::move(tuner));
    Phase phase;
    phase.name = "surface";
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    std::string compared;
    for (const auto& [label, optimizer] : compared_) compared += (compared.empty() ? "; compared with " : ", ") + label;
    const std::string light = settings_.light_angle_deg == 0
                                  ? std::string("collimated light")
                                  : fmt::format("collimated light {:g} degrees off vertical", settings_.light_angle_deg);
    return fmt::format(
        "smooth caustics: a {} slab{}, top a {} x {} B-spline; {} casts the goal "
        "image {} mm {} on a {:g} x {:g} mm receiver ({} x {} px); one tuner (caustics, "
        "image_mse, {}{})",
        settings_.material, settings_.mirror() ? " coated as a mirror" : "", surface_.control[0], surface_.control[1],
        light, settings_.distance_mm, settings_.mirror() ? "above" : "below", settings_.receiver_mm[0],
        settings_.receiver_mm[1], settings_.image[0], settings_.image[1],
        main_label_, compared);
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Smooth caustics (paper Fig. 9, after Finckh et al. 2010): a clear slab over the solid's "
        "footprint whose top is a B-spline height surface, tuned so that collimated light from "
        "above casts the goal image on a receiver below. One tuner: the caustics simulator, "
        "image_mse against the goal picture, L-BFGS on the tracer's derivative unless `optimizer` "
        "says otherwise (the paper's SPSA: {\"type\": \"spsa\", \"c\": 0.002, \"first_step\": 0.01}). "
        "Writes the smooth slab as print/surface.stl besides the voxel outputs; result.json's \"headline\" is "
        "that file traced by caustic_check, a tracer sharing no code with the simulator, beside the simulated SSIM "
        "and why they differ where they do (docs/run-report.md). With goal.surface \"mirror\" the top reflects "
        "instead (the print coated as a mirror; the same transport start, with the law of reflection) and the "
        "receiver hangs distance_mm above, lit by light tilted light_angle_deg off vertical.",
        prefixed(option_docs<Options>(), "goal."),
        R"({"translator": "smooth_caustics", "goal": {"image": "ring.png", "distance_mm": 200}})"};
    doc.properties.push_back({"optimizer", "optimizer", "nlopt LD_LBFGS, 1000 evaluations", "the surface's optimizer"});
    doc.properties.push_back({"compare_optimizers", "array of optimizers", "none",
                              "also run each from the same start first; reports and plots them against the main one"});
    append(doc.properties, CausticSurfaceSettings::docs());
    append(doc.properties, CausticGoalSettings::docs());
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  /// The start, and the other optimizers' runs from it.
  void prepare(RunContext& context) override {
    Tuner& tuner = network_.tuner(0);
    if (transport_start_)
      start_report_ = start_caustic_from_transport(tuner, slab_, *tree_->root().height_surface(),
                                                   context.timing, surface_.print_mesh == "cells" ? &transport_ : nullptr);
    slope_limit_.at_start = surface_.limit_slopes(tuner, settings_.slab);
    // The optimizer keeps near the limit (a penalty in units of the start's
    // error); the end is held to it exactly.
    tuner.set_penalty(surface_.slope_penalty(settings_.slab, tuner.error()));
    tuner.error();
    initial_ = static_cast<const ImageObservation&>(tuner.simulated()).pixels;
    const std::vector<double> start = tuner.search_space().values();
    compared_runs_.clear();
    for (auto& [label, optimizer] : compared_) {
      spdlog::info("comparison: {} from the flat start", label);
      optimizer->set_seed(context.seed);
      std::vector<double> x = start;
      compared_runs_.push_back(optimizer->minimize(tuner.problem(), x));
      spdlog::info("  {}", compared_runs_.back().brief_report());
      tuner.error_at(start);
    }
  }

  void report(const RunRecord& record, RunContext& context) override {
    Tuner& tuner = network_.tuner(0);
    slope_limit_.at_end = surface_.limit_slopes(tuner, settings_.slab);
    target_ = static_cast<const ImageObservation&>(tuner.goal().target());
    tuner.error();
    achieved_ = static_cast<const ImageObservation&>(tuner.simulated()).pixels;
    report_.image = settings_.image_report(achieved_, initial_, target_);
    report_.control = surface_.control;
    if (transport_start_) report_.start = start_report_;
    report_.slope_limit = slope_limit_;
    std::vector<std::string>& previews = context.report.files.previews;
    if (!compared_runs_.empty()) report_comparison(record.runs.front().summary, compared_runs_, context);
    write_caustic_panels({target_.pixels, achieved_}, target_.width, target_.height,
                         context.folder.path("preview/goal_vs_simulated.png"));
    write_height_map(tuner.search_space().values(), surface_.control[0], surface_.control[1],
                     context.folder.path("preview/height_map.png"));
    for (const char* file : {"preview/convergence.png", "preview/goal_vs_simulated.png", "preview/height_map.png"})
      previews.push_back(file);
    if (!compared_runs_.empty()) previews.push_back("preview/optimizer_comparison.png");
    if (outputs_.fabrication.writes("stl") && surface_.print_mesh == "cells") {
      // The start's transport meshed as it is; its mean height the tuned surface's.
      const std::vector<double> values = tuner.search_space().values();
      const double mean_height =
          std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size()) - slab_.origin_mm.z();
      TransportCellsMesh made = transport_cells_slab_mesh(slab_.setup, transport_, mean_height, 0.5 * surface_.print_copy_pixels);
      const double seconds = made.mesh_seconds + made.integration_seconds;
      const Eigen::Vector3d offset = slab_offset(slab_.setup, slab_.origin_mm);
      for (Eigen::Vector3d& p : made.mesh.vertices) p += offset;
      print_facets_ = fmt::format(
          "the transport's {} cells, each a patch of flat facets aimed at its pixel's centre: {} facets, none "
          "reaching over {:.2f} pixels from its centroid ({} of the diagram's edges collapsed, the cells' areas then "
          "restored to within {:.1e} of a mean pixel's light); facets' slopes {:.1e} rms off their aims; {} open "
          "edges, {} pinched cells",
          made.cells, made.top_triangles, made.worst_facet_radius_px, made.collapsed_edges, made.worst_area_error,
          made.rms_slope_error, made.open_edges, made.pinched_cells);
      spdlog::info("print mesh: {} ({:.1f} s)", print_facets_, seconds);
      if (context.timing) (*context.timing)["print_mesh_seconds"] = seconds;
      print_surfaces_ = {PrintSurface{"surface", std::move(made.mesh)}};
    } else if (outputs_.fabrication.writes("stl"))
      print_surfaces_ = {caustic_print_surface(slab_, surface_, surface(), {}, print_facets_, print_on_pixels_)};
  }

  /// print/surface.stl as written, traced: by the simulator's tracer, and
  /// by caustic_check for the headline.
  void after_print(RunContext& context) override {
    if (surface_stl_written(context.report)) {
      report_.surface_stl = check_caustic_surface_stl(slab_, surface_.print_vertices(), surface(),
                                                      print_surfaces_.front().mesh, achieved_, target_, {}, nullptr,
                                                      context.folder);
      context.report.files.previews.push_back(report_.surface_stl->preview);
      PrintHeadline headline = trace_print_independently(slab_, settings_.image_file, settings_.print_check_rays,
                                                         report_.image.achieved.ssim, context.folder,
                                                         PrintFrame{context.timing});
      if (std::abs(headline.ssim_difference) > kHeadlineAgreement)
        headline.printed_facets_ssim = printed_facets_errors(slab_, print_surfaces_.front().mesh, target_).ssim;
      explain_headline(headline,
                       {print_facets_, surface_.simulated_facets(), print_on_pixels_, surface_.print_mesh == "cells"});
      context.report.files.previews.push_back(headline.preview);
      context.report.add("headline", headline);
    }
    context.report.add("caustics", report_);
  }

  const HeightSurface& surface() const { return *tree_->root().height_surface(); }

  /// result.json "optimizers" (errors, evaluations), timing.json the wall
  /// times and when each run first reached every other run's final error,
  /// and the comparison plot.
  void report_comparison(const Summary& main, const std::vector<Summary>& compared, RunContext& context) {
    std::vector<LabelledRun> runs{{main_label_, &main}};
    for (size_t k = 0; k < compared.size(); ++k) runs.push_back({compared_[k].first, &compared[k]});
    std::vector<OptimizerOutcome> summaries;
    nlohmann::json times = nlohmann::json::array();
    for (const LabelledRun& run : runs) {
      summaries.push_back({run.label, run.summary->initial_error, run.summary->final_error, run.summary->evaluations});
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
    report_.optimizers = summaries;
    if (context.timing) (*context.timing)["optimizers"] = times;
    write_optimizer_comparison_plot(runs, context.folder.path("preview/optimizer_comparison.png"));
  }

  CausticSurfaceSettings surface_;
  std::string print_facets_;  ///< how print/surface.stl's top was meshed, in words
  bool print_on_pixels_ = false;  ///< on the pixels pulled back (else a grid)
  CausticGoalSettings settings_;
  std::string main_label_;
  CausticSlabConfig slab_;
  std::vector<std::pair<std::string, std::unique_ptr<Optimizer>>> compared_;
  std::vector<double> initial_;       ///< the image at the start
  bool transport_start_ = true;
  TransportStartReport start_report_;
  SemiDiscreteTransport transport_;  ///< the start's, kept for print_mesh "cells"
  SlopeLimits slope_limit_;
  std::vector<Summary> compared_runs_;
  ImageObservation target_;      ///< the goal image, for the check of print/surface.stl
  std::vector<double> achieved_;  ///< the image cast at the end
  SmoothCausticsReport report_;
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(smooth_caustics, "smooth_caustics", section_docs<SmoothCausticsReport>("caustics."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::SmoothCausticsTranslator, "smooth_caustics")

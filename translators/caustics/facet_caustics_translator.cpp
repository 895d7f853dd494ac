// The facet-caustics translator (paper §7.3, Fig. 9 left, after Papas et
// al. 2011): a clear slab whose top is a grid of facets, each a micro-lens
// sending its patch of collimated light to one Gaussian kernel of the goal
// image.
//
//   tree     Column (facets[0] × facets[1]) → per column a Paraboloid
//            ("facet": "lens", the default) or a Plane ("plane", as the
//            paper's tree has it), clear below, void above; slopes (and
//            curvatures) are the free parameters.
//   kernels  the goal decomposed into as many equal-flux Gaussians as there
//            are facets (simulators/caustics/gaussian_kernels.h); kernel
//            (i, j) starts on facet (i, j).
//   tuners   one per facet: facet_beam (where its plane sends the light) +
//            squared_distance to its kernel (the effective target) + the
//            aiming optimizer; a 4-neighbour network. A plane casts a sharp
//            copy of itself, so it can only aim; a lens also spreads its
//            light, and its tuner matches the spot's centroid and the square
//            root of its covariance to the kernel's (facet_beam "spread").
//   schedule "assign": annealing on the network, each tuner deciding at
//            random whether to swap kernels with a neighbour, judged by the
//            roughness of the surface the assignment asks for (below);
//            serial sweeps, 2000 moves per tuner as in the paper.
//            "aim": every tuner orients its plane at its kernel (parallel).
//   stitch   the facets' offsets by least squares so that neighbours meet
//            with the smallest steps (Eigen sparse Cholesky), then fitted
//            into the slab.
//
// Roughness: a facet deflecting light by d needs a slope roughly
// proportional to d, so Σ over neighbouring facets of |d_a − d_b|² measures
// how much neighbouring slopes differ — the steps and creases of the print.
// The finished surface is meshed (planes exactly, lenses on a grid of
// lens_subdivisions² cells each, with the walls between them), traced by the
// caustic tracer, written as print/surface.stl.

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "spec/report_fields.h"
#include "caustic_translation.h"
#include "facet_stitching.h"
#include "caustics/caustic_parts.h"
#include "caustics/caustic_start.h"
#include "caustics/facet_beam_simulator.h"
#include "caustics/gaussian_kernels.h"
#include "core/distance.h"
#include "fabrication/material_surfaces.h"
#include "reducer/height_surface.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"
#include "tuning/vector_parts.h"

namespace spec2fab {
namespace {

/// The kernels' own image against the goal: what the facets aim for.
struct KernelFit {
  CausticImageErrors errors;
  std::size_t count = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.errors, "", "the kernels' image against the goal");
    f(s.count, "count", "equal-flux Gaussian kernels");
  }
};

/// The swap phase: how much smoother the assignment of kernels got.
struct SwapRecord {
  int sweeps = 0;
  double roughness_mm2_start = 0, roughness_mm2_final = 0;
  std::vector<double> roughness_mm2_per_sweep;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.sweeps, "sweeps", "annealing sweeps");
    f(s.roughness_mm2_start, "roughness_mm2_start", "roughness of the assignment before");
    f(s.roughness_mm2_final, "roughness_mm2_final", "and after");
    f(s.roughness_mm2_per_sweep, "roughness_mm2_per_sweep", "after each sweep");
  }
};

/// How well the facets hit their kernels.
struct AimReport {
  double rms_miss_mm = 0, max_miss_mm = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.rms_miss_mm, "rms_miss_mm", "rms of the facets' misses");
    f(s.max_miss_mm, "max_miss_mm", "the largest miss");
  }
};

/// result.json "caustics".
struct FacetCausticsReport {
  CausticImageReport image;
  std::string targets;
  std::optional<KernelFit> kernels;
  std::array<int, 2> facets{};
  std::array<double, 2> facet_mm{};
  std::string print_mesh;
  SwapRecord assignment;
  AimReport aim;
  StitchReport stitch;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.image, "", "the traced slab's image");
    f(s.targets, "targets", "what the facets aim at: transport or kernels (goal.targets)");
    f(s.kernels, "kernels", "the kernels the facets aim for (targets: kernels)");
    f(s.facets, "facets", "facets along x and y");
    f(s.facet_mm, "facet_mm", "a facet's size");
    f(s.print_mesh, "print_mesh", "how the traced and printed slab is meshed");
    f(s.assignment, "assignment", "the swap phase");
    f(s.aim, "aim", "the aim phase");
    f(s.stitch, "stitch", "the facets' offsets stitched");
  }
};

class FacetCausticsTranslator final : public TuningTranslator {
 public:
  /// Its own goal keys; the caustic piece declares the rest.
  struct Options {
    std::array<int, 2> facets{45, 45};
    std::string facet = "lens", targets = "transport";
    int lens_subdivisions = 16, lens_rays = 4, lens_refinement_levels = 0;
    double min_height_mm = kUnset, start_height_mm = kUnset, max_slope = 1;
    int kernel_iterations = 20, assignment_sweeps = 200;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.facets, "facets", Range::at_least(1), "facets (and kernels) [nx, ny]");
      d.choice(o.facet, "facet", {"lens", "plane"},
               "each facet's shape: a paraboloid that aims and spreads its light like its kernel, or a "
               "plane that only aims it (casting a sharp copy of itself)");
      d.choice(o.targets, "targets", {"transport", "kernels"},
               "what each facet aims at: where optimal transport sends its square's light (the mean, and for a lens "
               "the spread: facets then tile the receiver as the transport does, no swap phase), or one of as many "
               "equal-flux Gaussian kernels of the goal, assigned by annealing swaps (the paper's)");
      d.number(o.lens_subdivisions, "lens_subdivisions", Range::closed(1, 64),
               "cells along each side of a lens in the traced and printed mesh");
      d.number(o.lens_refinement_levels, "lens_refinement_levels", Range::closed(0, 3),
               "with targets \"transport\", whose lenses meet within a printer's resolution: the lenses are meshed "
               "as one height field, each of their cells split in halves up to this many times where the light "
               "spreads (adaptive_caustic_slab_mesh; the steps between lenses, at most 0.01 mm, bridged); 0: each "
               "lens on its own grid with walls between");
      d.number(o.lens_rays, "lens_rays", Range::closed(2, 64), "rays along each side of a lens while tuning it");
      d.number(o.min_height_mm, "min_height_mm", Range::above(0), "lowest a facet may go",
               Default{"1/4 of the solid's height"});
      d.number(o.start_height_mm, "start_height_mm", Range::above(0), "facets' mean height",
               Default{"3/4 of the solid's height"});
      d.number(o.max_slope, "max_slope", Range::closed(1e-3, 10), "steepest facet (|dh/dx|, |dh/dy|)");
      d.number(o.kernel_iterations, "kernel_iterations", Range::closed(0, 1000), "EM iterations refining the kernels");
      d.number(o.assignment_sweeps, "assignment_sweeps", Range::closed(0, 1e6),
               "serial sweeps of the swap phase (0: no swaps; targets: kernels only)");
    }
    bool check(std::string* why) const {
      const long long cells = static_cast<long long>(facets[0]) * facets[1] *
                              (facet == "lens" ? static_cast<long long>(lens_subdivisions) * lens_subdivisions : 1);
      if (static_cast<long long>(facets[0]) * facets[1] > 250'000) *why = "facets: more than 250,000 facets";
      else if (cells > 4'000'000) *why = "lens_subdivisions: more than 4 million cells in the mesh";
      else return true;
      return false;
    }
  };

  FacetCausticsTranslator(const Properties& root, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    settings_ = CausticGoalSettings::read(goal, experiment);
    read_goal(goal);
    // The caustics simulator's slab and light (its top's vertex grid unused:
    // the faceted slab is meshed exactly).
    setup_ = CausticGoalSettings::slab_config(goal, settings_.slab_options({2, 2}), experiment.limits()).setup;
    setup_.validate();
    fit_kernels(goal, experiment);
    set_tree(facet_tree(goal, experiment.palette(), experiment.limits()), goal, experiment);
    const OptimizerChoice aim(root, "optimizer",
                              {{"type", "nlopt"}, {"algorithm", "LN_BOBYQA"}, {"max_evaluations", 200}, {"xtol_rel", 1e-10}});
    add_facet_tuners(aim);
    const OptimizerChoice swap(root, "swap_optimizer",
                               {{"type", "annealing"},
                                {"iterations", 10},
                                {"schedule_iterations", 2000},
                                {"swap_probability", 1.0},
                                {"initial_temperature", 1.0},
                                {"cooling", 0.9966}});
    add_phases(swap);
    aim_label_ = optimizer_label(aim.spec());
  }

  std::string summary() const override {
    const std::string targets =
        transport_targets_
            ? std::string("each facet's target where optimal transport sends its square's light")
            : fmt::format("the goal as {} equal-flux Gaussian kernels; annealing swaps kernels between neighbouring "
                          "facets for a smooth surface ({} sweeps)",
                          kernels_.size(), sweeps_);
    return fmt::format(
        "facet caustics: a {} slab, top {} x {} {} ({:.3g} x {:.3g} mm); {}, then each facet's tuner "
        "(facet_beam, squared_distance, {}) {}; light cast {} mm below on a {:g} x {:g} mm receiver ({} x {} px)",
        settings_.material, facets_[0], facets_[1], lens_ ? "micro-lenses (paraboloids)" : "planar facets",
        facet_mm_[0], facet_mm_[1], targets, aim_label_,
        lens_ ? "aims its lens and bends it to spread the light like its target" : "aims its plane",
        settings_.distance_mm, settings_.receiver_mm[0], settings_.receiver_mm[1], settings_.image[0],
        settings_.image[1]);
  }

  /// What the report compares with: the kernels' image and the flat slab's.
  void prepare(RunContext& /*context*/) override {
    if (!transport_targets_) kernel_image_ = render_kernels(kernels_, setup_.width_mm * setup_.depth_mm, raster_);
    flat_ = trace_surface(nullptr);
  }

  void report(const RunRecord& /*record*/, RunContext& context) override {
    const ImageObservation& goal = target();
    const StitchReport stitch = stitch_facet_offsets(tree_->root(), grid(), slab().lower.z() + start_mm_,
                                                     slab().lower.z() + low_mm_, slab().upper.z());

    Mesh slab;
    // Lenses that meet within the printer's resolution print as one height
    // field, refined where the light spreads.
    const bool continuous = lens_ && transport_targets_ && options_.lens_refinement_levels > 0 &&
                            stitch.max_step_mm <= kBridgedStepMm;
    const std::vector<double> achieved = trace_surface(&slab, continuous);
    const double energy_start = swaps_->energies().empty() ? roughness(network_) : swaps_->energies().front();
    FacetCausticsReport report;
    report.image = settings_.image_report(achieved, flat_, goal);
    report.targets = transport_targets_ ? "transport" : "kernels";
    if (!transport_targets_) report.kernels = KernelFit{caustic_image_errors(kernel_image_, goal), kernels_.size()};
    report.facets = facets_;
    report.facet_mm = facet_mm_;
    report.print_mesh =
        continuous ? fmt::format("one height field, {} x {} cells per lens split in halves up to {} times where "
                                 "the light spreads; steps of up to {:.2g} mm between lenses bridged",
                                 subdivisions_, subdivisions_, options_.lens_refinement_levels, stitch.max_step_mm)
                   : fmt::format("{} x {} cells per facet, walls between facets", subdivisions_, subdivisions_);
    if (options_.lens_refinement_levels > 0 && !continuous)
      spdlog::warn("lens_refinement_levels not used: steps between lenses reach {:.3g} mm, over the {:g} mm a print "
                   "bridges; each lens is meshed on its own grid with walls",
                   stitch.max_step_mm, kBridgedStepMm);
    report.assignment = {sweeps_, energy_start, roughness(network_), swaps_->energies()};
    report.aim = aim_report();
    report.stitch = stitch;
    context.report.add("caustics", report);
    simulated_ssim_ = report.image.achieved.ssim;

    // The goal, the kernels' own image where the paper's targets were used, and what the lenses cast.
    std::vector<std::span<const double>> panels{goal.pixels};
    if (!transport_targets_) panels.emplace_back(kernel_image_);
    panels.emplace_back(achieved);
    write_caustic_panels(panels, goal.width, goal.height, context.folder.path("preview/goal_vs_simulated.png"));
    std::vector<double> centre_heights;
    for (size_t k = 0; k < network_.size(); ++k)
      centre_heights.push_back(plane(k).surface_height(0.5 * facet_mm_[0], 0.5 * facet_mm_[1]));
    write_height_map(centre_heights, facets_[0], facets_[1], context.folder.path("preview/height_map.png"));
    for (const char* file : {"preview/convergence.png", "preview/goal_vs_simulated.png", "preview/height_map.png"})
      context.report.files.previews.push_back(file);
    // The faceted slab, walls included, beside the materials' STLs.
    if (outputs_.fabrication.writes("stl")) print_surfaces_ = {{"surface", std::move(slab)}};
  }

  /// print/surface.stl traced by caustic_check for the headline.
  void after_print(RunContext& context) override {
    if (!surface_stl_written(context.report)) return;
    CausticSlabConfig config;
    config.setup = setup_;
    config.origin_mm = slab().lower;
    // The rays trace_surface traced.
    config.setup.rays_x = std::max(setup_.rays_x, 8 * setup_.image_width);
    config.setup.rays_y = std::max(setup_.rays_y, 8 * setup_.image_height);
    PrintHeadline headline = trace_print_independently(config, settings_.image_file, settings_.print_check_rays,
                                                       simulated_ssim_, context.folder, PrintFrame{context.timing});
    explain_headline(headline, {});
    context.report.files.previews.push_back(headline.preview);
    context.report.add("headline", headline);
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "Facet caustics (paper Fig. 9 left, after Papas et al. 2011): a clear slab over the solid's "
        "footprint whose top is a grid of facets (Column -> Paraboloid, or -> Plane with facet: "
        "plane), each a micro-lens sending its light to one of as many equal-flux Gaussian kernels "
        "of the goal image. Annealing swaps kernels between neighbouring facets' tuners for a "
        "smoother surface (phase \"assign\"), then every facet's tuner aims its lens and curves it "
        "so that its spot has the kernel's centroid and spread (a plane only aims; facet_beam "
        "simulator, squared_distance, phase \"aim\"); offsets are stitched by least squares. "
        "Writes the faceted slab, walls included, as "
        "print/surface.stl besides the voxel outputs; result.json reports RMSE and SSIM of the "
        "traced surface, of the kernels themselves, and the roughness the swaps removed, and its \"headline\" "
        "the file traced by caustic_check, a tracer sharing no code with the simulator (docs/run-report.md).",
        prefixed(option_docs<Options>(), "goal."),
        R"({"translator": "facet_caustics", "goal": {"image": "ring.png", "facets": [45, 45]}})"};
    doc.properties.push_back({"swap_optimizer", "optimizer",
                              "annealing, 10 swaps per run, 2000 over the sweeps, T 1 -> 0.001 mm^2",
                              "the swap phase's optimizer (each tuner's own copy)"});
    doc.properties.push_back({"optimizer", "optimizer", "nlopt LN_BOBYQA, 200 evaluations", "each facet's aiming optimizer"});
    append(doc.properties, CausticGoalSettings::docs());
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  /// The translator's own goal keys (facets, their shape, heights, slope).
  void read_goal(const Properties& goal) {
    settings_.require_lens_straight_down(goal, "facet_caustics");
    // Each facet takes one equal-flux kernel: that needs equal light on every facet.
    if (settings_.aperture != "rectangle")
      goal.fail("aperture", "facet caustics give every facet an equal share of the light, so the light must cover "
                            "the whole footprint ('rectangle'); a disc aperture suits smooth_caustics");
    if (settings_.point_light())
      goal.fail("light_distance_mm", "facet caustics give every facet an equal share of the light, which only "
                                     "collimated light does; a point light suits smooth_caustics");
    options_ = read_options<Options>(goal);
    const Vec3 size = settings_.slab.size();
    facets_ = options_.facets;
    lens_ = options_.facet == "lens";
    subdivisions_ = lens_ ? options_.lens_subdivisions : 1;
    low_mm_ = std::isnan(options_.min_height_mm) ? 0.25 * size.z() : options_.min_height_mm;
    require_in(goal, "min_height_mm", low_mm_, Range::closed(1e-3, size.z()));
    start_mm_ = std::isnan(options_.start_height_mm) ? 0.75 * size.z() : options_.start_height_mm;
    require_in(goal, "start_height_mm", start_mm_, Range::closed(low_mm_, size.z()));
    max_slope_ = options_.max_slope;
    facet_mm_ = {size.x() / facets_[0], size.y() / facets_[1]};
    if (max_slope_ * (facet_mm_[0] + facet_mm_[1]) > size.z() - low_mm_)
      goal.fail("max_slope", fmt::format("a facet {:.3g} x {:.3g} mm at slope {:g} rises more than the {:.3g} mm "
                                         "between min_height_mm and the top",
                                         facet_mm_[0], facet_mm_[1], max_slope_, size.z() - low_mm_));
    sweeps_ = options_.assignment_sweeps;
    transport_targets_ = options_.targets == "transport";
    if (transport_targets_) {
      if (goal.has("assignment_sweeps"))
        goal.fail("assignment_sweeps", "the transport's targets are already the best assignment: no swap phase "
                                       "(\"targets\": \"kernels\" has one)");
      sweeps_ = 0;
    }
    if (options_.lens_refinement_levels > 0 && !(transport_targets_ && lens_))
      goal.fail("lens_refinement_levels", "refines lenses aimed at the transport's targets (\"targets\": "
                                          "\"transport\", \"facet\": \"lens\"), whose lenses meet without walls");
  }

  /// The goal image as irradiance, then as one equal-flux kernel per facet.
  void fit_kernels(const Properties& goal, const Experiment& experiment) {
    image_goal_ = settings_.image_goal(goal, experiment.limits());
    raster_.width = settings_.image[0];
    raster_.height = settings_.image[1];
    raster_.size_mm = {settings_.receiver_mm[0], settings_.receiver_mm[1]};
    raster_.centre_mm = slab().center().head<2>();
    if (transport_targets_) {
      // The tracer's frame (footprint centred on the origin) to the subtree's.
      // The run's cache: a process preparing many experiments from the same
      // image (the fuzz harness's session) solves each transport once.
      const std::span<const double> pixels = target().pixels;
      square_targets_ = *cached<const std::vector<TransportMoments>>(
          &experiment.cache(),
          fmt::format("square_targets|{}|{}|{}x{}", setup_.cache_key(), content_key(pixels), facets_[0], facets_[1]),
          [&] {
            return std::make_shared<const std::vector<TransportMoments>>(
                transport_square_targets(setup_, pixels, facets_[0], facets_[1]));
          });
      for (TransportMoments& m : square_targets_) m.mean += slab().center().head<2>();
    } else {
      kernels_ = fit_equal_mass_kernels(target().pixels, raster_, facets_[0], facets_[1], options_.kernel_iterations);
    }
  }

  /// Column (facets) → per column a Plane or Paraboloid, clear below, void above.
  NodePtr facet_tree(const Properties& goal, const MaterialPalette& palette, const Limits& limits) const {
    const Parameter slope = free_number(0, -max_slope_, max_slope_);
    const auto sides = [&](HeightCut::Options& cut) {
      cut.axis = "z";
      cut.below.node = make_solid_material(fixed_material(palette, settings_.material, goal.where("material")));
      cut.above.node = make_solid_material(fixed_material(palette, "void", goal.where()));
    };
    NodePtr facet;
    if (lens_) {
      // Bent no further than the steepest slope over half a facet.
      const double most = 2 * max_slope_ / std::min(facet_mm_[0], facet_mm_[1]);
      ParaboloidOptions lens;
      lens.offset_mm = fixed_number(slab().lower.z() + start_mm_, lens.offset_mm);
      lens.slope_a = lens.slope_b = slope;
      lens.curvature_aa = lens.curvature_ab = lens.curvature_bb = free_number(0, -most, most);
      sides(lens.cut);
      facet = make_paraboloid(std::move(lens));
    } else {
      PlaneOptions plane;
      plane.offset_mm = fixed_number(slab().lower.z() + start_mm_, plane.offset_mm);
      plane.slope_a = plane.slope_b = slope;
      sides(plane.cut);
      facet = make_plane(std::move(plane));
    }
    ColumnOptions columns;
    columns.count = facets_;
    columns.domain = {slab().lower.x(), slab().lower.y(), slab().upper.x(), slab().upper.y()};
    columns.cells.child.node = std::move(facet);
    return make_column(std::move(columns), limits);
  }

  /// One tuner per facet: facet_beam + squared_distance to its kernel (a
  /// lens matches its spot's centroid and spread, the square root of its
  /// covariance, to the kernel's; a plane its centroid alone); a 4-neighbour
  /// network.
  void add_facet_tuners(const OptimizerChoice& aim) {
    for (int j = 0; j < facets_[1]; ++j) {
      for (int i = 0; i < facets_[0]; ++i) {
        const size_t k = facet_index(i, j);
        centres_.push_back(facet_centre(i, j));
        FacetBeamOptions beam;
        beam.facet_mm = facet_mm_;
        beam.facet_origin_mm = {slab().lower.x() + i * facet_mm_[0], slab().lower.y() + j * facet_mm_[1]};
        beam.bottom_mm = slab().lower.z();
        beam.refractive_index = settings_.refractive_index;
        beam.distance_mm = settings_.distance_mm;
        beam.spread = lens_;
        beam.rays = options_.lens_rays;
        // The spot's centroid, and for a lens the square root of its covariance.
        Eigen::Vector2d centre;
        Eigen::Matrix2d spread;
        if (transport_targets_) {
          const TransportMoments& m = square_targets_[k];
          centre = m.mean;
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(m.covariance);
          spread = eigen.operatorSqrt();
        } else {
          centre = kernels_[k].centre_mm;
          spread = kernels_[k].sigma_mm * Eigen::Matrix2d::Identity();
        }
        std::vector<double> target = lens_ ? std::vector<double>{centre.x(), centre.y(), spread(0, 0), spread(0, 1),
                                                                 spread(1, 0), spread(1, 1)}
                                           : std::vector<double>{centre.x(), centre.y()};
        auto tuner = make_tuner(fmt::format("facet_{}_{}", i, j), make_facet_beam_simulator(beam),
                                std::make_unique<SquaredDistance>(), std::make_unique<FixedValuesGoal>(std::move(target)),
                                aim.build());
        tuner->set_node(*tree_, tree_->root().child(k));
        network_.add(std::move(tuner));
      }
    }
    network_.connect_grid(facets_[0], facets_[1], 4);
  }

  /// "assign": serial annealing sweeps swapping kernels between neighbours
  /// (none with assignment_sweeps 0); "aim": every facet tuned in parallel.
  void add_phases(const OptimizerChoice& swap) {
    swaps_ = std::make_shared<NeighbourSwaps>(
        [this](TunerNetwork& network, size_t a, size_t b) { return swap_delta(network, a, b); },
        [this](TunerNetwork& network) { return roughness(network); });
    Phase assign;
    assign.name = "assign";
    assign.sweeps = sweeps_;
    assign.coupling = swaps_;
    assign.optimizer = swap.spec();
    assign.record_every_sweep = false;
    Phase orient;
    orient.name = "aim";
    orient.mode = Phase::Mode::parallel;
    if (sweeps_ > 0) schedule_.add(std::move(assign));
    schedule_.add(std::move(orient));
  }

  const Bounds& slab() const { return settings_.slab; }
  double simulated_ssim_ = 0;  ///< the traced surface's, for the headline
  const ImageObservation& target() const { return image_goal_->typed_target(); }
  size_t facet_index(int i, int j) const { return grid().index(i, j); }
  Eigen::Vector2d facet_centre(int i, int j) const {
    return {slab().lower.x() + (i + 0.5) * facet_mm_[0], slab().lower.y() + (j + 0.5) * facet_mm_[1]};
  }
  const HeightSurface& plane(size_t k) const { return *tree_->root().child(k).height_surface(); }

  /// The kernel tuner t aims at (its effective target, which swaps exchange).
  static Eigen::Vector2d kernel(TunerNetwork& network, size_t t) {
    const auto target = network.tuner(t).effective_target().values();
    return {target[0], target[1]};
  }

  double roughness(TunerNetwork& network) const {
    double sum = 0;
    for (size_t t = 0; t < network.size(); ++t)
      for (size_t n : network.neighbours(t))
        if (n > t) sum += pair_roughness(t, kernel(network, t), n, kernel(network, n));
    return sum;
  }

  /// |d_t − d_n|², d the deflection each facet's kernel asks for.
  double pair_roughness(size_t t, const Eigen::Vector2d& kernel_t, size_t n, const Eigen::Vector2d& kernel_n) const {
    return ((kernel_t - centres_[t]) - (kernel_n - centres_[n])).squaredNorm();
  }

  /// Change of roughness if tuners a and b exchanged kernels: only pairs
  /// touching a or b change.
  double swap_delta(TunerNetwork& network, size_t a, size_t b) const {
    const Eigen::Vector2d ka = kernel(network, a), kb = kernel(network, b);
    const auto swapped = [&](size_t t) { return t == a ? kb : t == b ? ka : kernel(network, t); };
    double delta = 0;
    for (const size_t t : {a, b})
      for (size_t n : network.neighbours(t)) {
        if (t == b && n == a) continue;  // the pair (a, b) once
        delta += pair_roughness(t, swapped(t), n, swapped(n)) - pair_roughness(t, kernel(network, t), n, kernel(network, n));
      }
    return delta;
  }

  FacetGrid grid() const { return {facets_, facet_mm_}; }

  /// The steps between lenses a print may bridge: under a third of the
  /// J750's 0.027 mm layer.
  static constexpr double kBridgedStepMm = 0.01;

  /// The lenses' height at (a, b) in the subtree's frame: the facet under
  /// the point (the higher-index one on a shared edge).
  double lens_height(double a, double b) const {
    const int i = std::clamp(static_cast<int>(std::floor((a - slab().lower.x()) / facet_mm_[0])), 0, facets_[0] - 1);
    const int j = std::clamp(static_cast<int>(std::floor((b - slab().lower.y()) / facet_mm_[1])), 0, facets_[1] - 1);
    return plane(facet_index(i, j))
        .surface_height(a - slab().lower.x() - i * facet_mm_[0], b - slab().lower.y() - j * facet_mm_[1]);
  }

  /// A height field given by a function (w over (a, b)), for the mesher.
  class LensField final : public HeightSurface {
   public:
    explicit LensField(std::function<double(double, double)> height) : height_(std::move(height)) {}
    int height_axis() const override { return 2; }
    double surface_height(double a, double b) const override { return height_(a, b); }
    void visit_height_derivatives(double, double, const HeightDerivativeVisitor&) const override {
      throw std::logic_error("LensField: no parameters");
    }

   private:
    std::function<double(double, double)> height_;
  };

  /// The faceted slab as it stands, traced; `mesh` (when given) receives it
  /// in world coordinates. `continuous`: the lenses as one height field,
  /// refined where the light spreads (lens_refinement_levels).
  std::vector<double> trace_surface(Mesh* mesh, bool continuous = false) const {
    // Each facet as m × m cells (m = 1 for planes: exact).
    const int m = subdivisions_, nx = facets_[0] * m, ny = facets_[1] * m;
    Mesh faceted;
    if (continuous) {
      CausticSetup grid_setup = setup_;
      grid_setup.vertices_x = nx + 1;
      grid_setup.vertices_y = ny + 1;
      const LensField field([this](double a, double b) { return lens_height(a, b); });
      faceted = adaptive_caustic_slab_mesh(grid_setup, field, slab().lower, options_.lens_refinement_levels);
      for (Vec3& v : faceted.vertices) v -= slab_offset(setup_, slab().lower);  // to the tracer's frame
    } else {
      // Each cell's corners on its facet's surface: neighbouring cells of
      // one lens meet without a step, lenses with a wall.
      std::vector<std::array<double, 4>> heights(static_cast<size_t>(nx) * static_cast<size_t>(ny));
      const double a = facet_mm_[0] / m, b = facet_mm_[1] / m;
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const HeightSurface& p = plane(facet_index(i / m, j / m));
          const double a0 = (i % m) * a, b0 = (j % m) * b;
          auto& h = heights[static_cast<size_t>(i) + static_cast<size_t>(nx) * static_cast<size_t>(j)];
          h = {p.surface_height(a0, b0), p.surface_height(a0 + a, b0), p.surface_height(a0 + a, b0 + b),
               p.surface_height(a0, b0 + b)};
          for (double& z : h) z -= slab().lower.z();
        }
      faceted = faceted_slab_mesh(setup_, nx, ny, heights);
    }
    std::vector<double> image(static_cast<size_t>(setup_.image_width) * static_cast<size_t>(setup_.image_height));
    // As many rays as the print's own check uses (8 per pixel pitch): each
    // facet's spot is a sharp shape that fewer rays would speckle.
    CausticSetup traced = setup_;
    traced.rays_x = std::max(traced.rays_x, 8 * traced.image_width);
    traced.rays_y = std::max(traced.rays_y, 8 * traced.image_height);
    CausticTracer tracer(traced, faceted.vertices, faceted.triangles);
    tracer.render(image);
    if (mesh != nullptr) {
      const Eigen::Vector3d offset = slab_offset(setup_, slab().lower);
      for (Vec3& v : faceted.vertices) v += offset;
      *mesh = std::move(faceted);
    }
    return image;
  }

  /// How well the planes reached their kernels: RMS and largest miss (mm).
  AimReport aim_report() {
    double sum = 0, worst = 0;
    for (size_t t = 0; t < network_.size(); ++t) {
      Tuner& tuner = network_.tuner(t);
      const double e = tuner.error();
      sum += e;
      worst = std::max(worst, std::sqrt(e));
    }
    return {std::sqrt(sum / static_cast<double>(network_.size())), worst};
  }

  std::array<int, 2> facets_{45, 45};
  bool lens_ = true;
  int subdivisions_ = 1;
  std::array<double, 2> facet_mm_{1, 1};
  double low_mm_ = 2, start_mm_ = 6, max_slope_ = 1;
  int sweeps_ = 200;
  std::string aim_label_;
  CausticGoalSettings settings_;
  CausticSetup setup_;
  ReceiverRaster raster_;
  Options options_;
  std::unique_ptr<GoalFor<ImageObservation>> image_goal_;
  std::vector<GaussianKernel> kernels_;
  bool transport_targets_ = true;
  std::vector<TransportMoments> square_targets_;  ///< targets: transport (subtree frame)
  std::vector<Eigen::Vector2d> centres_;
  std::shared_ptr<NeighbourSwaps> swaps_;
  std::vector<double> kernel_image_, flat_;  ///< the kernels' image; the flat slab's
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(facet_caustics, "facet_caustics", section_docs<FacetCausticsReport>("caustics."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::FacetCausticsTranslator, "facet_caustics")

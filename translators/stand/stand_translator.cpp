// Make It Stand (Prévost et al. 2013), composed from the framework's pieces:
// a shape that topples when printed solid is given a solid shell of a
// printable thickness (a Stratum node) over a core of Voxel cells, each a
// material or void, and one tuner of two terms chooses the cells: it
// changes the mass as little as it can (mass_properties, mass_difference
// against the solid print's mass) while the centre of mass, projected
// along gravity, lies inside the support polygon with a margin (stability,
// stand_shortfall against "stands", held at most 0). The support polygon
// is the convex hull of the surface's lowest points within a contact
// tolerance (mass/stability.h). Where the carving alone cannot move the
// centre far enough, a denser material among the cells' choices can. A
// carved cell is a cavity: empty on an FDM printer, filled with support gel
// on a PolyJet one (MaterialPalette::cavity_fill), which the mass
// properties weigh — there, carving moves the centre far less.
//
// With goal.texture, the shell carries a picture: the texture piece
// (pieces/texture.h, method lookup) puts its ink stacks in a stratum at the
// surface, over the shell's material. The stacks are chosen before the
// cells are tuned, so the inks' weight is part of what must stand (a dense
// ink, such as bronzeFill on the FDM dual printer, moves the centre itself).

#include <cmath>
#include <limits>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "core/image_write.h"
#include "core/options.h"
#include "../pieces/shell_cells.h"
#include "../pieces/texture.h"
#include "mass/mass_properties.h"
#include "mass/stability.h"
#include "reducer/nodes/nodes.h"
#include "reducer/nodes/stack_grid.h"
#include "reducer/reducer_tree.h"
#include "spec/report_fields.h"
#include "spec/tuning_translator.h"
#include "tuning/optimizer.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {
namespace {

/// Whether the print stands, in one state (printed solid, or tuned).
struct StandState {
  bool stands = false;
  double margin_mm = 0, mass_kg = 0;
  std::array<double, 3> centre_mm{};
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.stands, "stands", "whether the centre of mass projects inside the support polygon with the margin");
    f(s.margin_mm, "margin_mm", "signed distance from its projection to the polygon's edge (negative: outside)");
    f(s.mass_kg, "mass_kg", "the print's mass");
    f(s.centre_mm, "centre_mm", "its centre of mass");
  }
};

struct StandReport {
  std::array<double, 3> gravity{};
  double margin_goal_mm = 0, support_area_mm2 = 0;
  std::vector<std::array<double, 3>> support_polygon_mm;
  std::array<int, 3> cells{};
  int core_cells = 0, carved_cells = 0;
  std::vector<std::string> materials, assignment;
  StandState solid, tuned;
  double mass_change_g = 0, mass_change_fraction = 0;
  std::optional<TextureReport> texture;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.gravity, "gravity", "the direction of gravity");
    f(s.margin_goal_mm, "margin_goal_mm", "the least margin asked for");
    f(s.support_area_mm2, "support_area_mm2", "the support polygon's area");
    f(s.support_polygon_mm, "support_polygon_mm", "its corners, on the floor, counter-clockwise seen from above");
    f(s.cells, "cells", "the core's voxel cells along x, y, z");
    f(s.core_cells, "core_cells", "cells that hold part of the core (the others are tuned by nothing)");
    f(s.carved_cells, "carved_cells", "core cells the tuner made void");
    f(s.materials, "materials", "what a core cell may be");
    f(s.assignment, "assignment", "each cell's material, x fastest (cells outside the core keep the first)");
    f(s.solid, "solid", "the shape printed solid (every cell the first material)");
    f(s.tuned, "tuned", "the tuned print");
    f(s.mass_change_g, "mass_change_g", "tuned mass minus solid mass");
    f(s.mass_change_fraction, "mass_change_fraction", "that, as a fraction of the solid mass");
    f(s.texture, "texture", "the picture on the shell (goal.texture), against its goal");
  }
};

// The texture's keys, under goal.texture; its inks lie on the shell's material.
TextureOptions stand_texture_options() {
  TextureOptions options;
  options.offers_lookup = true;
  options.default_inks_text = "the printer's model materials but the shell's and clear ones";
  // The picture's top row at the highest v: upright on the faces a planar
  // projection along x or y maps (v is z there).
  options.top_row_at_highest_v = true;
  return options;
}

class StandTranslator final : public TuningTranslator {
 public:
  struct Options {
    StabilityOptions stability;  ///< gravity, contact tolerance, the mass grid
    double margin_mm = 1;
    double shell_mm = 2;
    std::array<int, 3> cells{6, 6, 8};
    std::string material;
    std::vector<std::string> core_materials;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      StabilityOptions::declare(d, o.stability);
      d.number(o.margin_mm, "margin_mm", Range::at_least(0),
               "least distance from the centre of mass's projection to the support polygon's edge");
      // A stratum's depth bounds it: a deeper shell reached make_shell_cells's
      // fixed_number as an internal error (fuzz_experiment, 2026-11-30).
      d.number(o.shell_mm, "shell_mm", Range::open_closed(0, StratumOptions{}.depth_mm.upper()),
               "the shell kept solid under the surface (printable)");
      d.number(o.cells, "cells", Range::closed(1, 64), "the core's voxel cells along x, y, z, tiling the shape's bounds");
      d.value(o.material, "material", "the shell's material, and the cells' when solid",
              Default{"the printer's first model material"});
      d.value(o.core_materials, "core_materials",
              "what a core cell may be: the first is the solid print's; \"void\" carves",
              Default{"[material, \"void\"]"});
    }
    bool check(std::string* why) const { return stability.check(why); }
  };

  StandTranslator(const Properties& /*root*/, const Experiment& experiment)
      : options_(read_options<Options>(experiment.goal())) {
    const Properties goal = experiment.goal();
    const std::string where = goal.where();
    const MaterialPalette& palette = experiment.palette();
    if (options_.material.empty()) options_.material = palette.name(1);
    if (options_.core_materials.empty()) options_.core_materials = {options_.material, "void"};
    // stratum: the shell solid (or a texture's inks over it), the core in
    // voxel cells of a material or void.
    set_tree(make_shell_cells({fixed_number(options_.shell_mm, StratumOptions{}.depth_mm), options_.cells, options_.material,
                               options_.core_materials,
                               goal.has("texture") ? textured_shell(goal, experiment) : nullptr},
                              experiment, where, "core_materials"),
             goal, experiment);
    if (texture_) {
      // Looked up now: the mass properties below weigh the inks chosen.
      stacks_ = texture_->choose_stacks(texture_->diffusion());
      stack_grid_->set_cells(stacks_);
      tree_->evaluate();
    }

    // One tuner: the least change of mass, standing with the margin. The
    // solid print first: its simulator refuses a grid past the mass_cells limit.
    const PartContext context = experiment.part_context();
    MassPropertiesOptions mass;
    mass.voxel_mm = options_.stability.voxel_mm;
    solid_mass_kg_ = solid_state(context).mass_kg;
    core_cells_ = fix_empty_cells(where, context);
    const OptimizerChoice optimizer(experiment.root(), "optimizer",
                                    nlohmann::json{{"type", "annealing"},
                                                   {"iterations", 20000},
                                                   {"initial_temperature", 1.0},
                                                   {"cooling", 0.9995}});
    auto tuner = make_tuner("stand", make_mass_properties_simulator(mass, context), make_mass_difference_metric(),
                            make_mass_properties_goal(solid_mass_kg_, std::nullopt), optimizer.build());
    tuner->set_origin(where);
    tuner->add_term({"stands", make_stability_simulator(options_.stability, context), make_stand_shortfall_metric(),
                     make_stands_goal(options_.margin_mm), TermRule{1, 0.0, 1e3}});
    tuner->set_node(*tree_, tree_->root());
    // Branch and bound prunes on the mass a partial carving can reach.
    set_mass_bound(*tuner, *tree_, mass, context);
    network_.add(std::move(tuner));
    Phase phase;
    phase.name = "cells";
    phase.tuners = {0};
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    const std::string texture =
        texture_ ? fmt::format(" under a texture of {} x {} columns ({})", texture_->columns()[0],
                               texture_->columns()[1], fmt::join(texture_->inks(), ", "))
                 : std::string();
    return fmt::format(
        "stand (Make It Stand): a {} mm {} shell{} over {} x {} x {} core cells ({} hold core), each one of {}; one "
        "tuner: the least change of mass with the centre of mass at least {} mm inside the support polygon",
        options_.shell_mm, options_.material, texture, options_.cells[0], options_.cells[1], options_.cells[2],
        core_cells_, fmt::join(options_.core_materials, ", "), options_.margin_mm);
  }

  static TypeDoc doc() {
    TypeDoc doc{"Make It Stand (Prévost et al. 2013): a shape that topples printed solid is given a solid shell "
                "(shell_mm) over a core of voxel cells, each a material or void, tuned so that its centre of "
                "mass, projected along gravity, lies at least margin_mm inside its support polygon (the convex "
                "hull of its lowest points within contact_tolerance_mm) while its mass changes as little as it "
                "can. One tuner of two terms: mass_properties + mass_difference (the objective) and stability + "
                "stand_shortfall held at most 0. result.json's stand section says whether it stands solid and "
                "tuned; preview/stand.png draws both centres over the support polygon. With goal.texture the "
                "shell's surface carries a picture (the texture piece, method lookup: ink stacks over the "
                "shell's material), chosen before the cells so that its inks are weighed.",
                prefixed(option_docs<Options>(), "goal."),
                R"({"translator": "stand", "goal": {"cells": [6, 6, 8], "margin_mm": 1}})"};
    doc.properties.push_back({"goal.texture", "object", "none",
                              "a picture on the shell: the keys below, as the albedo translator's goal has them"});
    append(doc.properties, prefixed(option_docs(stand_texture_options()), "goal.texture."));
    doc.properties.push_back(
        {"optimizer", "optimizer", "annealing, 20000 iterations", "the cells' optimizer (any registered)"});
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  StandState state_of(const StabilityObservation& observed) const {
    StandState state;
    state.margin_mm = observed.margin_mm();
    state.stands = state.margin_mm >= options_.margin_mm;
    state.mass_kg = observed.mass_kg();
    const Vec3 c = observed.centre_mm();
    state.centre_mm = {c.x(), c.y(), c.z()};
    return state;
  }

  // The print as the tree holds it now.
  // One simulator for every state: its leaf sums are taken once and
  // reweighed (again where the cells' freedom changed).
  StandState simulate_state(const PartContext& context) {
    if (!stability_) {
      stability_ = make_stability_simulator(options_.stability, context);
      stability_->setup(tree_->root(), SimulationDomain(*tree_, tree_->root()));
    }
    StabilityObservation observed;
    stability_->simulate(tree_->root(), observed);
    return state_of(observed);
  }

  // The print with every cell its first material (the start).
  StandState solid_state(const PartContext& context) {
    return with_cells_solid(*tree_, first_core_material(), [&] { return simulate_state(context); });
  }

  MaterialId first_core_material() const {
    return tree_->palette().id(options_.core_materials.front(), "goal/core_materials");
  }

  // Cells that hold no part of the core (outside the solid, or all shell)
  // stay fixed: the tuner has nothing to gain from them. A cell holds core
  // where the mass properties' own grid samples it (their leaf sums).
  // Returns the rest.
  int fix_empty_cells(const std::string& where, const PartContext& context) {
    const Bounds& bounds = tree_->solid().bounds();
    const double h = options_.stability.voxel_mm > 0 ? options_.stability.voxel_mm : bounds.size().maxCoeff() / 96;
    const Vec3 cell = bounds.size().cwiseQuotient(Vec3(options_.cells[0], options_.cells[1], options_.cells[2]));
    if (h > 0.5 * cell.minCoeff()) {
      spdlog::warn("{}/voxel_mm: {:.3g} mm samples the core's {:.3g} mm cells coarsely: a cell the grid misses is "
                   "left solid and not tuned; a finer voxel_mm (at most half a cell) tunes every one",
                   where, h, cell.minCoeff());
    }
    MassPropertiesOptions mass;
    mass.voxel_mm = options_.stability.voxel_mm;
    return fix_cells_without_volume(*tree_, tree_->node("core"), mass, context);
  }

  // The shell's surface stratum: the texture's ink stacks (one column per
  // (u, v) cell) over one step of the shell's material, the rest of the
  // shell below it.
  NodePtr textured_shell(const Properties& goal, const Experiment& experiment) {
    const Properties texture_goal = goal.object("texture");
    // Refused before the piece simulates every printable stack.
    if (texture_goal.has("method") && texture_goal.get<std::string>("method") != "lookup")
      texture_goal.fail("method", "stand prints its texture by lookup (tuners per column would come before the "
                                  "cells' tuner, which is not built)");
    texture_.emplace(texture_goal, experiment, stand_texture_options(), options_.material);
    const double inks_mm = texture_->shell_depth().value();
    if (inks_mm > options_.shell_mm)
      goal.fail("shell_mm", fmt::format("{:g} mm is thinner than the texture's {:g} mm (its thickest stack and a step "
                                        "of {} under it); give at least that",
                                        options_.shell_mm, inks_mm, options_.material));
    const LookupEstimate estimate = texture_->lookup_estimate();
    spdlog::info("texture: {} x {} columns over {} printable stacks: ~{:.1f} s, ~{:.0f} MB", texture_->columns()[0],
                 texture_->columns()[1], estimate.printable_stacks, estimate.seconds, estimate.megabytes);
    const MaterialPalette& palette = experiment.palette();
    StratumOptions inks;
    inks.depth_mm = texture_->shell_depth();
    auto grid = texture_->stack_grid(palette, options_.material);
    stack_grid_ = grid.get();  // the lookup sets its cells
    inks.shell.node = std::move(grid);
    inks.core.node = make_solid_material(fixed_material(palette, options_.material, goal.where("material")));
    return make_stratum(std::move(inks));
  }

  void report(const RunRecord& /*record*/, RunContext& context) override {
    const PartContext part = context.experiment.part_context();
    StandReport report;
    report.gravity = options_.stability.gravity;
    report.margin_goal_mm = options_.margin_mm;
    report.cells = options_.cells;
    report.core_cells = core_cells_;
    report.materials = options_.core_materials;
    report.tuned = simulate_state(part);
    report.solid = solid_state(part);
    const CellAssignment cells = cell_assignment(*tree_);
    report.assignment = cells.materials;
    report.carved_cells = cells.carved;
    const SupportPolygon support = SupportPolygon::of(context.experiment.solid().mesh(),
                                                      Vec3(options_.stability.gravity[0], options_.stability.gravity[1],
                                                           options_.stability.gravity[2]),
                                                      options_.stability.contact_tolerance_mm);
    report.support_area_mm2 = support.area_mm2();
    for (const Vec3& corner : support.corners()) report.support_polygon_mm.push_back({corner.x(), corner.y(), corner.z()});
    report.mass_change_g = (report.tuned.mass_kg - report.solid.mass_kg) * 1e3;
    report.mass_change_fraction = report.solid.mass_kg > 0 ? report.mass_change_g / (report.solid.mass_kg * 1e3) : 0;
    if (!report.tuned.stands) {
      const Material* fill = tree_->palette().cavity_fill();
      spdlog::warn("stand: the tuned print still falls: its centre of mass is {:+.2f} mm from the support's edge, "
                   "{} asked{}",
                   report.tuned.margin_mm, options_.margin_mm,
                   fill != nullptr ? "; on this printer carved cells fill with " + fill->name +
                                         ", so carving moves the centre little (an FDM printer leaves them empty)"
                                   : "; more cells, a thinner shell or a denser core material may help");
    }
    write_preview(support, report, context.folder.path("preview/stand.png"));
    context.report.files.previews.push_back("preview/stand.png");
    if (texture_) {
      const std::vector<Rgb> achieved = texture_->colours_of(stacks_);
      report.texture = texture_->report(achieved);
      texture_->write_preview({&texture_->image().pixels, &achieved},
                              context.folder.path("preview/goal_vs_achieved.png"));
      context.report.files.previews.push_back("preview/goal_vs_achieved.png");
      texture_->write_look(achieved, tree_->solid(), context.folder);
    }
    context.report.add("stand", report);
  }

  // Two views at one scale: from above (the shape's footprint, the support
  // polygon, both centres of mass with the margin's circle) and from the
  // side (the silhouette across v, the floor under the support, the
  // centres at their heights). Solid: red; tuned: green where it stands.
  void write_preview(const SupportPolygon& support, const StandReport& report,
                     const std::filesystem::path& file) const {
    const Mesh& mesh = tree_->solid().mesh();
    const auto above = [&](const Vec3& p) { return support.project(p); };
    const auto side = [&](const Vec3& p) { return Vec2(p.dot(support.u()), -p.dot(support.down())); };
    const auto extent = [&](const auto& view, Vec2& lower, Vec2& upper) {
      lower = Vec2::Constant(std::numeric_limits<double>::infinity());
      upper = -lower;
      for (const Vec3& v : mesh.vertices) lower = lower.cwiseMin(view(v)), upper = upper.cwiseMax(view(v));
    };
    Vec2 lower_a, upper_a, lower_s, upper_s;
    extent(above, lower_a, upper_a);
    extent(side, lower_s, upper_s);
    constexpr int kPad = 36, kLegend = 76;
    const Vec2 size_a = (upper_a - lower_a).cwiseMax(1e-9), size_s = (upper_s - lower_s).cwiseMax(1e-9);
    const double scale = std::min(880.0 / (size_a.x() + size_s.x()), 520.0 / std::max(size_a.y(), size_s.y()));
    const int width_a = static_cast<int>(std::lround(size_a.x() * scale)) + 2 * kPad;
    const int width_s = static_cast<int>(std::lround(size_s.x() * scale)) + 2 * kPad;
    const int height = static_cast<int>(std::lround(std::max(size_a.y(), size_s.y()) * scale)) + 2 * kPad;
    cv::Mat image(height + kLegend, std::max(width_a + width_s, 560), CV_8UC3, cv::Scalar(255, 255, 255));
    const cv::Scalar red(40, 40, 210), green(40, 150, 40), grey(90, 90, 90), shape(225, 225, 225);
    const auto font = cv::FONT_HERSHEY_SIMPLEX;
    const auto panel = [&](int left, const Vec2& lower, const auto& view, const char* title) {
      const auto pixel = [&, left](const Vec2& p) {
        return cv::Point(left + kPad + static_cast<int>(std::lround((p.x() - lower.x()) * scale)),
                         height - kPad - static_cast<int>(std::lround((p.y() - lower.y()) * scale)));
      };
      for (const Eigen::Vector3i& t : mesh.triangles) {
        const cv::Point corners[3] = {pixel(view(mesh.vertices[static_cast<size_t>(t[0])])),
                                      pixel(view(mesh.vertices[static_cast<size_t>(t[1])])),
                                      pixel(view(mesh.vertices[static_cast<size_t>(t[2])]))};
        cv::fillConvexPoly(image, corners, 3, shape, cv::LINE_AA);
      }
      cv::putText(image, title, {left + 10, 22}, font, 0.5, grey, 1, cv::LINE_AA);
      return pixel;
    };
    const auto mark = [&](const cv::Point& at, const StandState& state, bool circle) {
      const cv::Scalar colour = state.stands ? green : red;
      if (circle) {
        cv::circle(image, at, std::max(3, static_cast<int>(std::lround(report.margin_goal_mm * scale))), colour, 1,
                   cv::LINE_AA);
      }
      cv::drawMarker(image, at, colour, cv::MARKER_CROSS, 16, 2, cv::LINE_AA);
    };
    const auto centre = [](const StandState& s) { return Vec3(s.centre_mm[0], s.centre_mm[1], s.centre_mm[2]); };

    const auto from_above = panel(0, lower_a, above, "from above");
    std::vector<cv::Point> polygon;
    for (const Vec2& p : support.hull()) polygon.push_back(from_above(p));
    if (polygon.size() >= 3) {
      cv::Mat fill = image.clone();
      cv::fillPoly(fill, std::vector<std::vector<cv::Point>>{polygon}, cv::Scalar(170, 215, 170), cv::LINE_AA);
      cv::addWeighted(fill, 0.6, image, 0.4, 0, image);
    }
    cv::polylines(image, polygon, true, green, 2, cv::LINE_AA);
    mark(from_above(above(centre(report.solid))), report.solid, true);
    mark(from_above(above(centre(report.tuned))), report.tuned, true);

    const auto from_side = panel(width_a, lower_s, side, "from the side (gravity down)");
    double support_lower = std::numeric_limits<double>::infinity(), support_upper = -support_lower;
    for (const Vec3& corner : support.corners()) {
      support_lower = std::min(support_lower, side(corner).x());
      support_upper = std::max(support_upper, side(corner).x());
    }
    const double floor = support.corners().empty() ? lower_s.y() : side(support.corners().front()).y();
    cv::line(image, from_side({lower_s.x() - 5, floor}), from_side({upper_s.x() + 5, floor}), grey, 1, cv::LINE_AA);
    cv::line(image, from_side({support_lower, floor}), from_side({support_upper, floor}), green, 4, cv::LINE_AA);
    for (const StandState* state : {&report.solid, &report.tuned}) {
      const Vec2 at = side(centre(*state));
      cv::line(image, from_side(at), from_side({at.x(), floor}), state->stands ? green : red, 1, cv::LINE_AA);
      mark(from_side(at), *state, false);
    }

    const auto verdict = [](const StandState& s) {
      return fmt::format("{} ({:+.2f} mm from the support's edge)", s.stands ? "stands" : "falls", s.margin_mm);
    };
    cv::putText(image, "solid: " + verdict(report.solid), {12, height + 22}, font, 0.5,
                report.solid.stands ? green : red, 1, cv::LINE_AA);
    cv::putText(image, "tuned: " + verdict(report.tuned), {12, height + 44}, font, 0.5,
                report.tuned.stands ? green : red, 1, cv::LINE_AA);
    cv::putText(image,
                fmt::format("crosses: centres of mass; green: support polygon; circles: the {} mm margin",
                            report.margin_goal_mm),
                {12, height + 66}, font, 0.4, grey, 1, cv::LINE_AA);
    write_image(file, image);
  }

  Options options_;
  int core_cells_ = 0;
  double solid_mass_kg_ = 0;
  std::unique_ptr<SimulatorFor<StabilityObservation>> stability_;
  std::optional<TexturePiece> texture_;
  std::vector<std::uint32_t> stacks_;    ///< each texture column's stack
  StackGridNode* stack_grid_ = nullptr;  ///< the texture's grid, owned by tree_
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(stand, "stand", section_docs<StandReport>("stand."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::StandTranslator, "stand")

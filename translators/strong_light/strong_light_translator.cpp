// Strong and light (Stress Relief, Stava et al. 2012; Build-to-Last, Lu et
// al. 2014), composed from the framework's pieces: a part under a load case
// (a clamped box, a force spread over a loaded box) is given a solid shell
// of a printable thickness (a Stratum node) over a core of Voxel cells,
// each its material or void, and one tuner of two terms chooses the
// shell's thickness (given in steps: its depth parameter, first in the
// search, so branch and bound takes each thickness with its cells) and the
// cells:
// as light as it can be (mass_properties, mass_difference against 0 g)
// while its von Mises stress under the load stays under the material's
// tensile strength over a safety factor (fem, stress_excess against
// stress_limit, held at most 0). Branch and bound prunes on the mass a
// partial carving can reach; the stress term only adds, so the bound holds.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/options.h"
#include "../pieces/shell_cells.h"
#include "fem/displacements.h"
#include "fem/fem_parts.h"
#include "fem/fem_setup.h"
#include "mass/mass_properties.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/report_fields.h"
#include "spec/tuning_translator.h"
#include "tuning/optimizer.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {
namespace {

/// The part in one state (printed solid, or tuned).
struct StrengthState {
  double mass_g = 0, stress_max_mpa = 0, stress_p99_mpa = 0;
  bool within_limit = false;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.mass_g, "mass_g", "the part's mass");
    f(s.stress_max_mpa, "stress_max_mpa", "the largest von Mises stress of a tet under the load");
    f(s.stress_p99_mpa, "stress_p99_mpa", "the tets' 99th percentile");
    f(s.within_limit, "within_limit", "whether the measured stress is at most the limit");
  }
};

struct StrongLightReport {
  std::string material, measure;
  double tensile_strength_mpa = 0, safety_factor = 0, limit_mpa = 0;
  std::array<int, 3> cells{};
  int core_cells = 0, carved_cells = 0;
  std::vector<std::string> assignment;
  double shell_mm = 0;
  bool shell_tuned = false;
  std::vector<double> shell_choices_mm;
  StrengthState solid, tuned;
  double mass_saved_fraction = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.material, "material", "the part's material");
    f(s.measure, "measure", "which stress the limit holds: p99 or max");
    f(s.tensile_strength_mpa, "tensile_strength_mpa", "the library's tensile strength of the material");
    f(s.safety_factor, "safety_factor", "the strength is divided by it");
    f(s.limit_mpa, "limit_mpa", "the stress allowed");
    f(s.shell_mm, "shell_mm", "the shell's thickness: as tuned, or as given");
    f(s.shell_tuned, "shell_tuned", "whether the tuner chose the thickness (goal.shell_mm with a step)");
    f(s.shell_choices_mm, "shell_choices_mm", "the thicknesses it chose from (the one given, when fixed)");
    f(s.cells, "cells", "the core's voxel cells along x, y, z");
    f(s.core_cells, "core_cells", "cells that hold part of the core (the others are tuned by nothing)");
    f(s.carved_cells, "carved_cells", "core cells the tuner made void");
    f(s.assignment, "assignment", "each cell's material, x fastest");
    f(s.solid, "solid", "the part printed solid");
    f(s.tuned, "tuned", "the tuned part");
    f(s.mass_saved_fraction, "mass_saved_fraction", "1 − tuned mass / solid mass");
  }
};

class StrongLightTranslator final : public TuningTranslator {
 public:
  /// Grams of mass per MPa past the limit: no part this builds for (up to
  /// a kilogram) may trade a thousandth of an MPa for a lighter carving.
  static constexpr double kPenaltyPerMpa = 1e6;
  struct Options {
    Parameter shell_mm = Parameter::continuous(1, 0, 1e3);
    std::array<int, 3> cells{5, 1, 1};
    std::string material;
    double safety_factor = 2;
    std::string measure = "max";
    std::array<double, 3> fixed_min{}, fixed_max{}, load_min{}, load_max{}, force_n{};
    double max_tet_volume_mm3 = 2;
    double voxel_mm = 0.5;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.parameter(o.shell_mm, "shell_mm",
                  "the shell kept solid under the surface (printable): a thickness, or {\"value\", \"min\", "
                  "\"max\", \"step\"} for the tuner to choose it in steps with the cells (from the thinnest)");
      d.number(o.cells, "cells", Range::closed(1, 64), "the core's voxel cells along x, y, z, tiling the part's bounds (at most 64 in all)");
      d.value(o.material, "material", "the part's material (the library must give its tensile strength)",
              Default{"the printer's first model material"});
      d.number(o.safety_factor, "safety_factor", Range::closed(1, 100), "the strength is divided by it");
      d.choice(o.measure, "measure", {"max", "p99"},
               "the stress the limit holds: the largest of any tet, or the tets' 99th percentile (steadier where a "
               "clamp's edge is singular)");
      d.required(o.fixed_min, "fixed_min", "lower corner (mm) of the clamped box: mesh nodes in it are held");
      d.required(o.fixed_max, "fixed_max", "its upper corner");
      d.required(o.load_min, "load_min", "lower corner (mm) of the loaded box: the force spreads over the faces in it");
      d.required(o.load_max, "load_max", "its upper corner");
      d.required(o.force_n, "force_n", "the total force (N)");
      d.number(o.max_tet_volume_mm3, "max_tet_volume_mm3", Range::closed(1e-3, 1e6), "largest tet of the FEM mesh");
      d.number(o.voxel_mm, "voxel_mm", Range::above(0), "edge of the mass sampling cells");
    }
    bool check(std::string* why) const {
      if (!(shell_mm.value() > 0) || (shell_mm.is_free() && !(shell_mm.lower() > 0))) {
        *why = "shell_mm: above 0 mm (a printable shell)";
        return false;
      }
      if (shell_mm.is_free() && shell_mm.kind() != ParameterKind::discrete) {
        *why = "shell_mm: a tuned thickness takes a \"step\" (each thickness is a mesh of its own, and branch "
               "and bound needs values to branch on)";
        return false;
      }
      if (shell_mm.is_free() && shell_mm.cardinality() > 16) {
        *why = fmt::format("shell_mm: {} thicknesses to choose from; at most 16 (each is a mesh and a search of the "
                           "cells): a larger step",
                           shell_mm.cardinality());
        return false;
      }
      for (int k = 0; k < 3; ++k) {
        if (fixed_min[k] > fixed_max[k]) {
          *why = "fixed_max: each coordinate at least fixed_min's";
          return false;
        }
        if (load_min[k] > load_max[k]) {
          *why = "load_max: each coordinate at least load_min's";
          return false;
        }
      }
      if (force_n[0] == 0 && force_n[1] == 0 && force_n[2] == 0) {
        *why = "force_n: a load of 0 N stresses nothing (every cell would be carved)";
        return false;
      }
      if (cells[0] * cells[1] * cells[2] > 64) {
        *why = "cells: at most 64 in all (each assignment branch and bound keeps is an FEM solve)";
        return false;
      }
      return true;
    }
  };

  StrongLightTranslator(const Properties& /*root*/, const Experiment& experiment)
      : options_(read_options<Options>(experiment.goal())) {
    const Properties goal = experiment.goal();
    const std::string where = goal.where();
    const MaterialPalette& palette = experiment.palette();
    if (options_.material.empty()) options_.material = palette.name(1);
    const Material& material = palette.material(palette.id(options_.material, where + "/material"));
    if (!material.tensile_strength_pa) {
      throw InputError(where + "/material: the library gives '" + options_.material +
                       "' no tensile strength (mechanical.tensile_strength_pa)");
    }
    strength_mpa_ = material.tensile_strength_pa->value * 1e-6;
    limit_mpa_ = strength_mpa_ / options_.safety_factor;
    // stratum: the shell solid, the core in voxel cells of the material or
    // void. A tuned shell starts at its thinnest: the cells it leaves some
    // core at that thickness are the ones tuned.
    Parameter shell = options_.shell_mm;
    if (shell.is_free()) shell.set(shell.lower());
    set_tree(make_shell_cells({shell, options_.cells, options_.material, {options_.material, "void"}}, experiment,
                              where, "material"),
             goal, experiment);

    const auto corner = [](const std::array<double, 3>& a) { return Vec3(a[0], a[1], a[2]); };
    fem_ = fem::FemSettings::defaults();
    fem_.mesh.max_volume_mm3 = options_.max_tet_volume_mm3;
    fem_.solve.nonlinear = false;
    fem_.fixed = {{Eigen::AlignedBox3d(corner(options_.fixed_min), corner(options_.fixed_max)), Vec3::Zero(),
                   where + "/fixed_min"}};
    fem_.loads = {{Eigen::AlignedBox3d(corner(options_.load_min), corner(options_.load_max)), corner(options_.force_n),
                   where + "/load_min"}};
    where_ = where;

    // One tuner: the least mass, the stress within its limit.
    const PartContext context = experiment.part_context();
    MassPropertiesOptions mass;
    mass.voxel_mm = options_.voxel_mm;
    core_cells_ = fix_cells_without_volume(*tree_, tree_->node("core"), mass, context);
    // Voids first (their bound is lowest): a light design that holds is
    // found early and prunes everything heavier.
    const OptimizerChoice optimizer(experiment.root(), "optimizer",
                                    nlohmann::json{{"type", "branch_and_bound"}, {"value_order", "best_bound_first"}});
    auto tuner = make_tuner("strong_light", make_mass_properties_simulator(mass, context), make_mass_difference_metric(),
                            make_mass_properties_goal(0.0, std::nullopt), optimizer.build());
    tuner->set_origin(where);
    tuner->add_term({"stress", fem::make_fem_simulator(fem_, context, where), fem::make_stress_excess_metric(options_.measure),
                     fem::make_stress_limit_goal(limit_mpa_), TermRule{1, 0.0, kPenaltyPerMpa}});
    tuner->set_node(*tree_, tree_->root());
    set_mass_bound(*tuner, *tree_, mass, context);
    network_.add(std::move(tuner));
    Phase phase;
    phase.name = options_.shell_mm.is_free() ? "shell and cells" : "cells";
    phase.tuners = {0};
    schedule_.add(std::move(phase));
  }

  std::string summary() const override {
    const Parameter& shell = options_.shell_mm;
    const std::string thickness =
        shell.is_free() ? fmt::format("{:g}–{:g} mm (tuned in {:g} mm steps)", shell.lower(),
                                      shell.admissible(shell.cardinality() - 1), shell.step())
                        : fmt::format("{:g} mm", shell.value());
    return fmt::format(
        "strong_light (Stress Relief / Build-to-Last): a {} {} shell over {} x {} x {} core cells, each {} or "
        "void ({} hold core); one tuner: the least mass with the von Mises stress ({}) under {:.3g} MPa (strength / "
        "{})",
        thickness, options_.material, options_.cells[0], options_.cells[1], options_.cells[2],
        options_.material, core_cells_, options_.measure, limit_mpa_, options_.safety_factor);
  }

  static TypeDoc doc() {
    TypeDoc doc{"Strong and light (Stress Relief, Stava et al. 2012; Build-to-Last, Lu et al. 2014): a part "
                "clamped in one box and loaded by a force over another is given a solid shell (shell_mm, fixed or "
                "tuned in steps) over a core of voxel cells, each its material or void, as light as it can be while "
                "its von Mises stress "
                "(the largest, or the tets' 99th percentile) stays under the library's tensile strength divided by "
                "safety_factor. One tuner of two terms: mass_properties + mass_difference against 0 g (the "
                "objective) and fem + stress_excess against stress_limit held at most 0 (a penalty of 1e6 g per "
                "MPa); branch and bound, voids first, prunes on the mass bound (the least over the thicknesses "
                "left, while the shell's is open). Each thickness is meshed with the shell's inner surface as an "
                "interface. The percentile is over the "
                "remaining tets, by count: carving a lightly loaded cell raises it, and it depends on the mesh. "
                "On a PolyJet printer carved cells fill with support gel, which the mass weighs. result.json's "
                "strong_light section gives the solid and the tuned part's mass and stress; fem/ holds the tuned "
                "part's solve (fem.vtu, deformation.png).",
                prefixed(option_docs<Options>(), "goal."),
                R"({"translator": "strong_light", "goal": {"cells": [5, 1, 1], "fixed_min": [-1, -1, -1], )"
                R"("fixed_max": [0.5, 11, 11], "load_min": [99.5, -1, -1], "load_max": [101, 11, 11], )"
                R"("force_n": [0, 0, -30]}})"};
    doc.properties.push_back({"optimizer", "optimizer", "branch_and_bound, best_bound_first",
                              "the cells' optimizer (any registered)"});
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  StrengthState state_now(const PartContext& context, DisplacementsObservation* keep = nullptr) {
    if (!mass_) {
      MassPropertiesOptions mass;
      mass.voxel_mm = options_.voxel_mm;
      mass_ = make_mass_properties_simulator(mass, context);
      mass_->setup(tree_->root(), SimulationDomain(*tree_, tree_->root()));
      fem_simulator_ = fem::make_fem_simulator(fem_, context, where_);
      fem_simulator_->setup(tree_->root(), SimulationDomain(*tree_, tree_->root()));
    }
    MassPropertiesObservation mass;
    mass_->simulate(tree_->root(), mass);
    DisplacementsObservation stress;
    fem_simulator_->simulate(tree_->root(), stress);
    StrengthState state;
    state.mass_g = mass.mass_kg() * 1e3;
    state.stress_max_mpa = stress.stress_max_mpa;
    state.stress_p99_mpa = stress.stress_p99_mpa;
    state.within_limit = (options_.measure == "max" ? stress.stress_max_mpa : stress.stress_p99_mpa) <= limit_mpa_;
    if (keep != nullptr) *keep = std::move(stress);
    return state;
  }

  void report(const RunRecord& /*record*/, RunContext& context) override {
    const PartContext part = context.experiment.part_context();
    StrongLightReport report;
    report.material = options_.material;
    report.measure = options_.measure;
    report.safety_factor = options_.safety_factor;
    report.limit_mpa = limit_mpa_;
    report.tensile_strength_mpa = strength_mpa_;
    report.cells = options_.cells;
    report.core_cells = core_cells_;
    tree_->root().read_parameters([&](const std::string& name, const Parameter& depth) {
      if (name == "depth_mm") report.shell_mm = depth.value();
    });
    report.shell_tuned = options_.shell_mm.is_free();
    if (report.shell_tuned) {
      for (long long i = 0; i < options_.shell_mm.cardinality(); ++i)
        report.shell_choices_mm.push_back(options_.shell_mm.admissible(i));
    } else {
      report.shell_choices_mm = {options_.shell_mm.value()};
    }
    const CellAssignment cells = cell_assignment(*tree_);
    report.assignment = cells.materials;
    report.carved_cells = cells.carved;
    DisplacementsObservation tuned_solution;
    report.tuned = state_now(part, &tuned_solution);
    // The tuned part's solve for ParaView and a look: fem/fem.vtu (tets,
    // material, displacement, von Mises stress), fem/deformation.png.
    const std::filesystem::path fem_folder = context.folder.path("fem");
    std::filesystem::create_directories(fem_folder);
    ReportSections fem_record;
    fem_simulator_->write_report(tuned_solution, fem_folder, fem_record);
    context.report.files.previews.push_back("fem/deformation.png");
    report.solid = with_cells_solid(*tree_, tree_->palette().id(options_.material, where_ + "/material"),
                                    [&] { return state_now(part); });
    report.mass_saved_fraction = report.solid.mass_g > 0 ? 1 - report.tuned.mass_g / report.solid.mass_g : 0;
    if (!report.tuned.within_limit) {
      spdlog::warn("strong_light: the tuned part's stress ({} {:.3g} MPa) is past its limit of {:.3g} MPa: even "
                   "solid it may be; a lower load, a thicker shell or a stronger material helps",
                   options_.measure, options_.measure == "max" ? report.tuned.stress_max_mpa : report.tuned.stress_p99_mpa,
                   limit_mpa_);
    }
    context.report.add("strong_light", report);
  }

  Options options_;
  fem::FemSettings fem_;
  std::string where_;
  double strength_mpa_ = 0, limit_mpa_ = 0;
  int core_cells_ = 0;
  std::unique_ptr<SimulatorFor<MassPropertiesObservation>> mass_;
  std::unique_ptr<SimulatorFor<DisplacementsObservation>> fem_simulator_;
};

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
SPEC2FAB_REPORT_FIELDS(strong_light, "strong_light", section_docs<StrongLightReport>("strong_light."))
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::StrongLightTranslator, "strong_light")

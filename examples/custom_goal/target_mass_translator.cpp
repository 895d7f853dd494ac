// The "target_mass" translator: a print of a given mass, hollowed from the
// top down. A Plane node cuts the solid at height h; below it the print is
// solid, above it a Stratum keeps a wall `wall_mm` thick under the surface
// and leaves the core empty:
//
//   plane (z = h)
//   ├ below: material
//   └ above: stratum (wall_mm) → shell: material, core: void
//
// One tuner — the mass simulator on the plane, relative_mass_error, the
// mass goal — moves h (on a step) until the print weighs what was asked.
// It is composed from Spec2Fab's pieces: TuningTranslator runs it and writes
// the tree, the tuning record, the previews and the print files.

#include <fmt/format.h>

#include "mass_parts.h"
#include "reducer/nodes/nodes.h"
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"
#include "tuning/tuner.h"

namespace custom_goal {
namespace {

using namespace spec2fab;

/// Its section of result.json, declared like options: each field once, with
/// its meaning (spec2fab/core/report.h).
struct MassReport {
  double target_g = 0, achieved_g = 0, relative_error = 0, cut_z_mm = 0, wall_mm = 0;
  std::string material;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.target_g, "target_g", "the mass asked for");
    f(s.achieved_g, "achieved_g", "the print's simulated mass");
    f(s.relative_error, "relative_error", "(achieved - target) / target");
    f(s.cut_z_mm, "cut_z_mm", "height of the tuned cut");
    f(s.wall_mm, "wall_mm", "wall of the hollow part");
    f(s.material, "material", "the print's material");
  }
};

class TargetMassTranslator final : public TuningTranslator {
 public:
  /// The goal's keys, declared once: read here, documented by doc().
  struct Options {
    double grams = 10, wall_mm = 2, step_mm = 0.1;
    std::string material = "VeroWhitePlus";
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.grams, "grams", Range::closed(1e-6, 1e9), "the mass (g)");
      d.value(o.material, "material", "what the print is made of");
      d.number(o.wall_mm, "wall_mm", Range::at_least(0.1), "wall above the cut (at most half the smallest side)");
      d.number(o.step_mm, "step_mm", Range::closed(1e-3, 10), "the cut's step");
    }
  };

  TargetMassTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    const Bounds box = experiment.solid().bounds();
    const Options options = read_options<Options>(goal);
    grams_ = options.grams;
    material_ = options.material;
    experiment.palette().id(material_, goal.where("material"));
    wall_mm_ = options.wall_mm;
    require_in(goal, "wall_mm", wall_mm_, Range::closed(0.1, 0.5 * box.size().minCoeff()));
    const double step = options.step_mm;
    // The tree, composed from the nodes' typed options (reducer/nodes/nodes.h):
    // a misspelt option does not compile.
    const MaterialPalette& palette = experiment.palette();
    const Parameter solid = fixed_material(palette, material_, goal.where("material"));
    StratumOptions hollow;
    hollow.depth_mm = fixed_number(wall_mm_, hollow.depth_mm);
    hollow.shell.node = make_solid_material(solid);
    hollow.core.node = make_solid_material(fixed_material(palette, "void", goal.where()));
    PlaneOptions cut;
    cut.cut.axis = "z";
    cut.offset_mm = free_steps(box.lower.z() + 0.5 * box.size().z(), box.lower.z(), box.upper.z(), step);
    cut.cut.below.node = make_solid_material(solid);
    cut.cut.above.node = make_stratum(std::move(hollow));
    set_tree(make_plane(std::move(cut)), goal, experiment);

    // The tuner, from the parts' factories; the optimizer is the
    // experiment's "optimizer", or exhaustive search.
    const OptimizerChoice optimizer(experiment.root(), "optimizer", {{"type", "exhaustive"}});
    auto tuner = make_tuner("cut", make_mass_simulator({.cell_mm = {1.0, 1.0, step}}, experiment.part_context()),
                            make_relative_mass_error(), make_mass_goal(grams_), optimizer.build());
    tuner->set_node(*tree_, tree_->root());
    network_.add(std::move(tuner));
    schedule_.add(Phase{.name = "cut"});
  }

  std::string summary() const override {
    return fmt::format("target mass: {} g of {}, solid below a tuned cut, a {} mm wall above it", grams_, material_,
                       wall_mm_);
  }

  static TypeDoc doc() {
    TypeDoc doc{"A print of a given mass: solid below a tuned horizontal cut, hollow with a wall above it "
                "(mass simulator, relative_mass_error, exhaustive search over the cut's steps).",
                prefixed(option_docs<Options>(), "goal."),
                R"({"translator": "target_mass", "goal": {"grams": 20}})"};
    doc.properties.push_back({"optimizer", "optimizer", "{\"type\": \"exhaustive\"}", "the cut's optimizer"});
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  void report(const RunRecord& /*record*/, RunContext& context) override {
    Tuner& tuner = network_.tuner(0);
    tuner.error();
    const double achieved = static_cast<const MassObservation&>(tuner.simulated()).grams;
    context.report.add("mass", MassReport{grams_, achieved, (achieved - grams_) / grams_,
                                          tuner.search_space().values().front(), wall_mm_, material_});
  }

  double grams_ = 10, wall_mm_ = 2;
  std::string material_;
};

}  // namespace
}  // namespace custom_goal

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, custom_goal::TargetMassTranslator, "target_mass")

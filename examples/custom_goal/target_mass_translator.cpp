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
#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"

namespace custom_goal {
namespace {

using namespace spec2fab;

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
    const nlohmann::json tree = {
        {"type", "plane"},
        {"axis", "z"},
        {"offset_mm",
         {{"value", box.lower.z() + 0.5 * box.size().z()},
          {"min", box.lower.z()},
          {"max", box.upper.z()},
          {"step", step}}},
        {"below", {{"type", "layered"}, {"material", material_}}},
        {"above",
         {{"type", "stratum"},
          {"depth_mm", wall_mm_},
          {"shell", {{"type", "layered"}, {"material", material_}}},
          {"core", {{"type", "layered"}, {"material", "void"}}}}}};
    set_tree(tree, "target mass tree", goal, experiment);

    const nlohmann::json parts = {
        {"simulator", {{"type", "mass"}, {"cell_mm", {1.0, 1.0, step}}}},
        {"metric", {{"type", "relative_mass_error"}}},
        {"goal", {{"type", "mass"}, {"grams", grams_}}},
        {"optimizer", experiment.optimizer_or({{"type", "exhaustive"}})}};
    auto tuner = build_tuner(Properties::wrap(parts, experiment.file().string() + " (tuner)"), "cut",
                             PartContext{experiment.palette(), &experiment.cache()});
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
    context.result["mass"] = {{"target_g", grams_},
                              {"achieved_g", achieved},
                              {"relative_error", (achieved - grams_) / grams_},
                              {"cut_z_mm", tuner.search_space().values().front()},
                              {"wall_mm", wall_mm_},
                              {"material", material_}};
  }

  double grams_ = 10, wall_mm_ = 2;
  std::string material_;
};

}  // namespace
}  // namespace custom_goal

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, custom_goal::TargetMassTranslator, "target_mass")

// The "mass" simulator, the "relative_mass_error" metric and the "mass" goal.
//
// The simulator integrates density over the print by the midpoint rule: the
// whole tree (where a tuner's subtree sits in it) is asked for its material at
// the centres of a grid of cells over the solid's bounding box, each cell
// adding density × cell volume. The grid is fine along z (the direction a
// cut moves) so that the mass changes in small steps as a parameter moves.

#include <cmath>
#include <vector>

#include "mass_parts.h"
#include "core/options.h"
#include "geometry/solid.h"
#include "tuning/parts.h"

namespace custom_goal {
namespace {

using namespace spec2fab;

class MassSimulator final : public SimulatorFor<MassObservation> {
 public:
  using Options = MassSimulatorOptions;

  MassSimulator(const Properties& properties, const PartContext& context)
      : MassSimulator(read_options<Options>(properties), context) {}
  MassSimulator(const Options& options, const PartContext& context) : cell_mm_(options.cell_mm) {
    // g/mm³ per material id: kg/m³ × 1e-6.
    for (MaterialId id = 0; id < context.palette.size(); ++id)
      grams_per_mm3_.push_back(id == kVoid ? 0.0 : context.palette.material(id).density_kg_m3.value * 1e-6);
  }
  static TypeDoc doc() {
    return {"Mass of the whole print (grams): density integrated over a grid of cells across the solid's "
            "bounding box, each cell's material asked of the whole tree at its centre. Produces mass.",
            option_docs<Options>(),
            R"({"type": "mass", "cell_mm": [1, 1, 0.05]})"};
  }
  std::string name() const override { return "mass"; }

  void setup(const ReducerNode& /*subtree*/, const SimulationDomain& domain) override {
    const Bounds box = domain.require_solid("mass").bounds();
    domain_ = domain;
    std::array<int, 3> n{};
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, static_cast<int>(std::ceil(box.size()[a] / cell_mm_[a])));
    centres_.clear();
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i)
          centres_.push_back(box.lower + Vec3((i + 0.5) * box.size().x() / n[0], (j + 0.5) * box.size().y() / n[1],
                                              (k + 0.5) * box.size().z() / n[2]));
    cell_volume_mm3_ = box.size().x() / n[0] * box.size().y() / n[1] * box.size().z() / n[2];
    materials_.resize(centres_.size());
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& /*subtree*/, MassObservation& out) override {
    domain_.materials_at(centres_, materials_);
    double grams = 0;
    for (MaterialId id : materials_) grams += grams_per_mm3_[id];
    out.grams = grams * cell_volume_mm3_;
  }

 private:
  std::array<double, 3> cell_mm_{1, 1, 0.05};
  std::vector<double> grams_per_mm3_;
  SimulationDomain domain_;
  std::vector<Vec3> centres_;
  std::vector<MaterialId> materials_;
  double cell_volume_mm3_ = 0;
};

/// ((m − m*) / m*)²: a 1 % miss costs 1e-4 whatever the print weighs.
class RelativeMassError final : public MetricFor<MassObservation> {
 public:
  RelativeMassError() = default;
  RelativeMassError(const Properties& /*properties*/, const PartContext& /*context*/) {}
  static TypeDoc doc() {
    return {"Squared relative difference of two masses, ((m - m*) / m*)^2.", {}, R"({"type": "relative_mass_error"})"};
  }
  std::string name() const override { return "relative_mass_error"; }
  using MetricFor::error;
  double error(const MassObservation& simulated, const MassObservation& target) const override {
    const double relative = (simulated.grams - target.grams) / target.grams;
    return relative * relative;
  }
};

class MassGoal final : public GoalFor<MassObservation> {
 public:
  struct Options {
    double grams = 10;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.grams, "grams", Range::closed(1e-6, 1e9), "the mass (g)");
    }
  };

  explicit MassGoal(double grams) { target_.grams = grams; }
  MassGoal(const Properties& properties, const PartContext& /*context*/)
      : MassGoal(read_options<Options>(properties).grams) {}
  static TypeDoc doc() {
    return {"A print of a given mass.", option_docs<Options>(),
            R"({"type": "mass", "grams": 20})"};
  }
  std::string name() const override { return "mass"; }
  const MassObservation& typed_target() const override { return target_; }

 private:
  MassObservation target_;
};

}  // namespace

std::unique_ptr<SimulatorFor<MassObservation>> make_mass_simulator(const MassSimulatorOptions& options,
                                                                   const PartContext& context) {
  return std::make_unique<MassSimulator>(require_valid(options, "mass"), context);
}

std::unique_ptr<MetricFor<MassObservation>> make_relative_mass_error() { return std::make_unique<RelativeMassError>(); }

std::unique_ptr<GoalFor<MassObservation>> make_mass_goal(double grams) { return std::make_unique<MassGoal>(grams); }

}  // namespace custom_goal

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, custom_goal::MassSimulator, "mass")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, custom_goal::RelativeMassError, "relative_mass_error")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, custom_goal::MassGoal, "mass")

#pragma once
// The parts of the "mass" goal: an observation (the print's mass), the
// simulator that integrates density over the print, a metric and a goal.
// Each registers itself by name in its .cpp file (experiment files name
// them) and has a factory here (a translator composes them in C++, typed);
// nothing in Spec2Fab changes.

#include <array>
#include <memory>
#include <string_view>

#include "core/options.h"
#include "tuning/observation.h"
#include "tuning/parts.h"

namespace custom_goal {

/// The mass of the whole print, in grams.
struct MassObservation final : spec2fab::ObservationOf<MassObservation> {
  static constexpr std::string_view kType = "mass";
  double grams = 0;
  std::span<const double> values() const override { return {&grams, 1}; }
  std::span<double> values() override { return {&grams, 1}; }
};

/// The "mass" simulator's options, declared once: reading, range checks and
/// the docs come from here.
struct MassSimulatorOptions {
  std::array<double, 3> cell_mm{1, 1, 0.05};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.cell_mm, "cell_mm", spec2fab::Range::closed(1e-3, 100),
             "cell size (x, y, z); fine along the direction a cut moves");
  }
};

std::unique_ptr<spec2fab::SimulatorFor<MassObservation>> make_mass_simulator(const MassSimulatorOptions& options,
                                                                             const spec2fab::PartContext& context);
std::unique_ptr<spec2fab::MetricFor<MassObservation>> make_relative_mass_error();
std::unique_ptr<spec2fab::GoalFor<MassObservation>> make_mass_goal(double grams);

}  // namespace custom_goal

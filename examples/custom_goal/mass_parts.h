#pragma once
// The parts of the "mass" goal: an observation (the print's mass), the
// simulator that integrates density over the print, a metric and a goal.
// Each registers itself by name in its .cpp file; nothing in Spec2Fab changes.

#include <string_view>

#include "tuning/observation.h"

namespace custom_goal {

/// The mass of the whole print, in grams.
struct MassObservation final : spec2fab::ObservationOf<MassObservation> {
  static constexpr std::string_view kType = "mass";
  double grams = 0;
  std::span<const double> values() const override { return {&grams, 1}; }
  std::span<double> values() override { return {&grams, 1}; }
};

}  // namespace custom_goal

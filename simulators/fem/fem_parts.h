#pragma once
/// The elastic parts composed in C++ (the elastic piece's tuner): the "fem"
/// simulator from its typed settings, the "shape_mse" metric and the
/// "deformed_shape" goal.

#include <memory>
#include <string>
#include <vector>

#include "fem/fem_setup.h"
#include "tuning/parts.h"
#include "fem/displacements.h"

namespace spec2fab::fem {

/// The "fem" simulator; `where` names the settings in errors (the goal that
/// asked for them). Settings with nothing fixed are the caller's bug.
std::unique_ptr<SimulatorFor<DisplacementsObservation>> make_fem_simulator(FemSettings settings,
                                                                          const PartContext& context,
                                                                          std::string where);
/// The "shape_mse" metric.
std::unique_ptr<MetricFor<DisplacementsObservation>> make_shape_mse();
/// The "deformed_shape" goal: probe `rest[i]` should move to `targets[i]`
/// (finite, as many as each other, at least one).
std::unique_ptr<GoalFor<DisplacementsObservation>> make_deformed_shape_goal(const std::vector<Vec3>& rest,
                                                                           const std::vector<Vec3>& targets);

/// The "stress_limit" goal: von Mises stress at most `mpa` (> 0).
std::unique_ptr<GoalFor<DisplacementsObservation>> make_stress_limit_goal(double mpa);
/// The "stress_excess" metric (MPa past the limit) on `measure`: "p99" or "max".
std::unique_ptr<MetricFor<DisplacementsObservation>> make_stress_excess_metric(const std::string& measure);

}  // namespace spec2fab::fem

#include "tuning/vector_parts.h"

#include <cmath>

#include "core/properties.h"

namespace spec2fab {

SquaredDistance::SquaredDistance(const Properties& /*properties*/, const PartContext& /*context*/) {}

double SquaredDistance::error(const VectorObservation& simulated, const VectorObservation& target) const {
  double sum = 0;
  for (size_t i = 0; i < simulated.data.size() && i < target.data.size(); ++i) {
    const double d = simulated.data[i] - target.data[i];
    sum += d * d;
  }
  return std::isfinite(sum) ? sum : kUnreachable;
}

void SquaredDistance::error_gradient(const Observation& simulated, const Observation& target,
                                     std::span<double> sensitivity) const {
  const auto s = simulated.values(), t = target.values();
  for (size_t i = 0; i < sensitivity.size(); ++i) sensitivity[i] = i < t.size() ? 2 * (s[i] - t[i]) : 0.0;
}

TypeDoc SquaredDistance::doc() {
  return {"Sum of squared differences of two vectors of numbers (e.g. a landing point and its "
          "target, in mm²); non-finite simulated values score 1e30.",
          {},
          R"({"type": "squared_distance"})"};
}

FixedValuesGoal::FixedValuesGoal(const Properties& properties, const PartContext& /*context*/) {
  target_.data = properties.get<std::vector<double>>("values");
  for (double v : target_.data)
    if (!std::isfinite(v)) properties.fail("values", "every value must be finite");
}

TypeDoc FixedValuesGoal::doc() {
  return {"A fixed vector of numbers as the target.",
          {{"values", "array of numbers", "required", "the target"}},
          R"({"type": "values", "values": [12.5, -3.0]})"};
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::SquaredDistance, "squared_distance")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::FixedValuesGoal, "values")

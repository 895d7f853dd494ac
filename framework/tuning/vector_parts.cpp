#include "tuning/vector_parts.h"

#include <cmath>

#include "core/options.h"
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

namespace {
struct FixedValuesOptions {
  std::vector<double> values;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.values, "values", Range::any(), "the target");
  }
};
}  // namespace

FixedValuesGoal::FixedValuesGoal(const Properties& properties, const PartContext& /*context*/) {
  target_.data = read_options<FixedValuesOptions>(properties).values;
}

TypeDoc FixedValuesGoal::doc() {
  return {"A fixed vector of numbers as the target.",
          option_docs<FixedValuesOptions>(),
          R"({"type": "values", "values": [12.5, -3.0]})"};
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::SquaredDistance, "squared_distance")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::FixedValuesGoal, "values")

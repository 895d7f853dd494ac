#pragma once
/// Parts for VectorObservation (plain numbers) that any simulator producing
/// them can use: the metric "squared_distance" and the goal "values".

#include <vector>

#include "tuning/parts.h"

namespace spec2fab {

/// Σ (simulated − target)²; differentiable. A non-finite simulated value (a
/// ray lost to total internal reflection, say) scores kUnreachable, so that
/// optimizers see a finite, very bad point rather than a NaN.
class SquaredDistance final : public MetricFor<VectorObservation> {
 public:
  static constexpr double kUnreachable = 1e30;
  SquaredDistance() = default;
  SquaredDistance(const Properties& properties, const PartContext& context);
  std::string name() const override { return "squared_distance"; }
  using MetricFor::error;
  double error(const VectorObservation& simulated, const VectorObservation& target) const override;
  bool differentiable() const override { return true; }
  void error_gradient(const Observation& simulated, const Observation& target,
                      std::span<double> sensitivity) const override;
  static TypeDoc doc();
};

/// A fixed vector: {"type": "values", "values": [x, y]}.
class FixedValuesGoal final : public GoalFor<VectorObservation> {
 public:
  explicit FixedValuesGoal(std::vector<double> values) { target_.data = std::move(values); }
  FixedValuesGoal(const Properties& properties, const PartContext& context);
  std::string name() const override { return "values"; }
  const VectorObservation& typed_target() const override { return target_; }
  static TypeDoc doc();

 private:
  VectorObservation target_;
};

}  // namespace spec2fab

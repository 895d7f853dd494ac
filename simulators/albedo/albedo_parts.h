#pragma once
/// The albedo parts composed in C++ (the texture piece's column tuners):
/// the "albedo" simulator's options, and factories for it, the colour goal
/// and the two colour metrics.

#include <array>
#include <memory>
#include <string>

#include "core/options.h"
#include "tuning/parts.h"

namespace spec2fab {

struct AlbedoSimulatorOptions {
  double depth_mm = 3, step_mm = 0.005;
  std::array<double, 2> at{0, 0};
  int max_table = 1'000'000;

  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.depth_mm, "depth_mm", Range::closed(1e-3, 1e3),
             "depth sampled; what lies below counts as infinitely thick");
    d.number(o.step_mm, "step_mm", Range::at_least(1e-5),
             "sampling step along the depth axis (finer than any layer), at most depth_mm");
    d.value(o.at, "at", "lateral position (a, b) in the subtree's frame");
    d.number(o.max_table, "max_table", Range::closed(0, 1e8), "largest table to build; 0 never tabulates");
  }
  bool check(std::string* why) const { return at_most(step_mm, "step_mm", depth_mm, "depth_mm", why); }
};

/// The "albedo" simulator (its options the caller's to get right: require_valid).
std::unique_ptr<SimulatorFor<AlbedoObservation>> make_albedo_simulator(const AlbedoSimulatorOptions& options,
                                                                       const PartContext& context);
/// The "albedo" goal: a constant colour, linear RGB.
std::unique_ptr<GoalFor<AlbedoObservation>> make_albedo_goal(const std::array<double, 3>& linear_rgb);

/// The colour metrics an experiment names, "ciede2000" and "rgb_mse" (also
/// what the albedo lookup searches with).
enum class ColourMetric { ciede2000, rgb_mse };
std::unique_ptr<MetricFor<AlbedoObservation>> make_colour_metric(ColourMetric metric);

}  // namespace spec2fab

#pragma once
/// A print's cost and time as a tuner weighs them. The "print_estimate"
/// simulator takes the census fabrication takes (fabrication/print_estimate.h)
/// on a coarser stated grid and prices it with the library and the run's
/// printer profile: the same model as result.json's "fabrication.print",
/// at the grid's resolution. The metrics "cost_usd" and "print_hours" are
/// how far the print goes past the goal "print_budget" (0 by default: as
/// little as possible), so a tuner may minimise either or hold it under a
/// budget as a term ("at_most").

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/options.h"
#include "tuning/parts.h"

namespace spec2fab {

/// Cost (US$), print time (h), mass (g, support included), model and support volume (mm³).
struct PrintEstimateObservation final : ObservationOf<PrintEstimateObservation> {
  static constexpr std::string_view kType = "print_estimate";
  static constexpr std::size_t kCost = 0, kHours = 1, kMass = 2, kModelVolume = 3, kSupportVolume = 4, kSize = 5;
  std::vector<double> data = std::vector<double>(kSize, 0.0);

  std::span<const double> values() const override { return data; }
  std::span<double> values() override { return data; }
  double cost_usd() const { return data[kCost]; }
  double print_hours() const { return data[kHours]; }
  /// print_estimate.csv: each quantity by name, with its unit.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

struct PrintEstimateOptions {
  double voxel_mm = 0;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.voxel_mm, "voxel_mm", Range::at_least(0),
             "edge of the census cells (layers and raster rows scale to the printer's); 0: the solid's longest "
             "extent / 96",
             Default{"longest extent / 96"});
  }
};

std::unique_ptr<SimulatorFor<PrintEstimateObservation>> make_print_estimate_simulator(
    const PrintEstimateOptions& options, const PartContext& context);
/// At most `cost_usd` and `hours` (0: as little as possible).
std::unique_ptr<GoalFor<PrintEstimateObservation>> make_print_budget_goal(double cost_usd, double hours);
std::unique_ptr<MetricFor<PrintEstimateObservation>> make_cost_metric();
std::unique_ptr<MetricFor<PrintEstimateObservation>> make_print_hours_metric();

}  // namespace spec2fab

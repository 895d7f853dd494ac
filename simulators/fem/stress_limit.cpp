// Goal `stress_limit` and metric `stress_excess`: a print whose stress under
// its load case stays under a limit (the material's strength over a safety
// factor: Stress Relief, Stava et al. 2012; Build-to-Last, Lu et al. 2014).
// The fem simulator observes each tet's von Mises stress, its largest value
// and its 99th percentile over the non-void tets, by count. A clamp's edge
// and a cavity's re-entrant edges are singular: the largest value there
// grows as the mesh refines. The percentile is steadier but no measure of
// strength by itself: it depends on the mesh, and carving a lightly loaded
// cell (fewer low-stress tets) raises it.

#include <cmath>
#include <limits>

#include "core/options.h"
#include "fem/fem_parts.h"

namespace spec2fab::fem {
namespace {

class StressLimit final : public GoalFor<DisplacementsObservation> {
 public:
  struct Options {
    double mpa = 0;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.required(o.mpa, "mpa", Range::above(0), "the von Mises stress (MPa) the print may reach");
    }
  };
  StressLimit(const Properties& properties, const PartContext& /*context*/)
      : StressLimit(read_options<Options>(properties).mpa) {}
  explicit StressLimit(double mpa) {
    target_.stress_max_mpa = mpa;
    target_.stress_p99_mpa = mpa;
  }
  std::string name() const override { return "stress_limit"; }
  const DisplacementsObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"A limit on the von Mises stress under the fem simulator's load case (MPa; e.g. the material's "
            "tensile strength over a safety factor); the metric stress_excess is how far the print goes past "
            "it. Describes displacements.",
            option_docs<Options>(), R"({"type": "stress_limit", "mpa": 25})"};
  }

 private:
  DisplacementsObservation target_;
};

class StressExcess final : public MetricFor<DisplacementsObservation> {
 public:
  struct Options {
    std::string measure = "p99";
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.choice(o.measure, "measure", {"p99", "max"},
               "which stress: the tets' 99th percentile (steadier at a clamp's singular edge, but mesh-dependent) "
               "or their largest");
    }
  };
  StressExcess(const Properties& properties, const PartContext& /*context*/)
      : StressExcess(read_options<Options>(properties)) {}
  explicit StressExcess(Options options) : largest_(options.measure == "max") {}
  std::string name() const override { return "stress_excess"; }
  using MetricFor::error;
  double error(const DisplacementsObservation& simulated, const DisplacementsObservation& target) const override {
    const double stress = largest_ ? simulated.stress_max_mpa : simulated.stress_p99_mpa;
    const double over = stress - (largest_ ? target.stress_max_mpa : target.stress_p99_mpa);
    return over > 0 || std::isnan(over) ? over : 0.0;  // NaN (a failed solve) stays the worst
  }
  static TypeDoc doc() {
    return {"How far (MPa) the print's von Mises stress goes past the goal's limit (0 within it); measure: the "
            "tets' 99th percentile or their largest. Compares displacements.",
            option_docs<Options>(), R"({"type": "stress_excess", "measure": "p99"})"};
  }

 private:
  bool largest_ = false;
};

}  // namespace

std::unique_ptr<GoalFor<DisplacementsObservation>> make_stress_limit_goal(double mpa) {
  return std::make_unique<StressLimit>(mpa);
}
std::unique_ptr<MetricFor<DisplacementsObservation>> make_stress_excess_metric(const std::string& measure) {
  StressExcess::Options options;
  options.measure = measure;
  return std::make_unique<StressExcess>(require_valid(options, "stress_excess"));
}

}  // namespace spec2fab::fem

SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::fem::StressLimit, "stress_limit")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::fem::StressExcess, "stress_excess")

// Compiled by ctest, not linked: with SPEC2FAB_BIND_INCOMPATIBLE defined it
// binds an image metric to a vector simulator and must NOT compile
// (test tuning.incompatible_parts_do_not_compile); without it, the same file
// with compatible parts must compile (tuning.compatible_parts_compile), which
// shows the failure comes from the type check and nothing else.

#include "tuning/tuner.h"

namespace spec2fab {

struct Displacements final : SimulatorFor<VectorObservation> {
  std::string name() const override { return "displacements"; }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode&, VectorObservation&) override {}
};
struct DisplacementRms final : MetricFor<VectorObservation> {
  std::string name() const override { return "displacement_rms"; }
  using MetricFor::error;
  double error(const VectorObservation&, const VectorObservation&) const override { return 0; }
};
struct ImageMse final : MetricFor<ImageObservation> {
  std::string name() const override { return "image_mse"; }
  using MetricFor::error;
  double error(const ImageObservation&, const ImageObservation&) const override { return 0; }
};
struct RestShape final : GoalFor<VectorObservation> {
  std::string name() const override { return "rest_shape"; }
  const VectorObservation& typed_target() const override { return target; }
  VectorObservation target;
};

#ifdef SPEC2FAB_BIND_INCOMPATIBLE
using Metric = ImageMse;
#else
using Metric = DisplacementRms;
#endif

std::unique_ptr<Tuner> bind() {
  return make_tuner("t", std::make_unique<Displacements>(), std::make_unique<Metric>(),
                    std::make_unique<RestShape>(), nullptr);
}

}  // namespace spec2fab

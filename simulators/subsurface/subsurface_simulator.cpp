// The subsurface simulator: the radial diffuse reflectance profile R(r), RGB,
// of the stack of materials a subtree assigns below one surface point, lit
// by a pencil beam — multipole diffusion per layer, layers combined in the
// frequency domain (multipole.h, layer_stack.h). The observation holds the
// profile's Fourier–Bessel coefficients (core/radial_basis.h), which the
// model produces directly from its spectra: no transform at run time.

#include <cmath>

#include "core/options.h"
#include "subsurface/layer_stack.h"
#include "subsurface/subsurface_parts.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class SubsurfaceSimulator final : public SimulatorFor<RadialProfileObservation> {
 public:
  using Options = SubsurfaceSimulatorOptions;

  SubsurfaceSimulator(const Properties& properties, const PartContext& context)
      : SubsurfaceSimulator(read_options<Options>(properties), context) {}
  SubsurfaceSimulator(const Options& options, const PartContext& context) {
    depth_mm_ = options.depth_mm;
    step_mm_ = options.step_mm;
    lateral_a_ = options.at[0];
    lateral_b_ = options.at[1];
    model_ = LayerStackModel::shared(context.palette, options.grid.basis(context.cache), step_mm_, context.cache);
    samples_.resize(static_cast<size_t>(std::ceil(depth_mm_ / step_mm_ - 1e-9)));
    runs_.reserve(samples_.size());
    spectrum_.resize(model_->value_count());
  }

  std::string name() const override { return "subsurface"; }

  std::unique_ptr<Observation> make_observation() const override {
    auto out = std::make_unique<RadialProfileObservation>();
    out->reset(model_->basis());
    return out;
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, RadialProfileObservation& out) override {
    stack_spectrum(subtree);
    if (out.basis != model_->basis()) out.reset(model_->basis());
    model_->to_coefficients(spectrum_, out.coefficients);
  }

  static TypeDoc doc() {
    return {
        "Radial diffuse reflectance profile R(r), RGB, of the material stack a subtree assigns "
        "below a surface point under a pencil beam: multipole diffusion per layer (Donner & "
        "Jensen 2005; every image summed in closed form), layers combined in the frequency "
        "domain, over a semi-infinite backing (what lies below depth_mm). Produces "
        "radial_profile: coefficients of an orthonormal Fourier-Bessel basis on a disc.",
        option_docs<Options>(),
        R"({"type": "subsurface", "depth_mm": 3, "step_mm": 0.027})"};
  }

 private:
  void stack_spectrum(const ReducerNode& subtree) {
    sample_along_depth(subtree, lateral_a_, lateral_b_, step_mm_, samples_);
    runs_.clear();
    // The last sample is the backing; the runs above it are layers.
    size_t begin = 0;
    const size_t end = samples_.size() - 1;
    while (begin < end) {
      size_t next = begin;
      while (next < end && samples_[next] == samples_[begin]) ++next;
      runs_.push_back({samples_[begin], static_cast<int>(next - begin)});
      begin = next;
    }
    if (!runs_.empty() && runs_.back().material == samples_.back()) runs_.pop_back();  // merges into the backing
    model_->reflectance(runs_, samples_.back(), spectrum_);
  }

  double depth_mm_ = 4, step_mm_ = 0.027, lateral_a_ = 0, lateral_b_ = 0;
  std::shared_ptr<LayerStackModel> model_;
  std::vector<MaterialId> samples_;  ///< sized once: simulate() does not allocate
  std::vector<StackRun> runs_;
  std::vector<double> spectrum_;
};

}  // namespace

std::unique_ptr<SimulatorFor<RadialProfileObservation>> make_subsurface_simulator(
    const SubsurfaceSimulatorOptions& options, const PartContext& context) {
  return std::make_unique<SubsurfaceSimulator>(require_valid(options, "subsurface"), context);
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::SubsurfaceSimulator, "subsurface")

// The subsurface simulator: the radial diffuse reflectance profile R(r), RGB,
// of the stack of materials a subtree assigns below one surface point, lit
// by a pencil beam — multipole diffusion per layer, layers combined in the
// frequency domain (multipole.h, layer_stack.h). The observation holds the
// profile's Fourier–Bessel coefficients (core/radial_basis.h), which the
// model produces directly from its spectra: no transform at run time.

#include <cmath>

#include "subsurface/layer_stack.h"
#include "subsurface/subsurface_parts.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class SubsurfaceSimulator final : public SimulatorFor<RadialProfileObservation> {
 public:
  SubsurfaceSimulator(const Properties& properties, const PartContext& context) {
    const ProfileGrid grid = ProfileGrid::read(properties);
    depth_mm_ = properties.get_in_range("depth_mm", 4.0, 1e-3, 1e3);
    step_mm_ = properties.get_in_range("step_mm", 0.027, 1e-4, depth_mm_);
    const auto at = properties.get<std::array<double, 2>>("at", {0.0, 0.0});
    lateral_a_ = at[0];
    lateral_b_ = at[1];
    model_ = LayerStackModel::shared(context.palette, grid.basis(context.cache), step_mm_, context.cache);
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
        {{"radius_mm", "number (mm)", "16", "profile support: R(r) is represented on [0, radius_mm]"},
         {"samples", "integer", "400", "basis size = number of radii the profile is written at"},
         {"depth_mm", "number (mm)", "4", "depth sampled; below it, the last material is semi-infinite"},
         {"step_mm", "number (mm)", "0.027", "depth sampling step; layer thicknesses are multiples of it"},
         {"at", "[a, b]", "[0, 0]", "lateral position in the subtree's frame"}},
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
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::SubsurfaceSimulator, "subsurface")

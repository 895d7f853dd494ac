// Bench problem "subsurface_stack" (spec2fab bench): one column of the
// subsurface translator — three layers over white, each one of four
// materials and 5, 10 or 20 printer layers thick — whose goal is the radial
// reflectance profile of a hidden reference stack. Discrete, 12^3 = 1,728
// stacks, with the profile bound of subsurface/stack_bound.h for branch and
// bound and profile_l2's residuals for least squares.

#include "bench/benchmark_problem.h"
#include "materials/palette.h"
#include "subsurface/stack_bound.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

constexpr double kLayerMm = 0.027;  // the J750's layer
constexpr double kRadiusMm = 16;
constexpr int kSamples = 100;
const std::vector<std::string> kMaterials{"VeroWhitePlus", "VeroCyan", "VeroMagenta", "VeroYellow"};
const std::vector<int> kSteps{5, 10, 20};
constexpr int kLayers = 3;

nlohmann::json subsurface_stack_spec() {
  std::vector<double> thicknesses;
  for (int s : kSteps) thicknesses.push_back(s * kLayerMm);
  nlohmann::json layers = nlohmann::json::array();
  for (int l = 0; l < kLayers; ++l) {
    layers.push_back(
        {{"material", {{"value", kMaterials.front()}, {"choices", kMaterials}}},
         {"thickness_mm", {{"value", thicknesses.front()}, {"choices", thicknesses}}}});
  }
  layers.push_back({{"material", "VeroWhitePlus"}});
  return {{"materials", "materials/polyjet.json"},
          {"printer", "printers/j750.json"},
          {"subtree", {{"type", "layered"}, {"layers", layers}}},
          {"simulator",
           {{"type", "subsurface"},
            {"radius_mm", kRadiusMm},
            {"samples", kSamples},
            {"depth_mm", kLayers * kSteps.back() * kLayerMm + kLayerMm},
            {"step_mm", kLayerMm}}},
          {"metric", {{"type", "profile_l2"}}},
          {"reference",
           {"VeroCyan", 10 * kLayerMm, "VeroYellow", 5 * kLayerMm, "VeroMagenta", 20 * kLayerMm}}};
}

const BenchmarkDescription kSubsurfaceStack{
    "subsurface_stack",
    "One subsurface-scattering column (paper Fig. 8): 3 layers over white, each one of 4 materials "
    "and "
    "0.135/0.27/0.54 mm thick (1,728 stacks), profile_l2 to the reflectance profile of a hidden "
    "reference stack. Discrete, with the stack bound (branch and bound) and residuals.",
    "subsurface (multipole diffusion per layer, Fourier-Bessel profile, 100 radii over 16 mm)",
    "profile_l2",
    "the profile of a hidden stack (cyan 0.27 mm, yellow 0.135 mm, magenta 0.54 mm)",
    "3 layers x (one of 4 materials, 5/10/20 layers thick)"};

class SubsurfaceStack final : public TunerBenchmark {
 public:
  SubsurfaceStack(const Properties& /*properties*/, const BenchmarkContext& context)
      : TunerBenchmark(subsurface_stack_spec(), kSubsurfaceStack, context) {}
  static TypeDoc doc() { return benchmark_doc(kSubsurfaceStack); }

 private:
  void install_bound(Tuner& tuner, ReducerTree& /*tree*/, ReducerNode& /*node*/,
                     const PartContext& context) const override {
    const MaterialPalette& palette = context.palette;
    auto model = LayerStackModel::shared(
        palette, RadialBasis::shared(kSamples, kRadiusMm, context.cache), kLayerMm, context.cache);
    std::vector<LayerOptions> layers(kLayers);
    for (LayerOptions& layer : layers) {
      for (const std::string& m : kMaterials)
        layer.materials.push_back(palette.id(m, "bench problem subsurface_stack"));
      layer.steps = kSteps;
    }
    auto bound = std::make_shared<StackBound>(
        model, layers, palette.id("VeroWhitePlus", "bench problem subsurface_stack"));
    tuner.set_lower_bound([bound](std::span<const double> x, int assigned,
                                  const Observation& target) {
      return bound->lower_bound(x, assigned, static_cast<const RadialProfileObservation&>(target));
    });
  }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::BenchmarkRegistry, spec2fab::SubsurfaceStack, "subsurface_stack")

// The albedo simulator: the linear RGB diffuse reflectance of the stack of
// materials a subtree assigns below one surface point, by the calibrated
// Kubelka–Munk model of kubelka_munk.h.

#include <cmath>
#include <vector>

#include "albedo/kubelka_munk.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class AlbedoSimulator final : public SimulatorFor<AlbedoObservation> {
 public:
  AlbedoSimulator(const Properties& properties, const PartContext& context) {
    depth_mm_ = properties.get_in_range("depth_mm", 3.0, 1e-3, 1e3);
    step_mm_ = properties.get_in_range("step_mm", 0.005, 1e-5, depth_mm_);
    const auto at = properties.get<std::array<double, 2>>("at", {0.0, 0.0});
    lateral_a_ = at[0];
    lateral_b_ = at[1];
    for (MaterialId id = 0; id < context.palette.size(); ++id) {
      optics_.push_back(KubelkaMunkMaterial::from_material(context.palette.material(id)));
    }
    samples_.resize(static_cast<size_t>(std::ceil(depth_mm_ / step_mm_)));
  }

  std::string name() const override { return "albedo"; }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, AlbedoObservation& out) override {
    for (size_t i = 0; i < samples_.size(); ++i) {
      samples_[i] = material_at(subtree, (static_cast<double>(i) + 0.5) * step_mm_);
    }
    // What lies below the sampled depth counts as infinitely thick; then each
    // run of equal samples is one layer, composed from the bottom up.
    for (int c = 0; c < 3; ++c) {
      double reflectance = optics_[samples_.back()].rgb[c].reflectance_infinite();
      size_t end = samples_.size();
      while (end > 0) {
        size_t begin = end - 1;
        while (begin > 0 && samples_[begin - 1] == samples_[end - 1]) --begin;
        const double thickness = static_cast<double>(end - begin) * step_mm_;
        reflectance = optics_[samples_[begin]].rgb[c].reflectance_over(thickness, reflectance);
        end = begin;
      }
      out.rgb[c] = reflectance;
    }
  }

  static TypeDoc doc() {
    return {
        "Linear RGB albedo of the material stack a subtree assigns below a surface point: "
        "Kubelka-Munk layers calibrated to each material's dipole diffusion albedo and "
        "transport coefficient (optical data of the material library). Produces albedo.",
        {{"depth_mm", "number (mm)", "3", "depth sampled; what lies below counts as infinitely thick"},
         {"step_mm", "number (mm)", "0.005", "sampling step along the depth axis (finer than any layer)"},
         {"at", "[a, b]", "[0, 0]", "lateral position in the subtree's frame"}},
        R"({"type": "albedo", "depth_mm": 2})"};
  }

 private:
  MaterialId material_at(const ReducerNode& subtree, double depth) const {
    const QueryPoint point;
    LocalFrame frame{lateral_a_, lateral_b_, depth};
    const ReducerNode* node = &subtree;
    while (node->role() == ReducerNode::Role::geometry) {
      const auto route = static_cast<const GeometryNode*>(node)->route(point, frame);
      node = &node->child(static_cast<size_t>(route.child));
      frame = route.frame;
    }
    return static_cast<const MaterialNode*>(node)->material(point, frame);
  }

  double depth_mm_ = 3, step_mm_ = 0.005, lateral_a_ = 0, lateral_b_ = 0;
  std::vector<KubelkaMunkMaterial> optics_;  ///< by material id
  std::vector<MaterialId> samples_;          ///< sized once: simulate() does not allocate
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::AlbedoSimulator, "albedo")

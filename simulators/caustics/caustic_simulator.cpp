// The caustic simulator: the irradiance image a subtree's slab casts
// (caustic_tracer.h). The slab's bottom corner sits at origin_mm in the
// subtree's frame, (a, b) along its footprint and w up from its flat bottom;
// whatever the subtree assigns below its top surface is the slab, void above.

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/SparseCore>

#include "caustics/caustic_parts.h"
#include "caustics/caustic_tracer.h"
#include "core/error.h"
#include "core/parameter.h"
#include "reducer/height_surface.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class CausticSimulator final : public SimulatorFor<ImageObservation> {
 public:
  CausticSimulator(const Properties& properties, const PartContext& context)
      : CausticSimulator(CausticSlabConfig::read(properties, context.limits())) {}
  explicit CausticSimulator(const CausticSlabConfig& config) {
    thickness_mm_ = config.thickness_mm;
    origin_ = config.origin_mm;
    tracer_ = std::make_unique<CausticTracer>(config.setup);
    heights_.resize(tracer_->heights().size());
  }

  std::string name() const override { return "caustics"; }

  std::unique_ptr<Observation> make_observation() const override {
    auto out = std::make_unique<ImageObservation>();
    shape(*out);
    return out;
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, ImageObservation& out) override {
    read_heights(subtree);
    tracer_->set_heights(heights_);
    shape(out);
    flux_ = tracer_->render(out.pixels);
  }

  // Derivatives need the heights as functions of parameters: a Plane or
  // B-spline root cutting along w.
  bool differentiable(const ReducerNode& subtree) const override {
    const HeightSurface* surface = subtree.height_surface();
    return surface != nullptr && surface->height_axis() == 2;
  }

  void pull_back(const ReducerNode& subtree, std::span<const double> sensitivity, const SearchSpace& space,
                 std::span<double> gradient) override {
    if (!differentiable(subtree))
      throw InputError("caustics: derivatives need a Plane or B-spline node (axis w) at the tuned subtree's root");
    d_heights_.resize(heights_.size());
    tracer_->pull_back(sensitivity, d_heights_);
    const Eigen::SparseMatrix<double, Eigen::RowMajor>& jacobian = height_jacobian(subtree, space);
    Eigen::Map<Eigen::VectorXd>(gradient.data(), static_cast<Eigen::Index>(gradient.size())) +=
        jacobian.transpose() * Eigen::Map<const Eigen::VectorXd>(d_heights_.data(), static_cast<Eigen::Index>(d_heights_.size()));
  }

  std::vector<SimulatorInput> inputs() const override {
    return {{"exit_transmittance",
             "fraction of the light kept where it leaves the flat face, per cell of a grid over the footprint "
             "(a texture printed there)"}};
  }
  void set_input(std::string_view name, GridField value) override {
    if (name != "exit_transmittance") return Simulator::set_input(name, std::move(value));
    tracer_->set_exit_transmittance(value.cells, std::move(value.values));
  }
  const CausticFlux& last_flux() const { return flux_; }

  static TypeDoc doc() {
    return {
        "Irradiance image (1 channel, in units of the incident irradiance) cast on a receiver "
        "plane by collimated light through a transparent slab: flat bottom at w = 0, top the "
        "surface where the subtree turns from material to void. The top is meshed on a vertex "
        "grid and traced with Embree (refraction at every surface, total internal reflection, "
        "optional Fresnel); stratified, deterministic rays. Plane and B-spline roots give their "
        "height directly; any other subtree is searched along w with material queries. Input "
        "(set by a coupling such as texture_shadow): exit_transmittance, a filter over the flat face.",
        option_docs<CausticSlabConfig::Options>(),
        R"({"type": "caustics", "size_mm": [50, 50], "distance_mm": 200, "image": [240, 240]})"};
  }

 private:
  void shape(ImageObservation& out) const {
    const CausticSetup& s = tracer_->setup();
    out.width = s.image_width;
    out.height = s.image_height;
    out.channels = 1;
    out.pixels.resize(static_cast<size_t>(out.width) * static_cast<size_t>(out.height));
  }

  void read_heights(const ReducerNode& subtree) {
    const HeightSurface* surface = subtree.height_surface();
    const bool direct = surface != nullptr && surface->height_axis() == 2;
    for_each_slab_vertex(tracer_->setup(), origin_, [&](size_t k, double a, double b) {
      heights_[k] = (direct ? surface->surface_height(a, b) : search_height(subtree, a, b)) - origin_.z();
    });
  }

  // ∂(vertex height)/∂(free parameter): the heights are linear in the
  // surface's parameters, so it is built once per subtree and search space.
  const Eigen::SparseMatrix<double, Eigen::RowMajor>& height_jacobian(const ReducerNode& subtree,
                                                                      const SearchSpace& space) {
    const auto& entries = space.entries();
    const bool cached = &subtree == jacobian_subtree_ && entries.size() == jacobian_parameters_.size() &&
                        std::equal(entries.begin(), entries.end(), jacobian_parameters_.begin(),
                                   [](const SearchSpace::Entry& e, const Parameter* p) { return e.parameter == p; });
    if (cached) return jacobian_;
    jacobian_parameters_.clear();
    for (const SearchSpace::Entry& e : entries) jacobian_parameters_.push_back(e.parameter);
    jacobian_ = slab_height_jacobian(tracer_->setup(), origin_, *subtree.height_surface(), space);
    jacobian_subtree_ = &subtree;
    return jacobian_;
  }

  // The top of the material below (a, b): bisection on [0, thickness] for
  // the change from material to void, to 1e-7 of the thickness.
  double search_height(const ReducerNode& subtree, double a, double b) const {
    const QueryPoint point;
    auto solid_at = [&](double w) { return route_to_material(subtree, point, LocalFrame{a, b, w}) != kVoid; };
    const double bottom = origin_.z(), top = origin_.z() + thickness_mm_;
    if (solid_at(top)) return top;
    double low = bottom, high = top;
    while (high - low > 1e-7 * thickness_mm_) {
      const double mid = 0.5 * (low + high);
      (solid_at(mid) ? low : high) = mid;
    }
    return 0.5 * (low + high);
  }

  std::unique_ptr<CausticTracer> tracer_;
  double thickness_mm_ = 10;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::vector<double> heights_;
  CausticFlux flux_;
  std::vector<double> d_heights_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> jacobian_;
  const ReducerNode* jacobian_subtree_ = nullptr;
  std::vector<const Parameter*> jacobian_parameters_;
};

}  // namespace

std::unique_ptr<SimulatorFor<ImageObservation>> make_caustic_simulator(const CausticSlabConfig& config) {
  return std::make_unique<CausticSimulator>(config);
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::CausticSimulator, "caustics")

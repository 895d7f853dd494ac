// "facet_beam": where one facet of a clear slab sends collimated light —
// the micro-lens of facet caustics (paper §7.3, after Papas et al. 2011).
// A plane refracts a collimated beam into another collimated beam, so the
// ray through the facet's centre says where the facet's whole patch of
// light lands. A curved facet (a paraboloid) spreads its patch: then a grid
// of rays over the facet, each refracted at the surface's tangent plane,
// gives the spot's centroid and spread (the symmetric square root of its
// covariance), which a tuner matches to its Gaussian kernel's. Rays use the
// caustic tracer's own refraction (top_receiver_point: into the facet, out
// through the flat bottom, onto the receiver). Walls between facets and
// neighbours' shadows are left to the full tracer, which the facet
// translator runs on the finished surface.

#include <array>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "caustics/facet_beam_simulator.h"

#include "caustics/caustic_tracer.h"
#include "core/error.h"
#include "core/options.h"
#include "core/properties.h"
#include "reducer/height_surface.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class FacetBeamSimulator final : public SimulatorFor<VectorObservation> {
 public:
  using Options = FacetBeamOptions;

  FacetBeamSimulator(const Properties& properties, const PartContext& /*context*/)
      : FacetBeamSimulator(read_options<Options>(properties)) {}
  explicit FacetBeamSimulator(const Options& options) {
    size_ = {options.facet_mm[0], options.facet_mm[1]};
    origin_ = {options.facet_origin_mm[0], options.facet_origin_mm[1]};
    bottom_ = options.bottom_mm;
    // The slab's refraction, as the caustic tracer sends light from its top.
    slab_.refractive_index = options.refractive_index;
    slab_.receiver_distance_mm = options.distance_mm;
    light_ = Eigen::Vector3d(options.light[0], options.light[1], options.light[2]).normalized();
    spread_ = options.spread;
    rays_ = options.rays;
  }

  std::string name() const override { return "facet_beam"; }

  std::unique_ptr<Observation> make_observation() const override {
    auto out = std::make_unique<VectorObservation>();
    out->data.assign(spread_ ? 6 : 2, 0.0);
    return out;
  }

  void setup(const ReducerNode& subtree, const SimulationDomain& /*domain*/) override { surface_of(subtree); }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const HeightSurface& surface = surface_of(subtree);
    if (!spread_) {
      const Eigen::Vector2d landing = land(surface, 0.5 * size_);
      out.data.assign({landing.x(), landing.y()});
      return;
    }
    // The patch's light is uniform: rays at the centres of rays_ × rays_
    // equal cells weigh the same.
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
    for (int j = 0; j < rays_; ++j)
      for (int i = 0; i < rays_; ++i) {
        const Eigen::Vector2d local((i + 0.5) / rays_ * size_.x(), (j + 0.5) / rays_ * size_.y());
        const Eigen::Vector2d p = land(surface, local);
        mean += p;
        second += p * p.transpose();
      }
    const double n = static_cast<double>(rays_) * rays_;
    mean /= n;
    // A grid of r midpoints has (1 − 1/r²) of the patch's variance along each
    // side; the correction is exact where the lens maps the patch affinely.
    const double grid = static_cast<double>(rays_) * rays_ / (static_cast<double>(rays_) * rays_ - 1);
    const Eigen::Matrix2d covariance = grid * (second / n - mean * mean.transpose());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
    const Eigen::Matrix2d root = eigen.eigenvectors() *
                                 eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                                 eigen.eigenvectors().transpose();
    out.data.assign({mean.x(), mean.y(), root(0, 0), root(0, 1), root(1, 0), root(1, 1)});
  }

  static TypeDoc doc() {
    return {"Where a facet (a Plane or Paraboloid node cutting along w, clear below) sends "
            "collimated light: the receiver point, in world x and y (mm), of the ray through the "
            "facet's centre, refracted into the facet and out through the slab's flat bottom — a "
            "plane's whole beam lands around it, translated. With spread, a grid of rays gives "
            "the spot's centroid and the square root of its covariance, the shape a curved facet "
            "(a micro-lens) gives its light. For facet caustics.",
            option_docs<Options>(),
            R"({"type": "facet_beam", "facet_mm": [1.33, 1.33], "facet_origin_mm": [0, 0], "distance_mm": 200})"};
  }

 private:
  /// Where the ray through the facet point `local` (from its corner) lands,
  /// refracted at the surface's tangent plane there.
  Eigen::Vector2d land(const HeightSurface& surface, const Eigen::Vector2d& local) const {
    // Central differences: exact slopes for a plane or a paraboloid.
    const double step = 1e-3 * size_.minCoeff();
    const auto h = [&](double a, double b) { return surface.surface_height(a, b) - bottom_; };
    const double centre = h(local.x(), local.y());
    const double slope_a = (h(local.x() + step, local.y()) - h(local.x() - step, local.y())) / (2 * step);
    const double slope_b = (h(local.x(), local.y() + step) - h(local.x(), local.y() - step)) / (2 * step);
    const Eigen::Vector2d at = local + origin_;
    const Eigen::Vector2d xy[3] = {at, at + Eigen::Vector2d(step, 0), at + Eigen::Vector2d(0, step)};
    const double heights[3] = {centre, centre + step * slope_a, centre + step * slope_b};
    // A point one unit up the beam from the surface point.
    const Eigen::Vector3d start = Eigen::Vector3d(at.x(), at.y(), centre) + light_ / light_.z();
    return top_receiver_point(slab_, start, light_, xy, heights);
  }

  // The subtree as a height surface, remembered: the swap phase simulates
  // millions of times.
  const HeightSurface& surface_of(const ReducerNode& subtree) {
    if (&subtree != node_) {
      const HeightSurface* surface = subtree.height_surface();
      if (surface == nullptr || surface->height_axis() != 2)
        throw InputError("facet_beam: the tuned subtree must be a Plane or B-spline cutting along w (a facet)");
      node_ = &subtree;
      surface_ = surface;
    }
    return *surface_;
  }

  const ReducerNode* node_ = nullptr;
  const HeightSurface* surface_ = nullptr;
  Eigen::Vector2d size_, origin_;
  double bottom_ = 0;
  CausticSetup slab_;  ///< index and receiver distance: what top_receiver_point reads
  Eigen::Vector3d light_{0, 0, -1};
  bool spread_ = false;
  int rays_ = 8;
};

}  // namespace

std::unique_ptr<SimulatorFor<VectorObservation>> make_facet_beam_simulator(const FacetBeamOptions& options) {
  return std::make_unique<FacetBeamSimulator>(require_valid(options, "facet_beam"));
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::FacetBeamSimulator, "facet_beam")

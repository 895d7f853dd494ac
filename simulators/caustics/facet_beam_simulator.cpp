// "facet_beam": where one planar facet of a clear slab sends collimated
// light — the micro-lens of facet caustics (paper §7.3, after Papas et al.
// 2011). A plane refracts a collimated beam into another collimated beam, so
// the ray through the facet's centre says where the facet's whole patch of
// light lands; it is traced with the caustic tracer's own refraction
// (slab_receiver_point: into the facet, out through the flat bottom, onto
// the receiver). Walls between facets and neighbours' shadows are left to
// the full tracer, which the facet translator runs on the finished surface.

#include <array>
#include <cmath>

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
  struct Options {
    std::array<double, 2> facet_mm{};
    std::array<double, 2> facet_origin_mm{0, 0};
    double bottom_mm = 0, refractive_index = 1.5, distance_mm = 100;
    std::array<double, 3> light{0, 0, -1};

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.required(o.facet_mm, "facet_mm", Range::above(0), "the facet's size (its column)");
      d.number(o.facet_origin_mm, "facet_origin_mm", Range::any(),
               "world position (x, y) of the facet's (a, b) = (0, 0) corner");
      d.number(o.bottom_mm, "bottom_mm", Range::any(), "world height of the slab's flat bottom");
      d.number(o.refractive_index, "refractive_index", Range::closed(1, 4), "of the slab's material");
      d.number(o.light, "light", Range::any(), "direction (x, y, z) the light travels, z < 0");
      d.number(o.distance_mm, "distance_mm", Range::closed(1e-3, 1e6), "receiver plane below the slab's bottom");
    }
    bool check(std::string* why) const {
      if (light[2] < 0) return true;
      *why = "light: the light must travel downwards (z < 0)";
      return false;
    }
  };

  FacetBeamSimulator(const Properties& properties, const PartContext& /*context*/) {
    const Options options = read_options<Options>(properties);
    size_ = {options.facet_mm[0], options.facet_mm[1]};
    origin_ = {options.facet_origin_mm[0], options.facet_origin_mm[1]};
    bottom_ = options.bottom_mm;
    eta_ = options.refractive_index;
    distance_ = options.distance_mm;
    light_ = Eigen::Vector3d(options.light[0], options.light[1], options.light[2]).normalized();
  }

  std::string name() const override { return "facet_beam"; }

  std::unique_ptr<Observation> make_observation() const override {
    auto out = std::make_unique<VectorObservation>();
    out->data.assign(2, 0.0);
    return out;
  }

  void setup(const ReducerNode& subtree, const SimulationDomain& /*domain*/) override { surface_of(subtree); }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const HeightSurface& surface = surface_of(subtree);
    // The facet's plane through three points around its centre, in the
    // column's frame (a, b from its corner); world xy for the tracer.
    const Eigen::Vector2d centre = 0.5 * size_;
    const Eigen::Vector2d local[3] = {centre, centre + Eigen::Vector2d(0.25 * size_.x(), 0),
                                      centre + Eigen::Vector2d(0, 0.25 * size_.y())};
    Eigen::Vector2d xy[3];
    double h[3];
    for (int k = 0; k < 3; ++k) {
      xy[k] = local[k] + origin_;
      h[k] = surface.surface_height(local[k].x(), local[k].y()) - bottom_;
    }
    // A point one unit up the beam from the centre's surface point.
    const Eigen::Vector3d start = Eigen::Vector3d(xy[0].x(), xy[0].y(), h[0]) + light_ / light_.z();
    const Eigen::Vector2d landing = slab_receiver_point(start, light_, xy, h, eta_, -distance_);
    out.data.resize(2);
    out.data[0] = landing.x();
    out.data[1] = landing.y();
  }

  static TypeDoc doc() {
    return {"Where a planar facet (a Plane node cutting along w, clear below) sends collimated "
            "light: the receiver point, in world x and y (mm), of the ray through the facet's "
            "centre, refracted into the facet and out through the slab's flat bottom — the "
            "whole facet's beam lands around it, translated. For facet caustics.",
            option_docs<Options>(),
            R"({"type": "facet_beam", "facet_mm": [1.33, 1.33], "facet_origin_mm": [0, 0], "distance_mm": 200})"};
  }

 private:
  // The subtree as a height surface; the cast is remembered, since the swap
  // phase simulates millions of times.
  const HeightSurface& surface_of(const ReducerNode& subtree) {
    if (&subtree != node_) {
      const auto* surface = dynamic_cast<const HeightSurface*>(&subtree);
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
  double bottom_ = 0, eta_ = 1.5, distance_ = 100;
  Eigen::Vector3d light_{0, 0, -1};
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::FacetBeamSimulator, "facet_beam")

// The caustic simulator: the irradiance image a subtree's slab casts
// (caustic_tracer.h). The slab's bottom corner sits at origin_mm in the
// subtree's frame, (a, b) along its footprint and w up from its flat bottom;
// whatever the subtree assigns below its top surface is the slab, void above.

#include <cmath>

#include "caustics/caustic_tracer.h"
#include "reducer/height_surface.h"
#include "tuning/parts.h"

namespace spec2fab {
namespace {

class CausticSimulator final : public SimulatorFor<ImageObservation> {
 public:
  CausticSimulator(const Properties& properties, const PartContext& /*context*/) {
    CausticSetup s;
    const auto size = properties.get<std::array<double, 2>>("size_mm", {50.0, 50.0});
    s.width_mm = size[0];
    s.depth_mm = size[1];
    thickness_mm_ = properties.get_in_range("thickness_mm", 10.0, 1e-3, 1e4);
    const auto origin = properties.get<std::array<double, 3>>("origin_mm", {0.0, 0.0, 0.0});
    origin_ = Eigen::Vector3d(origin[0], origin[1], origin[2]);
    if (!origin_.allFinite()) properties.fail("origin_mm", "expected three finite numbers");
    const auto vertices = properties.get<std::array<int, 2>>("vertices", {121, 121});
    s.vertices_x = vertices[0];
    s.vertices_y = vertices[1];
    s.refractive_index = properties.get_in_range("refractive_index", 1.5, 1.0, 4.0);
    const auto light = properties.get<std::array<double, 3>>("light", {0.0, 0.0, -1.0});
    s.light_direction = Eigen::Vector3d(light[0], light[1], light[2]);
    s.receiver_distance_mm = properties.get_in_range("distance_mm", 100.0, 1e-3, 1e6);
    const auto receiver = properties.get<std::array<double, 2>>("receiver_mm", size);
    s.receiver_width_mm = receiver[0];
    s.receiver_depth_mm = receiver[1];
    const auto centre = properties.get<std::array<double, 2>>("receiver_centre_mm", {0.0, 0.0});
    s.receiver_centre_mm = Eigen::Vector2d(centre[0], centre[1]);
    const auto image = properties.get<std::array<int, 2>>("image", {240, 240});
    s.image_width = image[0];
    s.image_height = image[1];
    const auto rays = properties.get<std::array<int, 2>>("rays", {2 * image[0], 2 * image[1]});
    s.rays_x = rays[0];
    s.rays_y = rays[1];
    s.jitter = properties.get<bool>("jitter", true);
    s.fresnel = properties.get<bool>("fresnel", false);
    s.seed = static_cast<unsigned>(properties.get_in_range("seed", 1, 0, 4294967295.0));
    tracer_ = std::make_unique<CausticTracer>(s);
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

  const CausticTracer& tracer() const { return *tracer_; }
  const CausticFlux& last_flux() const { return flux_; }

  static TypeDoc doc() {
    return {
        "Irradiance image (1 channel, in units of the incident irradiance) cast on a receiver "
        "plane by collimated light through a transparent slab: flat bottom at w = 0, top the "
        "surface where the subtree turns from material to void. The top is meshed on a vertex "
        "grid and traced with Embree (refraction at every surface, total internal reflection, "
        "optional Fresnel); stratified, deterministic rays. Plane and B-spline roots give their "
        "height directly; any other subtree is searched along w with material queries.",
        {{"size_mm", "[x, y]", "[50, 50]", "slab footprint; the subtree's (a, b) run from its corner"},
         {"origin_mm", "[a, b, w]", "[0, 0, 0]", "the subtree's coordinates of the slab's bottom corner"},
         {"thickness_mm", "number (mm)", "10", "highest the top may be (search range along w)"},
         {"vertices", "[nx, ny]", "[121, 121]", "top-surface mesh vertices, corners included"},
         {"refractive_index", "number", "1.5", "of the slab's material"},
         {"light", "[x, y, z]", "[0, 0, -1]", "direction the light travels (z < 0)"},
         {"distance_mm", "number (mm)", "100", "receiver plane below the slab's bottom"},
         {"receiver_mm", "[x, y]", "size_mm", "receiver extent imaged"},
         {"receiver_centre_mm", "[x, y]", "[0, 0]", "receiver centre below the slab's centre"},
         {"image", "[width, height]", "[240, 240]", "pixels; row 0 at +y"},
         {"rays", "[nx, ny]", "2 × image", "stratified samples over the footprint"},
         {"jitter", "boolean", "true", "jitter samples within their strata (hashed, deterministic)"},
         {"fresnel", "boolean", "false", "weight transmissions by unpolarised Fresnel"},
         {"seed", "integer", "1", "jitter pattern"}},
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
    const CausticSetup& s = tracer_->setup();
    const auto* surface = dynamic_cast<const HeightSurface*>(&subtree);
    const bool direct = surface != nullptr && surface->height_axis() == 2;
    size_t k = 0;
    for (int j = 0; j < s.vertices_y; ++j) {
      for (int i = 0; i < s.vertices_x; ++i, ++k) {
        const Eigen::Vector2d xy = tracer_->vertex_xy(i, j);
        const double a = origin_.x() + xy.x() + 0.5 * s.width_mm, b = origin_.y() + xy.y() + 0.5 * s.depth_mm;
        heights_[k] = (direct ? surface->surface_height(a, b) : search_height(subtree, a, b)) - origin_.z();
      }
    }
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
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::CausticSimulator, "caustics")

// The stability simulator, its goal and metric (mass/stability.h).

#include "mass/stability.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>
#include <fmt/format.h>

#include "core/error.h"
#include "core/file_write.h"
#include "mass/mass_properties.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {

namespace {

// Distance from p to the segment [a, b].
double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}
}  // namespace

SupportPolygon SupportPolygon::of(const Mesh& mesh, const Vec3& gravity, double tolerance_mm) {
  SupportPolygon polygon;
  // Scaled before it is normalised: 1e-200 is a direction, and 1e200 must
  // not overflow to a zero one.
  polygon.down_ = (gravity / gravity.cwiseAbs().maxCoeff()).normalized();
  // Any basis of the floor's plane, right-handed with "up" (−down): hulls
  // counter-clockwise in (u, v) are counter-clockwise seen from above.
  const Vec3 up = -polygon.down_;
  const Vec3 helper = std::abs(up.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  polygon.u_ = (helper - helper.dot(up) * up).normalized();
  polygon.v_ = up.cross(polygon.u_);  // u × v = up
  double lowest = -std::numeric_limits<double>::infinity();
  for (const Vec3& vertex : mesh.vertices) lowest = std::max(lowest, vertex.dot(polygon.down_));
  polygon.floor_ = lowest;
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Kernel::Point_2> contact, hull;
  for (const Vec3& vertex : mesh.vertices) {
    if (vertex.dot(polygon.down_) >= lowest - tolerance_mm) {
      const Vec2 p = polygon.project(vertex);
      contact.emplace_back(p.x(), p.y());
    }
  }
  CGAL::convex_hull_2(contact.begin(), contact.end(), std::back_inserter(hull));  // counter-clockwise
  for (const auto& p : hull) polygon.hull_.emplace_back(p.x(), p.y());
  return polygon;
}

double SupportPolygon::margin_mm(const Vec3& point) const {
  if (hull_.empty() || !point.allFinite()) return kNaN;
  const Vec2 p = project(point);
  if (hull_.size() == 1) return -(p - hull_.front()).norm();
  double nearest = std::numeric_limits<double>::infinity();
  bool inside = hull_.size() >= 3;
  for (size_t i = 0; i < hull_.size(); ++i) {
    const Vec2& a = hull_[i];
    const Vec2& b = hull_[(i + 1) % hull_.size()];
    nearest = std::min(nearest, segment_distance(p, a, b));
    const Vec2 edge = b - a, to = p - a;
    if (edge.x() * to.y() - edge.y() * to.x() < 0) inside = false;  // right of a counter-clockwise edge
  }
  return inside ? nearest : -nearest;
}

double SupportPolygon::area_mm2() const {
  double twice = 0;
  for (size_t i = 0; i < hull_.size(); ++i) {
    const Vec2& a = hull_[i];
    const Vec2& b = hull_[(i + 1) % hull_.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

std::vector<Vec3> SupportPolygon::corners() const {
  std::vector<Vec3> out;
  for (const Vec2& p : hull_) out.push_back(p.x() * u_ + p.y() * v_ + floor_ * down_);
  return out;
}

std::vector<std::string> StabilityObservation::write_files(const std::filesystem::path& folder) const {
  std::string csv = "quantity,value,unit\n";
  const auto row = [&](const std::string& name, double value, const char* unit) {
    csv += fmt::format("{},{:.9g},{}\n", name, value, unit);
  };
  row("margin", margin_mm(), "mm");
  row("mass", mass_kg(), "kg");
  for (int k = 0; k < 3; ++k) row(std::string("centre_of_mass_") + "xyz"[k], data[kCentre + k], "mm");
  row("support_area", data[kSupportArea], "mm^2");
  write_file(folder / "stability.csv", csv);
  return {"stability.csv"};
}

bool StabilityOptions::check(std::string* why) const {
  // Every component finite (std::max would skip a NaN after the first), one of them not 0.
  const bool finite = std::isfinite(gravity[0]) && std::isfinite(gravity[1]) && std::isfinite(gravity[2]);
  if (finite && (gravity[0] != 0 || gravity[1] != 0 || gravity[2] != 0)) return true;
  *why = "gravity: a finite direction, not [0, 0, 0]";
  return false;
}

namespace {

class StabilitySimulator final : public SimulatorFor<StabilityObservation> {
 public:
  using Options = StabilityOptions;
  StabilitySimulator(const Properties& properties, const PartContext& context)
      : StabilitySimulator(read_options<Options>(properties), context) {}
  StabilitySimulator(const Options& options, const PartContext& context)
      : options_(options), mass_(make_mass_properties_simulator({options.voxel_mm}, context)) {}

  std::string name() const override { return "stability"; }
  bool reads_beyond_subtree() const override { return true; }  // the whole print stands or falls

  void setup(const ReducerNode& subtree, const SimulationDomain& domain) override {
    const Solid& solid = domain.require_solid(name());
    mass_->setup(subtree, domain);
    const auto& g = options_.gravity;
    support_ = SupportPolygon::of(solid.mesh(), Vec3(g[0], g[1], g[2]), options_.contact_tolerance_mm);
  }

  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, StabilityObservation& out) override {
    mass_->simulate(subtree, mass_properties_);
    const auto centre = mass_properties_.centre_mm();
    const Vec3 c(centre[0], centre[1], centre[2]);
    out.data.assign(StabilityObservation::kSize, kNaN);
    out.data[StabilityObservation::kMargin] = support_.margin_mm(c);  // NaN for a print that weighs nothing
    out.data[StabilityObservation::kMass] = mass_properties_.mass_kg();
    for (int k = 0; k < 3; ++k) out.data[StabilityObservation::kCentre + k] = c[k];
    out.data[StabilityObservation::kSupportArea] = support_.area_mm2();
  }

  std::string failure() const override { return mass_->failure(); }

  const SupportPolygon& support() const { return support_; }

  static TypeDoc doc() {
    return {"Whether the print stands on a flat floor (Make It Stand): the signed distance (mm) from its centre "
            "of mass, projected along gravity, to the edge of its support polygon (the convex hull of the "
            "surface's lowest points within contact_tolerance_mm), positive inside. The mass properties are "
            "mass_properties' (the same sampling). Produces stability: margin (mm), mass (kg), centre of mass "
            "(mm), support area (mm^2).",
            option_docs<Options>(), R"({"type": "stability", "gravity": [0, 0, -1], "voxel_mm": 0.5})"};
  }

 private:
  Options options_;
  std::unique_ptr<SimulatorFor<MassPropertiesObservation>> mass_;
  MassPropertiesObservation mass_properties_;
  SupportPolygon support_;
};

class StandsGoal final : public GoalFor<StabilityObservation> {
 public:
  struct Options {
    double margin_mm = 1;
    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.margin_mm, "margin_mm", Range::any(),
               "least distance from the centre's projection to the support polygon's edge");
    }
  };
  StandsGoal(const Properties& properties, const PartContext& /*context*/)
      : StandsGoal(read_options<Options>(properties).margin_mm) {}
  explicit StandsGoal(double margin_mm) {
    target_.data.assign(StabilityObservation::kSize, kNaN);
    target_.data[StabilityObservation::kMargin] = margin_mm;
  }
  std::string name() const override { return "stands"; }
  const StabilityObservation& typed_target() const override { return target_; }
  static TypeDoc doc() {
    return {"Stands with a margin: the centre of mass's projection at least margin_mm inside the support "
            "polygon. Describes stability.",
            option_docs<Options>(), R"({"type": "stands", "margin_mm": 2})"};
  }

 private:
  StabilityObservation target_;
};

class StandShortfall final : public MetricFor<StabilityObservation> {
 public:
  StandShortfall() = default;
  StandShortfall(const Properties& /*properties*/, const PartContext& /*context*/) {}
  std::string name() const override { return "stand_shortfall"; }
  using MetricFor::error;
  double error(const StabilityObservation& simulated, const StabilityObservation& target) const override {
    const double shortfall = target.margin_mm() - simulated.margin_mm();
    // NaN (a print that weighs nothing) stays NaN: the worst error.
    return shortfall > 0 || std::isnan(shortfall) ? shortfall : 0.0;
  }
  static TypeDoc doc() {
    return {"How far (mm) the centre of mass's projection falls short of the goal's margin inside the "
            "support polygon; 0 once the print stands with it. Compares stability.",
            {}, R"({"type": "stand_shortfall"})"};
  }
};

}  // namespace

std::unique_ptr<SimulatorFor<StabilityObservation>> make_stability_simulator(const StabilityOptions& options,
                                                                             const PartContext& context) {
  return std::make_unique<StabilitySimulator>(require_valid(options, "stability"), context);
}
std::unique_ptr<GoalFor<StabilityObservation>> make_stands_goal(double margin_mm) {
  return std::make_unique<StandsGoal>(margin_mm);
}
std::unique_ptr<MetricFor<StabilityObservation>> make_stand_shortfall_metric() {
  return std::make_unique<StandShortfall>();
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::SimulatorRegistry, spec2fab::StabilitySimulator, "stability")
SPEC2FAB_REGISTER(spec2fab::GoalRegistry, spec2fab::StandsGoal, "stands")
SPEC2FAB_REGISTER(spec2fab::MetricRegistry, spec2fab::StandShortfall, "stand_shortfall")

#pragma once
/// Whether a print stands (Make It Stand, Prévost et al. 2013): it stands
/// on a flat floor when its centre of mass, projected along gravity, lies
/// inside its support polygon — the convex hull of where it touches the
/// floor, taken as the lowest points of its surface (along gravity) within
/// a contact tolerance.
///
/// The "stability" simulator computes the mass properties as
/// mass_properties does (its stated grid) and reports the margin: the
/// signed distance (mm) from the centre's projection to the support
/// polygon's boundary, positive inside. The goal "stands" asks for a least
/// margin; the metric "stand_shortfall" is how far (mm) the print falls
/// short of it (0 once it stands with the margin).

#include <array>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/options.h"
#include "geometry/mesh.h"
#include "tuning/parts.h"

namespace spec2fab {

/// The support polygon in the floor's plane (normal to gravity).
class SupportPolygon {
 public:
  /// The convex hull of the mesh's vertices within `tolerance_mm` of its
  /// lowest along `gravity` (any finite length but 0). Fewer than three hull
  /// points (a point or a line of contact) give a polygon nothing stands on.
  static SupportPolygon of(const Mesh& mesh, const Vec3& gravity, double tolerance_mm);

  /// The signed distance (mm) from `point`'s projection along gravity to the
  /// polygon's boundary: positive inside, negative outside (always ≤ 0 for a
  /// point or a line of contact).
  double margin_mm(const Vec3& point) const;
  double area_mm2() const;
  /// The hull's corners in 3D, on the floor's plane, counter-clockwise seen
  /// from above (against gravity).
  std::vector<Vec3> corners() const;
  /// The floor plane's coordinates of a point (u, v), and its basis.
  Vec2 project(const Vec3& point) const { return {point.dot(u_), point.dot(v_)}; }
  const std::vector<Vec2>& hull() const { return hull_; }
  const Vec3& u() const { return u_; }
  const Vec3& v() const { return v_; }
  const Vec3& down() const { return down_; }

 private:
  Vec3 down_ = -Vec3::UnitZ(), u_ = Vec3::UnitX(), v_ = Vec3::UnitY();
  double floor_ = 0;         ///< the contact plane's position along down_
  std::vector<Vec2> hull_;  ///< counter-clockwise in (u, v)
};

/// The margin (mm), mass (kg), centre of mass (mm) and support area (mm²).
struct StabilityObservation final : ObservationOf<StabilityObservation> {
  static constexpr std::string_view kType = "stability";
  static constexpr std::size_t kMargin = 0, kMass = 1, kCentre = 2, kSupportArea = 5, kSize = 6;
  std::vector<double> data = std::vector<double>(kSize, 0.0);

  std::span<const double> values() const override { return data; }
  std::span<double> values() override { return data; }
  double margin_mm() const { return data[kMargin]; }
  double mass_kg() const { return data[kMass]; }
  Vec3 centre_mm() const { return {data[kCentre], data[kCentre + 1], data[kCentre + 2]}; }
  /// stability.csv: each quantity by name, with its unit.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

struct StabilityOptions {
  std::array<double, 3> gravity{0, 0, -1};
  double contact_tolerance_mm = 0.5;
  double voxel_mm = 0;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.gravity, "gravity", "direction of gravity (any length but 0)");
    d.number(o.contact_tolerance_mm, "contact_tolerance_mm", Range::at_least(0),
             "surface points this close to the lowest (along gravity) touch the floor");
    d.number(o.voxel_mm, "voxel_mm", Range::at_least(0),
             "edge of the mass sampling cells; 0: the solid's longest extent / 96", Default{"longest extent / 96"});
  }
  bool check(std::string* why) const;
};

std::unique_ptr<SimulatorFor<StabilityObservation>> make_stability_simulator(const StabilityOptions& options,
                                                                             const PartContext& context);
/// Stands with at least `margin_mm` between the centre's projection and the support polygon's edge.
std::unique_ptr<GoalFor<StabilityObservation>> make_stands_goal(double margin_mm);
std::unique_ptr<MetricFor<StabilityObservation>> make_stand_shortfall_metric();

}  // namespace spec2fab

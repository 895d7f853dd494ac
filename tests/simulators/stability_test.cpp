// The stability simulator (Make It Stand's test: the centre of mass over the
// support polygon) against closed forms: the support polygon of a box on
// its base and on its side, a point contact, a leaning prism whose centre
// lies beyond its base, a box whose one heavy end moves its centre; and the
// goal and metric, NaN included.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "mass/stability.h"
#include "materials/palette.h"
#include "simulators/mass_test_palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

TEST(SupportPolygon, ABoxStandsOnItsBase) {
  const Mesh box = make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 3);
  const SupportPolygon support = SupportPolygon::of(box, Vec3(0, 0, -1), 0.1);
  EXPECT_EQ(support.hull().size(), 4u);
  EXPECT_NEAR(support.area_mm2(), 40 * 30, 1e-9);
  EXPECT_NEAR(support.margin_mm(Vec3(20, 15, 10)), 15, 1e-9);     // the nearer edges, y = 0 and 30
  EXPECT_NEAR(support.margin_mm(Vec3(37, 15, 99)), 3, 1e-9);      // height does not count
  EXPECT_NEAR(support.margin_mm(Vec3(45, 15, 10)), -5, 1e-9);     // beyond the edge x = 40
  EXPECT_NEAR(support.margin_mm(Vec3(43, 34, 10)), -5, 1e-9);     // beyond the corner (40, 30): 3-4-5
  for (const Vec3& corner : support.corners()) EXPECT_NEAR(corner.z(), 0, 1e-12);
}

TEST(SupportPolygon, GravityAlongXPutsTheBoxOnItsSide) {
  const Mesh box = make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2);
  const SupportPolygon support = SupportPolygon::of(box, Vec3(-3, 0, 0), 0.1);  // any length
  EXPECT_NEAR(support.area_mm2(), 30 * 20, 1e-9);
  EXPECT_NEAR(support.margin_mm(Vec3(20, 15, 10)), 10, 1e-9);
  EXPECT_NEAR(support.margin_mm(Vec3(5, 15, 24)), -4, 1e-9);
  for (const Vec3& corner : support.corners()) EXPECT_NEAR(corner.x(), 0, 1e-12);
}

TEST(SupportPolygon, APointOfContactHoldsNothingUp) {
  const Mesh ball = make_sphere(10, 32, 16);  // one pole at the bottom
  const SupportPolygon support = SupportPolygon::of(ball, Vec3(0, 0, -1), 1e-6);
  EXPECT_EQ(support.hull().size(), 1u);
  EXPECT_NEAR(support.margin_mm(Vec3(0, 0, 0)), 0, 1e-9);  // balanced on the point, no margin
  EXPECT_NEAR(support.margin_mm(Vec3(3, 4, 0)), -5, 1e-9);
}

class Stability : public ::testing::Test {
 protected:
  Stability() : palette_(light_and_heavy()) {}
  StabilityObservation simulate(const Solid& solid, const std::string& json, double voxel_mm) {
    const Properties properties = Properties::parse(json, "tree.json");
    ReducerTree tree(properties, palette_);
    tree.bind(solid);
    StabilityOptions options;
    options.voxel_mm = voxel_mm;
    options.contact_tolerance_mm = 0.1;
    auto simulator = make_stability_simulator(options, PartContext{palette_});
    simulator->setup(tree.root(), SimulationDomain(tree, tree.root()));
    StabilityObservation out;
    simulator->simulate(tree.root(), out);
    return out;
  }
  MaterialPalette palette_;
};

// A prism on a 20 × 20 base whose top leans 30 mm along x: every horizontal
// section is the base moved by 30 z / 60, so the centre of mass (uniform
// density) is at x = 10 + 15 = 25, 5 mm beyond the base's edge x = 20.
TEST_F(Stability, ALeaningPrismFallsByItsClosedForm) {
  Mesh prism = make_box(Vec3(0, 0, 0), Vec3(20, 20, 60), 4);
  for (Vec3& v : prism.vertices) v.x() += 30 * v.z() / 60;
  const Solid solid(std::move(prism), UvSource::planar, 2);
  const StabilityObservation out = simulate(solid, R"({"type": "layered", "material": "light"})", 0.5);
  EXPECT_NEAR(out.centre_mm().x(), 25, 0.05);
  EXPECT_NEAR(out.margin_mm(), -5, 0.05);
  EXPECT_NEAR(out.data[StabilityObservation::kSupportArea], 400, 1e-9);
  EXPECT_NEAR(out.mass_kg(), 20 * 20 * 60 * 1e-6, 0.01 * 20 * 20 * 60 * 1e-6);
}

// A 40 × 30 × 20 box, heavy (3×) for x > 30: its centre moves from x = 20
// to (30·1·15 + 10·3·35) / (30 + 30) = 25; the nearest edges of its base
// are then y = 0 and 30, 15 mm away. Cells of 1 mm are not cut: exact.
TEST_F(Stability, AHeavyEndMovesTheCentreByTheClosedForm) {
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  const StabilityObservation out = simulate(box, R"({"type": "plane", "axis": "x", "offset_mm": 30,
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "heavy"}})",
                                            1.0);
  EXPECT_NEAR(out.centre_mm().x(), 25, 1e-9);
  EXPECT_NEAR(out.centre_mm().y(), 15, 1e-9);
  EXPECT_NEAR(out.margin_mm(), 15, 1e-9);
  EXPECT_NEAR(out.mass_kg(), (30 + 30) * 30 * 20 * 1e-6, 1e-12);
}

// A 60 × 10 × 10 bar, heavy (3×) for x > 40: centre at
// (40·20 + 20·3·50) / 100 = 38, 22 mm from the edge x = 60 but 5 mm from
// y's edges: the margin is the distance to the nearest edge, 5 mm.
TEST_F(Stability, MarginIsTheDistanceToTheNearestEdge) {
  const Solid bar(make_box(Vec3(0, 0, 0), Vec3(60, 10, 10), 2), UvSource::planar, 2);
  const StabilityObservation out = simulate(bar, R"({"type": "plane", "axis": "x", "offset_mm": 40,
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "heavy"}})",
                                            1.0);
  EXPECT_NEAR(out.centre_mm().x(), 38, 1e-9);
  EXPECT_NEAR(out.margin_mm(), 5, 1e-9);
}

TEST(StandShortfall, IsHowFarTheMarginFallsShortAndNaNStaysNaN) {
  const auto goal = make_stands_goal(2.0);
  const auto metric = make_stand_shortfall_metric();
  StabilityObservation simulated;
  simulated.data[StabilityObservation::kMargin] = -1.5;
  EXPECT_DOUBLE_EQ(metric->error(simulated, goal->target()), 3.5);
  simulated.data[StabilityObservation::kMargin] = 2.5;
  EXPECT_DOUBLE_EQ(metric->error(simulated, goal->target()), 0);
  simulated.data[StabilityObservation::kMargin] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(metric->error(simulated, goal->target()))) << "a print that weighs nothing never stands";
  std::string why;
  StabilityOptions zero;
  zero.gravity = {0, 0, 0};
  EXPECT_FALSE(zero.check(&why));
  EXPECT_THAT(why, HasSubstr("gravity"));
}

}  // namespace
}  // namespace spec2fab

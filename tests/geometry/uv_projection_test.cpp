#include "geometry/uv_projection.h"

#include <numbers>

#include <gtest/gtest.h>

namespace spec2fab {
namespace {

using std::numbers::pi;

Bounds box(const Vec3& lower, const Vec3& upper) {
  Bounds b;
  b.extend(lower);
  b.extend(upper);
  return b;
}

TEST(UvProjection, NamesRoundTrip) {
  for (UvSource s : {UvSource::mesh, UvSource::planar, UvSource::cylindrical, UvSource::spherical})
    EXPECT_EQ(parse_uv_source(to_string(s)), s);
  EXPECT_THROW(parse_uv_source("cubic"), std::invalid_argument);
}

TEST(UvProjection, PlanarUsesTheOtherTwoAxes) {
  const Bounds b = box(Vec3(0, 10, 20), Vec3(2, 14, 28));
  const UvProjection along_z(UvSource::planar, 2, b);
  EXPECT_TRUE(along_z(Vec3(0.5, 13, 99)).isApprox(Vec2(0.25, 0.75)));
  const UvProjection along_x(UvSource::planar, 0, b);  // u from y, v from z
  EXPECT_TRUE(along_x(Vec3(99, 11, 22)).isApprox(Vec2(0.25, 0.25)));
}

TEST(UvProjection, CylindricalAngleAndHeight) {
  const Bounds b = box(Vec3(-1, -1, 0), Vec3(1, 1, 10));
  const UvProjection p(UvSource::cylindrical, 2, b);
  EXPECT_NEAR(p(Vec3(1, 0, 5)).x(), 0, 1e-12);
  EXPECT_NEAR(p(Vec3(0, 1, 5)).x(), 0.25, 1e-12);
  EXPECT_NEAR(p(Vec3(-1, 0, 5)).x(), 0.5, 1e-12);
  EXPECT_NEAR(p(Vec3(0, -1, 5)).x(), 0.75, 1e-12);
  EXPECT_NEAR(p(Vec3(0, -1, 2.5)).y(), 0.25, 1e-12);
  EXPECT_GE(p(Vec3(1, -1e-12, 5)).x(), 0.99);  // just below the seam: u near 1
}

TEST(UvProjection, SphericalLongitudeAndColatitude) {
  const Bounds b = box(Vec3(-2, -2, -2), Vec3(2, 2, 2));
  const UvProjection p(UvSource::spherical, 2, b);
  const double theta = 0.7, phi = 4.0;
  const Vec3 point(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
  EXPECT_TRUE(p(2 * point).isApprox(Vec2(phi / (2 * pi), theta / pi)));
  EXPECT_NEAR(p(Vec3(0, 0, 2)).y(), 0, 1e-12);
  EXPECT_NEAR(p(Vec3(0, 0, -2)).y(), 1, 1e-12);
  // Pole on x: colatitude measured from +x, longitude in the (y, z) plane.
  const UvProjection px(UvSource::spherical, 0, b);
  EXPECT_TRUE(px(Vec3(0, 0, 1)).isApprox(Vec2(0.25, 0.5)));
}

}  // namespace
}  // namespace spec2fab

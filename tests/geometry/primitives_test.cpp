#include "geometry/primitives.h"

#include <numbers>

#include <gtest/gtest.h>

#include "geometry/mesh_check.h"
#include "geometry_test_support.h"

namespace spec2fab {
namespace {

using std::numbers::pi;

TEST(Primitives, SphereIsClosedWithAnalyticVolumeAndArea) {
  const double r = 10;
  const int segments = 64, rings = 32;
  const Mesh mesh = make_sphere(r, segments, rings);
  EXPECT_TRUE(find_mesh_defects(mesh).ok());
  EXPECT_EQ(mesh.triangles.size(), size_t(2 * segments * (rings - 1)));
  EXPECT_EQ(mesh.vertices.size(), size_t(segments * (rings - 1) + 2));
  EXPECT_EQ(mesh.corner_uv.size(), 3 * mesh.triangles.size());
  // A convex inscribed polyhedron that contains the sphere shrunk by the
  // tessellation error, so its volume lies between the two spheres' volumes.
  const double error = testing::sphere_tessellation_error(r, segments, rings);
  const double volume = 4 * pi / 3 * r * r * r;
  const double inner = 4 * pi / 3 * std::pow(r - error, 3);
  EXPECT_LT(mesh.signed_volume(), volume);
  EXPECT_GT(mesh.signed_volume(), inner);
  // Convex bodies nest, and so do their areas.
  EXPECT_LT(mesh.surface_area(), 4 * pi * r * r);
  EXPECT_GT(mesh.surface_area(), 4 * pi * (r - error) * (r - error));
}

TEST(Primitives, SphereVerticesLieOnTheSphere) {
  const Mesh mesh = make_sphere(3, 12, 7);
  for (const Vec3& v : mesh.vertices) EXPECT_NEAR(v.norm(), 3, 1e-12);
}

TEST(Primitives, SphereUvFollowsLongitudeAndColatitude) {
  const int segments = 16, rings = 8;
  const Mesh mesh = make_sphere(1, segments, rings);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const bool at_pole = mesh.triangles[t].minCoeff() == 0 ||
                         mesh.triangles[t].maxCoeff() == int(mesh.vertices.size()) - 1;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.vertices[mesh.triangles[t][k]];
      const Vec2& uv = mesh.corner_uv[3 * t + k];
      EXPECT_NEAR(uv.y(), std::acos(std::clamp(p.z(), -1.0, 1.0)) / pi, 1e-12);
      if (std::hypot(p.x(), p.y()) < 1e-9) continue;  // poles: any longitude
      double longitude = std::atan2(p.y(), p.x());
      if (longitude < -1e-12) longitude += 2 * pi;
      const double u = longitude / (2 * pi);
      // The seam column has u = 0 on one side and u = 1 on the other.
      EXPECT_TRUE(std::abs(uv.x() - u) < 1e-12 || std::abs(uv.x() - (u + 1)) < 1e-12)
          << "triangle " << t << " corner " << k << " uv " << uv.transpose() << " u " << u;
    }
    if (at_pole) continue;
    // Away from the poles a triangle spans one segment: no wrap-around jump.
    const double u0 = mesh.corner_uv[3 * t].x(), u1 = mesh.corner_uv[3 * t + 1].x(),
                 u2 = mesh.corner_uv[3 * t + 2].x();
    EXPECT_LE(std::max({u0, u1, u2}) - std::min({u0, u1, u2}), 1.0 / segments + 1e-12);
  }
}

TEST(Primitives, TorusIsClosedWithAnalyticVolume) {
  const double R = 20, r = 8;
  const int n = 96, m = 48;
  const Mesh mesh = make_torus(R, r, n, m);
  EXPECT_TRUE(find_mesh_defects(mesh).ok());
  EXPECT_EQ(mesh.triangles.size(), size_t(2 * n * m));
  EXPECT_EQ(mesh.vertices.size(), size_t(n * m));
  const double volume = 2 * pi * pi * R * r * r;
  // Inscribed polygons around the tube and around the ring.
  const double polygon_fraction =
      (m / (2 * pi)) * std::sin(2 * pi / m) * (n / (2 * pi)) * std::sin(2 * pi / n);
  EXPECT_LT(mesh.signed_volume(), volume);
  EXPECT_GT(mesh.signed_volume(), volume * (1 - 2 * (1 - polygon_fraction)));
  for (const Vec3& v : mesh.vertices) EXPECT_NEAR(testing::torus_distance(v, R, r), 0, 1e-12);
}

TEST(Primitives, TorusUvGoesAroundRingAndTube) {
  const int n = 12, m = 6;
  const Mesh mesh = make_torus(5, 2, n, m);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.vertices[mesh.triangles[t][k]];
      const Vec2& uv = mesh.corner_uv[3 * t + k];
      double phi = std::atan2(p.y(), p.x());
      if (phi < -1e-12) phi += 2 * pi;
      double psi = std::atan2(p.z(), std::hypot(p.x(), p.y()) - 5);
      if (psi < -1e-12) psi += 2 * pi;
      const double u = phi / (2 * pi), v = psi / (2 * pi);
      EXPECT_TRUE(std::abs(uv.x() - u) < 1e-12 || std::abs(uv.x() - u - 1) < 1e-12);
      EXPECT_TRUE(std::abs(uv.y() - v) < 1e-12 || std::abs(uv.y() - v - 1) < 1e-12);
    }
  }
}

TEST(Primitives, BoxIsClosedWithExactVolumeAndPerFaceUvs) {
  const Vec3 lower(-1, 2, 3), upper(4, 5, 9);
  for (int n : {1, 2, 5}) {
    const Mesh mesh = make_box(lower, upper, n);
    EXPECT_TRUE(find_mesh_defects(mesh).ok()) << n;
    EXPECT_EQ(mesh.triangles.size(), size_t(12 * n * n));
    EXPECT_EQ(mesh.vertices.size(), size_t(6 * n * n + 2));  // Euler: V = T/2 + 2
    EXPECT_NEAR(mesh.signed_volume(), 5 * 3 * 6, 1e-12);
    EXPECT_NEAR(mesh.surface_area(), 2 * (5 * 3 + 3 * 6 + 5 * 6), 1e-12);
    for (const Vec2& uv : mesh.corner_uv) {
      EXPECT_GE(uv.minCoeff(), 0);
      EXPECT_LE(uv.maxCoeff(), 1);
    }
  }
}

TEST(Primitives, RejectsBadArguments) {
  EXPECT_THROW(make_sphere(0, 8, 4), std::invalid_argument);
  EXPECT_THROW(make_sphere(1, 2, 4), std::invalid_argument);
  EXPECT_THROW(make_torus(1, 2, 8, 8), std::invalid_argument);
  EXPECT_THROW(make_box(Vec3(0, 0, 0), Vec3(1, 0, 1)), std::invalid_argument);
}

}  // namespace
}  // namespace spec2fab

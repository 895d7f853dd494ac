#include "geometry/solid.h"

#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "geometry/mesh_io.h"
#include "geometry/primitives.h"
#include "geometry/surface_field.h"
#include "geometry_test_support.h"

namespace spec2fab {
namespace {

using std::numbers::pi;
using ::testing::HasSubstr;

TEST(Solid, SphereSignedDistanceMatchesAnalytic) {
  const double r = 10;
  const int segments = 64, rings = 32;
  const Solid solid(make_sphere(r, segments, rings), UvSource::mesh);
  const double error = testing::sphere_tessellation_error(r, segments, rings);
  EXPECT_NEAR(solid.volume(), 4 * pi / 3 * r * r * r, 4 * pi * r * r * error);
  std::mt19937_64 rng(7);
  int disagreements = 0;
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p = testing::random_in_box(rng, Vec3::Constant(-14), Vec3::Constant(14));
    const double expected = testing::sphere_distance(p, r);
    const SurfacePoint s = solid.closest_point(p);
    ASSERT_NEAR(s.signed_distance, expected, error + 1e-9) << p.transpose();
    EXPECT_NEAR((s.position - p).norm(), std::abs(s.signed_distance), 1e-9);
    EXPECT_NEAR(s.barycentric.sum(), 1, 1e-12);
    EXPECT_GE(s.barycentric.minCoeff(), -1e-12);
    // The inside test can only differ from the sphere's within the error.
    if (solid.inside(p) != (expected < 0)) {
      ++disagreements;
      EXPECT_LT(std::abs(expected), error);
    }
  }
  EXPECT_LT(disagreements, 50);
}

TEST(Solid, BoxSignedDistanceIsExact) {
  const Vec3 lower(-3, -2, -1), upper(5, 2, 3);
  const Solid solid(make_box(lower, upper, 3), UvSource::mesh);
  EXPECT_NEAR(solid.volume(), 8 * 4 * 4, 1e-9);
  std::mt19937_64 rng(11);
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p =
        testing::random_in_box(rng, lower - Vec3::Constant(2), upper + Vec3::Constant(2));
    const double expected = testing::box_distance(p, lower, upper);
    ASSERT_NEAR(solid.signed_distance(p), expected, 1e-9) << p.transpose();
    EXPECT_EQ(solid.inside(p), expected < 0);
  }
  // Near edges and corners (where the sign comes from edge and vertex
  // pseudo-normals), both just outside and just inside.
  for (double offset : {1e-3, -1e-3, 0.3, -0.3}) {
    const Vec3 corner = upper + Vec3::Constant(offset);
    EXPECT_NEAR(solid.signed_distance(corner), testing::box_distance(corner, lower, upper), 1e-9);
    const Vec3 edge(1, upper.y() + offset, upper.z() + offset);
    EXPECT_NEAR(solid.signed_distance(edge), testing::box_distance(edge, lower, upper), 1e-9);
  }
}

TEST(Solid, TorusSignedDistanceMatchesAnalytic) {
  const double R = 20, r = 8;
  const int n = 96, m = 48;
  const Solid solid(make_torus(R, r, n, m), UvSource::mesh);
  const double error = testing::torus_tessellation_error(R, r, n, m);
  std::mt19937_64 rng(13);
  for (int i = 0; i < 5000; ++i) {
    const Vec3 p = testing::random_in_box(rng, Vec3(-32, -32, -12), Vec3(32, 32, 12));
    const double expected = testing::torus_distance(p, R, r);
    ASSERT_NEAR(solid.signed_distance(p), expected, error) << p.transpose();
    if (std::abs(expected) > error) {
      EXPECT_EQ(solid.inside(p), expected < 0) << p.transpose();
    }
  }
}

TEST(Solid, SphereMeshUvsAreLongitudeAndColatitude) {
  const int segments = 64, rings = 32;
  const Solid solid(make_sphere(10, segments, rings), UvSource::mesh);
  std::mt19937_64 rng(17);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 d = testing::random_direction(rng);
    const double theta = std::acos(d.z());
    double phi = std::atan2(d.y(), d.x());
    if (phi < 0) phi += 2 * pi;
    if (theta < 2 * pi / rings || theta > pi - 2 * pi / rings) continue;  // pole fans
    const SurfacePoint s = solid.closest_point((10 + 0.5 * (i % 3 - 1)) * d);
    const double du = s.uv.x() - phi / (2 * pi);  // on the seam either 0 or 1 is right
    EXPECT_NEAR(du - std::round(du), 0, 0.5 / segments) << d.transpose();
    EXPECT_NEAR(s.uv.y(), theta / pi, 0.5 / rings) << d.transpose();
  }
  // The seam: just below longitude 2π the last segment gives u near 1.
  const double phi = 2 * pi - 0.2 * (2 * pi / segments);
  const SurfacePoint before_seam =
      solid.closest_point(11 * Vec3(std::cos(phi), std::sin(phi), 0.1));
  EXPECT_GT(before_seam.uv.x(), 0.99);
  const SurfacePoint after_seam =
      solid.closest_point(11 * Vec3(std::cos(0.01), std::sin(0.01), 0.1));
  EXPECT_LT(after_seam.uv.x(), 0.01);
}

TEST(Solid, BoxFaceUvsAreLinearOnEachFace) {
  const Vec3 lower(0, 0, 0), upper(4, 2, 8);
  const Solid solid(make_box(lower, upper, 2), UvSource::mesh);
  // +x face: u along y, v along z.
  const SurfacePoint s = solid.closest_point(Vec3(5, 0.5, 6));
  EXPECT_TRUE(s.position.isApprox(Vec3(4, 0.5, 6)));
  EXPECT_NEAR(s.uv.x(), 0.25, 1e-12);
  EXPECT_NEAR(s.uv.y(), 0.75, 1e-12);
}

TEST(Solid, ProjectionsWhenTheMeshHasNoUvs) {
  Mesh mesh = make_sphere(10, 64, 32);
  mesh.corner_uv.clear();
  mesh.name = "ball.stl";
  try {
    Solid bad(mesh, UvSource::mesh);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("ball.stl: uv source 'mesh' needs texture coordinates, and "
                                    "the mesh has none; name a projection (planar, cylindrical, "
                                    "spherical)"));
  }
  const Solid solid(mesh, UvSource::spherical);
  EXPECT_EQ(solid.uv_source(), UvSource::spherical);
  const double theta = 1.0, phi = 2.5;
  const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  const SurfacePoint s = solid.closest_point(12 * d);
  // Spherical projection of the closest point, about the bounds' centre (the origin).
  const Vec3 q = s.position.normalized();
  double longitude = std::atan2(q.y(), q.x());
  if (longitude < 0) longitude += 2 * pi;
  EXPECT_NEAR(s.uv.x(), longitude / (2 * pi), 1e-12);
  EXPECT_NEAR(s.uv.y(), std::acos(q.z()) / pi, 1e-12);
  EXPECT_NEAR(s.uv.x(), phi / (2 * pi), 0.01);
}

TEST(Solid, InsideOutMeshIsFlippedAndOpenMeshRejected) {
  Mesh mesh = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  mesh.flip();
  const Solid solid(mesh, UvSource::planar);
  EXPECT_NEAR(solid.volume(), 1, 1e-12);
  EXPECT_TRUE(solid.inside(Vec3(0.5, 0.5, 0.5)));
  EXPECT_FALSE(solid.inside(Vec3(1.5, 0.5, 0.5)));

  Mesh open = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  open.triangles.pop_back();
  open.name = "open.obj";
  EXPECT_THROW(Solid(open, UvSource::planar), InputError);
}

TEST(Solid, ClosestPointOnTriangleAgreesWithClosestPoint) {
  const Solid solid(make_torus(5, 2, 32, 16), UvSource::mesh);
  std::mt19937_64 rng(19);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p = testing::random_in_box(rng, Vec3(-8, -8, -3), Vec3(8, 8, 3));
    const SurfacePoint best = solid.closest_point(p);
    const SurfacePoint same = solid.closest_point_on_triangle(best.triangle, p);
    EXPECT_EQ(same.position, best.position);
    EXPECT_EQ(same.signed_distance, best.signed_distance);
    EXPECT_EQ(same.uv, best.uv);
    // No triangle is closer (brute force).
    for (int t = 0; t < int(solid.mesh().triangles.size()); t += 7)
      EXPECT_GE(std::abs(solid.closest_point_on_triangle(t, p).signed_distance),
                std::abs(best.signed_distance) - 1e-12);
  }
}

TEST(Solid, LoadsFromFileAndQueriesInMillimetres) {
  testing::TempDir dir;
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), dir.path() / "cube.stl");
  const Solid solid(load_mesh(dir.path() / "cube.stl", 10), UvSource::planar);
  EXPECT_NEAR(solid.volume(), 1000, 1e-6);
  EXPECT_NEAR(solid.signed_distance(Vec3(5, 5, 5)), -5, 1e-6);
  EXPECT_EQ(solid.default_field_voxel(0), 10.0 / 256);
}

}  // namespace
}  // namespace spec2fab

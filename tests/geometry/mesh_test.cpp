#include "geometry/mesh.h"

#include <numbers>

#include <gtest/gtest.h>

#include "geometry/primitives.h"

namespace spec2fab {
namespace {

Mesh unit_tetrahedron() {
  Mesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

TEST(Mesh, TetrahedronVolumeAreaAndBounds) {
  const Mesh mesh = unit_tetrahedron();
  EXPECT_NEAR(mesh.signed_volume(), 1.0 / 6, 1e-15);
  // Three right triangles of area 1/2 and an equilateral one with side √2.
  EXPECT_NEAR(mesh.surface_area(), 1.5 + std::sqrt(3.0) / 2, 1e-14);
  const Bounds b = mesh.bounds();
  EXPECT_EQ(b.lower, Vec3(0, 0, 0));
  EXPECT_EQ(b.upper, Vec3(1, 1, 1));
  EXPECT_FALSE(b.empty());
}

TEST(Mesh, EmptyMeshHasEmptyBoundsAndNoVolume) {
  const Mesh mesh;
  EXPECT_TRUE(mesh.bounds().empty());
  EXPECT_EQ(mesh.signed_volume(), 0);
  EXPECT_EQ(mesh.surface_area(), 0);
}

TEST(Mesh, VolumeDoesNotDependOnPosition) {
  Mesh mesh = make_box(Vec3(1e4, 1e4, 1e4), Vec3(1e4 + 2, 1e4 + 3, 1e4 + 4), 3);
  EXPECT_NEAR(mesh.signed_volume(), 24, 1e-9);
  EXPECT_NEAR(mesh.surface_area(), 2 * (6 + 8 + 12), 1e-9);
}

TEST(Mesh, FlipNegatesVolumeAndReversesCornerUvs) {
  Mesh mesh = make_box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  const Mesh original = mesh;
  mesh.flip();
  EXPECT_NEAR(mesh.signed_volume(), -6, 1e-12);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    EXPECT_EQ(mesh.triangles[t][0], original.triangles[t][0]);
    EXPECT_EQ(mesh.triangles[t][1], original.triangles[t][2]);
    EXPECT_EQ(mesh.triangles[t][2], original.triangles[t][1]);
    EXPECT_EQ(mesh.corner_uv[3 * t + 1], original.corner_uv[3 * t + 2]);
    EXPECT_EQ(mesh.corner_uv[3 * t + 2], original.corner_uv[3 * t + 1]);
  }
  mesh.flip();
  EXPECT_EQ(mesh.triangles, original.triangles);
  EXPECT_EQ(mesh.corner_uv, original.corner_uv);
}

}  // namespace
}  // namespace spec2fab

#include "geometry/mesh_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "geometry/primitives.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

// Outward-facing tetrahedron on four given vertex indices of `mesh`, whose
// positions must make (a, b, c, d) positively oriented.
void add_tetrahedron(Mesh& mesh, int a, int b, int c, int d) {
  mesh.triangles.emplace_back(a, c, b);
  mesh.triangles.emplace_back(a, b, d);
  mesh.triangles.emplace_back(a, d, c);
  mesh.triangles.emplace_back(b, c, d);
}

std::string message_of(Mesh mesh) {
  try {
    require_closed_manifold(mesh);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(MeshCheck, PrimitivesHaveNoDefects) {
  EXPECT_TRUE(find_mesh_defects(make_sphere(1, 10, 6)).ok());
  EXPECT_TRUE(find_mesh_defects(make_torus(3, 1, 10, 6)).ok());
  EXPECT_TRUE(find_mesh_defects(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), 3)).ok());
}

TEST(MeshCheck, OpenBoxReportsItsBoundaryEdges) {
  // Each face of a box with 2×2 subdivisions is 8 triangles, and its rim
  // is 4·2 edges long.
  Mesh mesh = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), 2);
  mesh.triangles.erase(mesh.triangles.begin(), mesh.triangles.begin() + 8);
  mesh.corner_uv.clear();
  mesh.name = "bunny.stl";
  const MeshDefects d = find_mesh_defects(mesh);
  EXPECT_EQ(d.boundary_edges, 8);
  EXPECT_EQ(d.non_manifold_edges, 0);
  EXPECT_EQ(d.inconsistent_edges, 0);
  EXPECT_EQ(message_of(mesh), "bunny.stl: not closed: 8 boundary edges");
}

TEST(MeshCheck, TwoTetrahedraOnOneEdgeAreNotManifold) {
  Mesh mesh;
  mesh.name = "x.obj";
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0),  Vec3(0, 1, 0),
                   Vec3(0, 0, 1), Vec3(0, -1, 0), Vec3(0, 0, -1)};
  add_tetrahedron(mesh, 0, 1, 2, 3);
  add_tetrahedron(mesh, 0, 1, 4, 5);
  const MeshDefects d = find_mesh_defects(mesh);
  EXPECT_EQ(d.non_manifold_edges, 1);
  EXPECT_EQ(d.boundary_edges, 0);
  EXPECT_EQ(d.non_manifold_vertices, 0);
  EXPECT_THAT(message_of(mesh),
              HasSubstr("x.obj: not manifold: 1 edge shared by more than two triangles"));
}

TEST(MeshCheck, TwoTetrahedraOnOneVertexAreNotManifold) {
  Mesh mesh;
  mesh.name = "x.obj";
  mesh.vertices = {Vec3(0, 0, 0),  Vec3(1, 0, 0),  Vec3(0, 1, 0), Vec3(0, 0, 1),
                   Vec3(-1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, -1)};
  add_tetrahedron(mesh, 0, 1, 2, 3);
  add_tetrahedron(mesh, 0, 4, 6, 5);
  const MeshDefects d = find_mesh_defects(mesh);
  EXPECT_EQ(d.non_manifold_vertices, 1);
  EXPECT_EQ(d.non_manifold_edges, 0);
  EXPECT_EQ(d.boundary_edges, 0);
  EXPECT_EQ(d.inconsistent_edges, 0);
  EXPECT_THAT(message_of(mesh),
              HasSubstr("x.obj: not manifold: 1 vertex where separate sheets touch"));
}

TEST(MeshCheck, OneFlippedTriangleIsInconsistent) {
  Mesh mesh = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  mesh.name = "x.stl";
  std::swap(mesh.triangles[5][1], mesh.triangles[5][2]);
  EXPECT_EQ(find_mesh_defects(mesh).inconsistent_edges, 3);
  EXPECT_THAT(
      message_of(mesh),
      HasSubstr("x.stl: not consistently oriented: 3 edges traversed twice in the same direction"));
}

TEST(MeshCheck, ZeroAreaTriangleIsDegenerate) {
  // A tetrahedron whose edge 0–1 is split at vertex 4 on one side only; a
  // sliver (0, 1, 4) of three collinear points closes the gap.
  Mesh mesh;
  mesh.name = "x.stl";
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(0.5, 0, 0)};
  mesh.triangles = {{0, 2, 4}, {4, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 4, 1}};
  const MeshDefects d = find_mesh_defects(mesh);
  EXPECT_EQ(d.degenerate_triangles, 1);
  EXPECT_EQ(
      d.boundary_edges + d.non_manifold_edges + d.non_manifold_vertices + d.inconsistent_edges, 0);
  EXPECT_THAT(message_of(mesh), HasSubstr("x.stl: degenerate: 1 triangle with zero area"));
}

TEST(MeshCheck, RepeatedIndexIsDegenerate) {
  Mesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  mesh.triangles = {{0, 1, 1}};
  EXPECT_EQ(find_mesh_defects(mesh).degenerate_triangles, 1);
}

TEST(MeshCheck, InsideOutMeshIsFlipped) {
  Mesh mesh = make_sphere(2, 16, 8);
  const Mesh original = mesh;
  mesh.flip();
  ASSERT_LT(mesh.signed_volume(), 0);
  require_closed_manifold(mesh);
  EXPECT_GT(mesh.signed_volume(), 0);
  EXPECT_EQ(mesh.triangles, original.triangles);
  EXPECT_EQ(mesh.corner_uv, original.corner_uv);
}

TEST(MeshCheck, ClosedMeshWithoutVolumeIsRejected) {
  // Two copies of one triangle, back to back: closed and consistent, but flat.
  Mesh mesh;
  mesh.name = "flat.obj";
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 1}};
  EXPECT_TRUE(find_mesh_defects(mesh).ok());
  EXPECT_THAT(message_of(mesh), HasSubstr("flat.obj: encloses no volume"));
}

TEST(MeshCheck, GoodMeshPasses) { EXPECT_EQ(message_of(make_torus(3, 1, 12, 8)), "no error"); }

}  // namespace
}  // namespace spec2fab

namespace spec2fab {
namespace {

// `b`'s vertices and triangles after `a`'s: a mesh of two shells.
Mesh with_shell(Mesh a, const Mesh& b, bool flip_b = false) {
  const int offset = static_cast<int>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Eigen::Vector3i t : b.triangles) {
    if (flip_b) std::swap(t[1], t[2]);
    a.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  }
  a.corner_uv.clear();
  a.name = "shells.obj";
  return a;
}

const Mesh kOuter = make_box(Vec3(0, 0, 0), Vec3(10, 10, 10), 2);
const Mesh kInner = make_box(Vec3(3, 3, 3), Vec3(7, 7, 7), 2);

TEST(MeshShells, CavitiesFacingInwardsAndIslandsInThemAreAccepted) {
  Mesh hollow = with_shell(kOuter, kInner, /*flip_b=*/true);
  EXPECT_EQ(message_of(hollow), "no error");
  // A solid island in the cavity faces outwards again.
  EXPECT_EQ(message_of(with_shell(hollow, make_box(Vec3(4, 4, 4), Vec3(6, 6, 6)))), "no error");
  // Two parts side by side, both facing outwards.
  EXPECT_EQ(message_of(with_shell(kOuter, make_box(Vec3(20, 0, 0), Vec3(25, 5, 5)))), "no error");
}

TEST(MeshShells, APartTurnedInsideOutIsRefused) {
  EXPECT_THAT(message_of(with_shell(kOuter, make_box(Vec3(20, 0, 0), Vec3(25, 5, 5)), true)),
              HasSubstr("shells.obj: shell 2 of 2 (125 mm³) faces inwards inside 0 other shell(s): a part turned inside out"));
}

TEST(MeshShells, ASolidInsideAnotherIsRefused) {
  EXPECT_THAT(message_of(with_shell(kOuter, kInner)), HasSubstr("shell 2 of 2 (64 mm³) faces outwards inside 1 other shell(s)"));
}

TEST(MeshShells, OverlappingShellsAreRefused) {
  EXPECT_THAT(message_of(with_shell(kOuter, make_box(Vec3(5, 5, 5), Vec3(15, 15, 15)))),
              HasSubstr("shells.obj: 2 shells overlap"));
}

}  // namespace
}  // namespace spec2fab

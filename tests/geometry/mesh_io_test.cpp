#include "geometry/mesh_io.h"

#include <cstdint>
#include <cstring>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "geometry/mesh_check.h"
#include "geometry/primitives.h"
#include "geometry_test_support.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;

// A unit cube as 8 positions and 6 quads, with one [0,1]² texture square per
// face (OBJ indices are 1-based).
constexpr const char* kCubeObj = R"(# unit cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 1/1 4/2 3/3 2/4
f 5/1 6/2 7/3 8/4
f 1/1 2/2 6/3 5/4
f 2/1 3/2 7/3 6/4
f 3/1 4/2 8/3 7/4
f 4/1 1/2 5/3 8/4
)";

constexpr const char* kTetrahedronStl = R"(solid tetra
facet normal 0 0 -1
 outer loop
  vertex 0 0 0
  vertex 0 1 0
  vertex 1 0 0
 endloop
endfacet
facet normal 0 -1 0
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 0 1
 endloop
endfacet
facet normal -1 0 0
 outer loop
  vertex 0 0 0
  vertex 0 0 1
  vertex 0 1 0
 endloop
endfacet
facet normal 0.577 0.577 0.577
 outer loop
  vertex 1 0 0
  vertex 0 1 0
  vertex 0 0 1
 endloop
endfacet
endsolid tetra
)";

constexpr const char* kCubePly = R"(ply
format ascii 1.0
comment unit cube
element vertex 8
property float x
property float y
property float z
element face 6
property list uchar int vertex_indices
end_header
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
)";

constexpr const char* kCubeOff = R"(OFF
8 6 0
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
)";

std::string binary_stl_tetrahedron() {
  const float facets[4][12] = {
      {0, 0, -1, 0, 0, 0, 0, 1, 0, 1, 0, 0},
      {0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
      {-1, 0, 0, 0, 0, 0, 0, 0, 1, 0, 1, 0},
      {0.577f, 0.577f, 0.577f, 1, 0, 0, 0, 1, 0, 0, 0, 1},
  };
  std::string bytes(80, ' ');
  bytes.replace(0, 14, "binary fixture");  // must not start with "solid"
  const std::uint32_t count = 4;
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& facet : facets) {
    bytes.append(reinterpret_cast<const char*>(facet), sizeof(facet));
    bytes.append(2, '\0');  // attribute byte count
  }
  return bytes;
}

void expect_closed(const Mesh& mesh) {
  const MeshDefects d = find_mesh_defects(mesh);
  EXPECT_TRUE(d.ok()) << "boundary " << d.boundary_edges << " non-manifold " << d.non_manifold_edges
                      << " inconsistent " << d.inconsistent_edges;
}

TEST(MeshIo, ObjWithUvsIsTriangulatedWeldedAndKeepsCornerUvs) {
  TempDir dir;
  ::testing::internal::CaptureStdout();
  const Mesh mesh = load_mesh(dir.file("cube.obj", kCubeObj));
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(mesh.name, "cube.obj");
  EXPECT_EQ(mesh.vertices.size(), 8u);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  expect_closed(mesh);
  EXPECT_NEAR(mesh.signed_volume(), 1, 1e-12);
  ASSERT_TRUE(mesh.has_uv());
  ASSERT_EQ(mesh.corner_uv.size(), 36u);
  // Every corner's uv is the one its face gives to that position: on each
  // face the texture square's corners follow the quad's corners.
  const Vec2 square[4] = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const Vec3 corners[8] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0),
                           Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)};
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    // Find the quad holding all three corners of this triangle.
    int found = 0;
    for (const auto& quad : quads) {
      int matched = 0;
      Vec2 expected[3];
      for (int k = 0; k < 3; ++k)
        for (int q = 0; q < 4; ++q)
          if (mesh.vertices[mesh.triangles[t][k]] == corners[quad[q]]) {
            expected[k] = square[q];
            ++matched;
          }
      if (matched != 3) continue;
      ++found;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(mesh.corner_uv[3 * t + k], expected[k]);
    }
    EXPECT_EQ(found, 1) << "triangle " << t;
  }
}

// Line and point statements are no part of a solid, but well-formed ones
// are no reason to refuse a file (the check against Assimp 5.2.5's overrun
// on a one-vertex line, mesh_grammar.cpp, lets them through); nor is a
// free-form section, which Assimp skips (Blender writes `parm` lines there).
TEST(MeshIo, ObjLineStatementsAndFreeFormSectionsAreRead) {
  TempDir dir;
  const Mesh mesh = load_mesh(dir.file("lines.obj", std::string(kCubeObj) + "l 1 2\r\nl -1 -2 -3\rl 1/1 2/2\t\np 3\n"
                                                                            "cstype bspline\ndeg 3\nparm u 0 0 1 1\nend\n"));
  EXPECT_EQ(mesh.triangles.size(), 12u);
  expect_closed(mesh);
  EXPECT_NEAR(mesh.signed_volume(), 1, 1e-12);
}

// Assimp reads the shape alone: a material library beside an OBJ is not
// opened (the materials are the library's). Debian 12's Assimp (5.2.5)
// dereferences a null material for this one's anisotropy line and crashes
// the process, here where Assimp runs in it, as under mpirun.
TEST(MeshIo, ObjMaterialLibrariesAreNotOpened) {
  TempDir dir;
  dir.file("bad.mtl", "a 1\nKd 1 1 1\n");
  dir.file("cube.mtl", "a 1\n");  // what Assimp falls back to when bad.mtl cannot be opened
  const Mesh mesh = load_mesh(dir.file("cube.obj", "mtllib bad.mtl\n" + std::string(kCubeObj)), 1.0, default_limits(),
                              MeshReaderProcess::this_one);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_NEAR(mesh.signed_volume(), 1, 1e-12);
  // Nor the OBJ itself, by a path Assimp cleans up to its own ('//' → '/').
  const Mesh itself = load_mesh(dir.file("self.obj", "mtllib /self.obj\na 1\n" + std::string(kCubeObj)), 1.0,
                                default_limits(), MeshReaderProcess::this_one);
  EXPECT_EQ(itself.triangles.size(), 12u);
}

TEST(MeshIo, AsciiStl) {
  TempDir dir;
  const Mesh mesh = load_mesh(dir.file("tetra.stl", kTetrahedronStl));
  EXPECT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.triangles.size(), 4u);
  EXPECT_FALSE(mesh.has_uv());
  expect_closed(mesh);
  EXPECT_NEAR(mesh.signed_volume(), 1.0 / 6, 1e-12);
}

TEST(MeshIo, BinaryStlScaledToMillimetres) {
  TempDir dir;
  const Mesh mesh = load_mesh(dir.file("tetra_inches.stl", binary_stl_tetrahedron()), 25.4);
  EXPECT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.triangles.size(), 4u);
  expect_closed(mesh);
  EXPECT_NEAR(mesh.signed_volume(), std::pow(25.4, 3) / 6, 1e-9);
  EXPECT_NEAR(mesh.bounds().upper.x(), 25.4, 1e-12);
}

TEST(MeshIo, PlyAndOffQuadsAreTriangulated) {
  TempDir dir;
  for (const auto& [name, text] :
       {std::pair{"cube.ply", kCubePly}, std::pair{"cube.off", kCubeOff}}) {
    const Mesh mesh = load_mesh(dir.file(name, text));
    EXPECT_EQ(mesh.vertices.size(), 8u) << name;
    EXPECT_EQ(mesh.triangles.size(), 12u) << name;
    expect_closed(mesh);
    EXPECT_NEAR(mesh.signed_volume(), 1, 1e-12) << name;
  }
}

TEST(MeshIo, MissingFile) {
  try {
    load_mesh("/nonexistent/folder/bunny.stl");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bunny.stl: cannot read mesh: file not found"));
  }
}

TEST(MeshIo, UnreadableAndEmptyFilesAreInputErrors) {
  TempDir dir;
  for (const auto& [name, text] :
       {std::pair{"garbage.stl", "this is not a mesh\n"},
        std::pair{"points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"}, std::pair{"empty.ply", ""}}) {
    try {
      ::testing::internal::CaptureStdout();
      load_mesh(dir.file(name, text));
      ::testing::internal::GetCapturedStdout();
      ADD_FAILURE() << name << ": no error";
    } catch (const InputError& e) {
      EXPECT_EQ(::testing::internal::GetCapturedStdout(), "") << name;
      const std::string message = e.what();
      EXPECT_THAT(message, HasSubstr(name + std::string(": cannot read mesh: ")));
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

TEST(MeshIo, SavedMeshesLoadBack) {
  TempDir dir;
  const Mesh sphere = make_sphere(5, 24, 12);
  for (const char* name : {"sphere.obj", "sphere.stl", "sphere.ply"}) {
    const auto file = dir.path() / name;
    save_mesh(sphere, file);
    const Mesh loaded = load_mesh(file);
    EXPECT_EQ(loaded.triangles.size(), sphere.triangles.size()) << name;
    EXPECT_EQ(loaded.vertices.size(), sphere.vertices.size()) << name;
    expect_closed(loaded);
    EXPECT_NEAR(loaded.signed_volume(), sphere.signed_volume(), 1e-4 * sphere.signed_volume())
        << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "sphere.mtl"));
  // OBJ keeps the seam-correct corner uvs.
  const Mesh loaded = load_mesh(dir.path() / "sphere.obj");
  ASSERT_TRUE(loaded.has_uv());
  ASSERT_EQ(loaded.corner_uv.size(), sphere.corner_uv.size());
  for (size_t t = 0; t < loaded.triangles.size(); ++t) {
    // Triangles keep their order; match corners by position.
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = loaded.vertices[loaded.triangles[t][k]];
      int corner = -1;
      for (int j = 0; j < 3; ++j)
        if ((sphere.vertices[sphere.triangles[t][j]] - p).norm() < 1e-5) corner = j;
      ASSERT_GE(corner, 0);
      EXPECT_NEAR((loaded.corner_uv[3 * t + k] - sphere.corner_uv[3 * t + corner]).norm(), 0, 1e-6);
    }
  }
}

TEST(MeshIo, SaveRejectsUnknownExtension) {
  TempDir dir;
  EXPECT_THROW(save_mesh(make_box(Vec3(0, 0, 0), Vec3(1, 1, 1)), dir.path() / "box.xyz"),
               InputError);
}

}  // namespace
}  // namespace spec2fab

// Writes the meshes in datasets/meshes/ from the primitives in
// framework/geometry/primitives.h (see datasets/README.md):
//   build/tools/make_meshes datasets/meshes

#include <filesystem>
#include <iostream>

#include "geometry/mesh_io.h"
#include "geometry/primitives.h"

int main(int argc, char** argv) {
  using namespace spec2fab;
  if (argc != 2) {
    std::cerr << "usage: make_meshes OUTPUT_FOLDER\n";
    return 2;
  }
  const std::filesystem::path out = argv[1];
  std::filesystem::create_directories(out);
  save_mesh(make_sphere(25.0, 64, 32), out / "sphere_r25.obj");
  save_mesh(make_sphere(25.0, 32, 16), out / "sphere_r25_coarse.obj");
  save_mesh(make_torus(20.0, 8.0, 64, 24), out / "torus_R20_r8.obj");
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), out / "box_40x30x20.stl");
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(60, 60, 8), 2), out / "board_60x60x8.stl");
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(100, 10, 10), 1), out / "beam_100x10x10.stl");
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(60, 40, 10), 1), out / "block_60x40x10.stl");
  save_mesh(make_box(Vec3(0, 0, 0), Vec3(60, 40, 20), 1), out / "book_60x40x20.stl");
  // Shapes that topple printed solid (the stand translator's experiments).
  // A tower on a 20 x 20 mm base whose top leans 22 mm along x: its centre
  // of mass lies 1 mm beyond the base's edge.
  Mesh tower = make_box(Vec3(0, 0, 0), Vec3(20, 20, 60), 4);
  for (Vec3& v : tower.vertices) v.x() += 22.0 * v.z() / 60.0;
  save_mesh(tower, out / "leaning_tower_20x20x60.stl");
  // A crane: a 16 x 16 mm column 60 mm tall and an arm 12 mm thick reaching
  // 56 mm along x at its top (a Γ in x, z, 16 mm deep in y): its centre of
  // mass lies 1.3 mm beyond the column's foot.
  save_mesh(make_extrusion({{16, 48}, {56, 48}, {56, 60}, {0, 60}, {0, 0}, {16, 0}}, 16), out / "crane_56x16x60.stl");
  std::cout << "wrote meshes to " << out.string() << "\n";
  return 0;
}

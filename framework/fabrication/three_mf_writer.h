#pragma once
/// A 3MF file (lib3mf) of a multi-material print: one mesh object per
/// material, named after it, coloured with its display colour through a base
/// material group, and one build item each (the objects share one coordinate
/// frame, so they assemble into the print). Units: millimetres.

#include <filesystem>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "materials/palette.h"

namespace spec2fab {

/// `meshes[id]` is the surface of material id (empty meshes are skipped).
/// Writes through a temporary name. Throws std::runtime_error on failure.
void write_three_mf(const std::vector<Mesh>& meshes, const MaterialPalette& palette,
                    const std::filesystem::path& file);

/// What a 3MF file holds, read back with lib3mf: per mesh object its name,
/// vertex and triangle counts (for tests and `export` checks).
struct ThreeMfObject {
  std::string name;
  unsigned vertices = 0, triangles = 0;
  bool manifold_and_oriented = false;
};
std::vector<ThreeMfObject> read_three_mf_objects(const std::filesystem::path& file);

}  // namespace spec2fab

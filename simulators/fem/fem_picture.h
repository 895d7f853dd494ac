#pragma once
/// A picture of a tet mesh's boundary at rest (left) and deformed (right),
/// both coloured by displacement magnitude (viridis, with a scale
/// bar), seen from one oblique orthographic camera so the two share a scale.

#include <filesystem>
#include <vector>

#include "fem/tet_mesh.h"

namespace spec2fab::fem {

void write_deformation_picture(const TetMesh& mesh, const std::vector<Face>& boundary,
                               const std::vector<double>& displacement_mm,
                               const std::filesystem::path& file);

}  // namespace spec2fab::fem

#pragma once
/// Fewer triangles for viewing: a mesh simplified by edge collapse with
/// Lindstrom–Turk costs (CGAL's Surface_mesh_simplification), so a
/// report can carry a print's surfaces at a few MB.

#include <cstddef>

#include "geometry/mesh.h"

namespace spec2fab {

/// `mesh` with at most about `target_triangles` triangles (itself when it has
/// no more). Open or non-manifold meshes are decimated too: the soup is
/// repaired and oriented first (CGAL's polygon soup processing), which may
/// duplicate vertices at non-manifold points. Corner uvs are dropped.
Mesh decimate_for_viewing(const Mesh& mesh, std::size_t target_triangles);

}  // namespace spec2fab

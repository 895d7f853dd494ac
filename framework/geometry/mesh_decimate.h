#pragma once
/// Fewer triangles for viewing: a mesh simplified with meshoptimizer's
/// quadric edge collapse (meshopt_simplify), falling back to its vertex
/// clustering (meshopt_simplifySloppy) where topology blocks the target —
/// so a report carries a print's surfaces at a few MB. Fast enough for the
/// 1.8 M-triangle caustic slab (CGAL's edge collapse took 470 s there).

#include <cstddef>

#include "geometry/mesh.h"

namespace spec2fab {

/// `mesh` with at most about `target_triangles` triangles: itself (its
/// vertices and triangles) when it has no more, else the simplified mesh
/// with only the vertices its triangles use. Corner uvs are dropped.
Mesh decimate_for_viewing(const Mesh& mesh, std::size_t target_triangles);

}  // namespace spec2fab

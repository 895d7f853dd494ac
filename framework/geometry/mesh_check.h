#pragma once
/// Topology checks a Solid needs: closed, manifold, consistently oriented.

#include <string>

#include "geometry/mesh.h"

namespace spec2fab {

struct MeshDefects {
  long long boundary_edges = 0;            ///< edges used by one triangle
  long long non_manifold_edges = 0;        ///< edges used by three or more triangles
  long long non_manifold_vertices = 0;     ///< vertices whose triangles form more than one fan
  long long inconsistent_edges = 0;        ///< edges two triangles traverse in the same direction
  long long degenerate_triangles = 0;      ///< repeated vertex indices or zero area
  bool ok() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && non_manifold_vertices == 0 &&
           inconsistent_edges == 0 && degenerate_triangles == 0;
  }
};

MeshDefects find_mesh_defects(const Mesh& mesh);

/// Throws InputError naming the file and the first defect, e.g.
/// `bunny.stl: not closed: 14 boundary edges`, or
/// `cup.obj: not consistently oriented: 3 edges traversed twice in the same direction`.
/// A closed, consistent mesh whose triangles all face inwards is flipped, not
/// rejected; a mesh enclosing no volume is rejected.
void require_closed_manifold(Mesh& mesh);

}  // namespace spec2fab

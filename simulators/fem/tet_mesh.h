#pragma once
/// A tetrahedral mesh in millimetres: nodes and positively oriented tets
/// (det[x1−x0, x2−x0, x3−x0] > 0), as TetGen makes them and the FEM solves on.

#include <array>
#include <utility>
#include <vector>

#include "geometry/mesh.h"

namespace spec2fab::fem {

using Tet = std::array<int, 4>;
using Face = std::array<int, 3>;

/// One key for the edge between nodes a and b, whichever way round.
inline unsigned long long edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<unsigned long long>(a) << 32) | static_cast<unsigned int>(b);
}

struct TetMesh {
  std::vector<Vec3> nodes;  ///< #N rest positions (mm)
  std::vector<Tet> tets;    ///< #T node indices, positively oriented

  double volume(size_t tet) const;  ///< mm³ (signed: positive when oriented)
  Vec3 centroid(size_t tet) const;
  double total_volume() const;
  /// Faces that belong to one tet only, oriented outwards (counter-clockwise
  /// seen from outside), in a deterministic order.
  std::vector<Face> boundary_faces() const;
};

/// The nodes in the order of a Morton (Z-order) curve through their
/// positions, ties in their own order: neighbours in space get nearby
/// numbers, so a matrix numbered this way has a small bandwidth and its
/// products touch memory in runs (and a contiguous run of it is a compact
/// piece of the mesh, which is how the distributed solver splits it).
std::vector<int> morton_order(const std::vector<Vec3>& nodes);

/// Writes the boundary of `mesh`, displaced by `displacement_mm` (3 per node,
/// may be empty), as a triangle mesh.
Mesh boundary_surface(const TetMesh& mesh, const std::vector<Face>& faces,
                      const std::vector<double>& displacement_mm);

}  // namespace spec2fab::fem

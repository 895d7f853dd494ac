#pragma once
/// Exact volume integrals of a closed triangle mesh clipped to an
/// axis-aligned box: the mass properties of a voxel cell or a layer of a
/// shape without sampling it.
///
/// The mesh's solid is the signed sum of the tetrahedra that join a point
/// (beyond the mesh along −x, level with the box) to each triangle (the
/// winding number, for any closed mesh). Each tetrahedron that reaches the
/// box is clipped to it (a convex polyhedron cut by up to six planes) and
/// integrated exactly: the clipped pieces add up to the solid within the
/// box, with no capping of the cut faces. Cost: the triangles times the
/// share of them across the box's shadow along x.

#include <array>

#include <Eigen/Geometry>

#include "geometry/mesh.h"

namespace spec2fab {

/// ∫ over (the mesh's solid ∩ box) of 1, x, y, z, x², y², z², xy, xz, yz
/// (mm³, mm⁴, mm⁵), with x, y, z measured from `origin`. The mesh must be
/// closed; its orientation does not matter (the sign is taken from its
/// volume). An empty or flat box, or one that misses the solid, gives
/// zeros; an unbounded one is refused (std::invalid_argument).
std::array<double, 10> box_moments(const Mesh& mesh, const Eigen::AlignedBox3d& box, const Vec3& origin);

}  // namespace spec2fab

#pragma once
/// Local frames: where a query point lies as seen by one node of the tree.
///
/// Every node reads the point in the frame its parent hands it: two lateral
/// coordinates (a, b) and one along the node's depth/height axis (w). The root
/// frame is the world, in mm: (a, b, w) = (x, y, z). A Stratum hands its shell
/// (u, v, depth below the surface); a Column hands each column coordinates
/// relative to the column's corner; a Plane or BSpline hands each side the
/// lateral coordinates and the distance from the cut surface. Because nodes
/// only read frames, one tree works on any shape.

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "geometry/surface_field.h"

namespace spec2fab {

struct LocalFrame {
  double a = 0, b = 0;  ///< lateral coordinates
  double w = 0;         ///< along the depth/height axis
};

/// The extent of a frame's coordinates over the solid, and what they mean —
/// nodes use it to choose defaults (a Column spreads its columns over it).
struct FrameDomain {
  enum class Kind { world, surface, column, plane };
  Kind kind = Kind::world;
  Eigen::AlignedBox3d box;  ///< (a, b, w) ranges
};

/// One query point with what the solid says about it, computed once per point
/// and shared by every node on the way down.
struct QueryPoint {
  Vec3 world = Vec3::Zero();
  SurfaceSample surface;
};

}  // namespace spec2fab

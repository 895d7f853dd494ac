#pragma once
/// Surface (u,v) when a mesh has no texture coordinates, or when the user asks
/// for a projection instead of them.

#include <string>

#include "geometry/mesh.h"

namespace spec2fab {

enum class UvSource {
  mesh,         ///< the mesh's own texture coordinates (interpolated on each triangle)
  planar,       ///< (u,v) from the two axes other than `axis`, in x, y, z order, normalised to the bounds
  cylindrical,  ///< u = angle around `axis` / 2π, v = height along it, normalised to the bounds
  spherical,    ///< u = longitude / 2π, v = colatitude / π, about the bounds' centre, pole on `axis`
};

/// "mesh", "planar", "cylindrical", "spherical"; throws std::invalid_argument otherwise.
UvSource parse_uv_source(const std::string& name);
std::string to_string(UvSource source);

/// Maps surface points to (u,v) ∈ [0,1]² by a named projection about the
/// mesh's bounds.
class UvProjection {
 public:
  UvProjection(UvSource source, int axis, const Bounds& bounds);
  Vec2 operator()(const Vec3& surface_point) const;

 private:
  UvSource source_;
  int axis_, a_, b_;  ///< projection axis and the two others
  Bounds bounds_;
};

}  // namespace spec2fab

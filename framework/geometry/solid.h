#pragma once
/// A closed solid: inside tests, signed distance, closest surface point with
/// its (u,v), bounds. Exact queries go through an Embree BVH (point queries);
/// batch queries near the surface go through a SurfaceField (OpenVDB).

#include <memory>

#include "core/limits.h"
#include "geometry/mesh.h"
#include "geometry/uv_projection.h"

namespace spec2fab {

class SurfaceField;

/// The surface point closest to a query point.
struct SurfacePoint {
  Vec3 position = Vec3::Zero();     ///< closest point on the surface (mm)
  int triangle = -1;                ///< triangle it lies on
  Vec3 barycentric = Vec3::Zero();  ///< its barycentric coordinates in that triangle
  Vec2 uv = Vec2::Zero();           ///< surface coordinates at it
  double signed_distance = 0;       ///< from the query point (mm); negative inside
};

class Solid {
 public:
  /// Checks the mesh (require_closed_manifold; may flip it), builds the BVH.
  /// `uv_source` mesh needs texture coordinates (InputError otherwise);
  /// `uv_axis` (0,1,2) is the projection axis for the named projections.
  Solid(Mesh mesh, UvSource uv_source, int uv_axis = 2);
  ~Solid();
  Solid(const Solid&) = delete;
  Solid& operator=(const Solid&) = delete;

  const Mesh& mesh() const;
  const Bounds& bounds() const;
  double volume() const;  ///< mm³
  UvSource uv_source() const;

  /// Exact queries (thread-safe).
  SurfacePoint closest_point(const Vec3& point) const;
  double signed_distance(const Vec3& point) const;
  bool inside(const Vec3& point) const { return signed_distance(point) < 0; }

  /// The closest point to `point` on one given triangle, with (u,v) and a
  /// signed distance whose sign comes from the angle-weighted pseudo-normal of
  /// the feature (face, edge or vertex) it lies on — exact when that triangle
  /// is the closest one of the whole mesh.
  SurfacePoint closest_point_on_triangle(int triangle, const Vec3& point) const;

  /// The narrow-band field for batch queries, covering at least
  /// `interior_band_mm` below the surface, with cells of `voxel_mm` (0: chosen
  /// from the bounds). Built on first request and rebuilt only when a wider
  /// band or finer voxel is asked for; not thread-safe to build, so call it
  /// before querying in parallel.
  const SurfaceField& field(double interior_band_mm, double voxel_mm = 0) const;

  /// The voxel size `field` chooses when given 0: the largest extent / 256,
  /// coarsened where needed so that a band of `interior_band_mm` holds about
  /// two million voxels at most (build time and memory stay bounded; accuracy
  /// near the surface comes from the exact projection, not the voxel size).
  double default_field_voxel(double interior_band_mm) const;
  /// About how many voxels field(interior_band_mm, voxel_mm) holds, before
  /// it is built: the band's volume over the surface in voxels.
  double field_band_voxels(double interior_band_mm, double voxel_mm) const;
  /// Why field(interior_band_mm, voxel_mm) must not be built — its voxels
  /// past the field_band_voxels limit, with their memory and build time —
  /// or nothing.
  std::string field_beyond_limit(double interior_band_mm, double voxel_mm, const Limits& limits) const;

 private:
  friend class SurfaceField;  // its hot path projects onto triangles inline
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab

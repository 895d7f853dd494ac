#pragma once
/// A narrow-band acceleration structure over a Solid (OpenVDB): for a query
/// point it answers inside/outside everywhere, and depth below the surface and
/// surface (u,v) within a band around it, at a cost independent of the
/// triangle count.
///
/// Built with OpenVDB's meshToVolume, which gives a level set and, for every
/// voxel of the band, the index of the closest triangle. A query looks up the
/// triangle of its nearest voxel and projects exactly onto it
/// (Solid::closest_point_on_triangle); when the projection lands on an edge or
/// a corner it walks on to neighbouring triangles while they are closer. So
/// depth and (u,v) are exact whenever that reaches the closest triangle (it
/// almost always does); otherwise the depth error is below one voxel diagonal.
/// The sign comes from the level set wherever the whole voxel lies on one side
/// of the surface, and from angle-weighted pseudo-normals nearer to it. Beyond
/// the band the sign comes from the level set.

#include <memory>

#include "geometry/mesh.h"

namespace spec2fab {

class Solid;

struct SurfaceSample {
  bool inside = false;
  bool near_surface = false;  ///< within the band: depth_mm and uv are valid
  double depth_mm = 0;        ///< distance below the surface (≥ 0 inside); beyond the band: the band width
  Vec2 uv = Vec2::Zero();
};

class SurfaceField {
 public:
  SurfaceField(const Solid& solid, double voxel_mm, double interior_band_mm,
               double exterior_band_mm);
  ~SurfaceField();
  SurfaceField(const SurfaceField&) = delete;
  SurfaceField& operator=(const SurfaceField&) = delete;

  double voxel_mm() const;
  double interior_band_mm() const;
  /// Number of active (band) voxels, for memory reports.
  long long band_voxels() const;

  /// Per-thread query object (it caches tree paths); cheap to create.
  class Sampler {
   public:
    explicit Sampler(const SurfaceField& field);
    ~Sampler();
    Sampler(Sampler&&) noexcept;
    SurfaceSample sample(const Vec3& point);
    /// sample(point), and in `run` how many of the points point + k·step,
    /// k = 0 … count − 1, are sure to give the same sample (at least 1):
    /// more than one only beyond the band, where the field is a tile of
    /// one value, and only for a step along +x.
    SurfaceSample sample_run(const Vec3& point, const Vec3& step, int count, int& run);
    /// For `point` in the band: how many of the points point + k·step,
    /// k = 0 … count − 1 (a step along +x), are sure to have samples affine
    /// in k, at least 1. More than one where their field cells all hold one
    /// triangle, both ends of the run project onto its face, on one side of
    /// the surface, and the uv comes from the mesh or a planar projection:
    /// then depth and uv at every point of the run, as sample() computes
    /// them, lie on the line between their values at the ends (up to
    /// rounding), so whatever is affine in them changes sign at most once.
    int affine_run(const Vec3& point, const Vec3& step, int count);

   private:
    /// The sample at `point`, whose nearest field cell is in the band and
    /// holds `cell` (its closest triangle and sign code).
    SurfaceSample sample_band(const Vec3& point, int cell);
    struct Impl;
    std::unique_ptr<Impl> impl_;
  };

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab

#pragma once
/// Goal and metric for caustic images (ImageObservation, 1 channel,
/// irradiance in units of the incident irradiance), and SSIM for reports
/// (RMSE: core/distance.h).

#include <array>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "caustics/caustic_tracer.h"
#include "geometry/mesh.h"
#include "reducer/height_surface.h"

namespace spec2fab {

/// Structural similarity (Wang et al. 2004) of two single-channel images of
/// the same size: 11 × 11 Gaussian window (σ = 1.5), K1 = 0.01, K2 = 0.03,
/// dynamic range L = the larger of the two images' peaks. 1 for identical images.
double image_ssim(std::span<const double> a, std::span<const double> b, int width, int height);

class Properties;

/// What the "caustics" simulator reads (its documented properties): the
/// tracer's setup, and where the slab sits in the subtree's coordinates.
struct CausticSlabConfig {
  CausticSetup setup;
  double thickness_mm = 10;  ///< highest the top may be (height search range)
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();  ///< the slab's bottom corner
  static CausticSlabConfig read(const Properties& properties);
};

/// Where the tracer's frame (footprint centred on the origin, bottom at
/// z = 0) sits in the subtree's coordinates when the slab's bottom corner is
/// at origin_mm: tracer point + offset = subtree point.
inline Eigen::Vector3d slab_offset(const CausticSetup& setup, const Eigen::Vector3d& origin_mm) {
  return origin_mm + Eigen::Vector3d(0.5 * setup.width_mm, 0.5 * setup.depth_mm, 0);
}

/// Calls visit(k, a, b) for every top vertex k of `tracer`'s grid, (a, b)
/// its position in the subtree's coordinates: where the slab's heights are
/// read, their derivatives taken and its mesh written.
template <class Visit>
void for_each_slab_vertex(const CausticTracer& tracer, const Eigen::Vector3d& origin_mm, Visit&& visit) {
  const CausticSetup& s = tracer.setup();
  const Eigen::Vector2d offset = slab_offset(s, origin_mm).head<2>();
  size_t k = 0;
  for (int j = 0; j < s.vertices_y; ++j)
    for (int i = 0; i < s.vertices_x; ++i, ++k) {
      const Eigen::Vector2d ab = tracer.vertex_xy(i, j) + offset;
      visit(k, ab.x(), ab.y());
    }
}

/// The closed slab a height surface (axis w) describes, meshed exactly as
/// the caustics simulator meshes it (setup's footprint and vertex grid), in
/// the subtree's coordinates: what print/surface.stl holds.
Mesh caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface, const Eigen::Vector3d& origin_mm);

/// A slab whose top is nx × ny planar facets over the setup's footprint
/// (tracer frame: centred on the origin, flat bottom at z = 0), closed by
/// vertical walls wherever neighbouring facets meet at different heights and
/// around the sides: the surface facet caustics print, traced exactly.
/// `corner_heights[i + nx·j]` are facet (i, j)'s heights (> 0) at its
/// corners (x0, y0), (x1, y0), (x1, y1), (x0, y1); facet (0, 0) has the
/// lowest x and y. Triangles face outwards; vertices are not shared.
Mesh faceted_slab_mesh(const CausticSetup& setup, int nx, int ny,
                       std::span<const std::array<double, 4>> corner_heights);

}  // namespace spec2fab

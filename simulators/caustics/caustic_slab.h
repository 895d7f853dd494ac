#pragma once
/// The caustics simulator's slab: what the "caustics" simulator reads (the
/// tracer's setup, where the slab sits in the subtree's coordinates), where
/// its top vertices lie, the heights' derivatives and least-squares fit to
/// a height surface's parameters, and the closed meshes of a smooth or a
/// faceted slab.

#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "caustics/caustic_tracer.h"
#include "core/limits.h"
#include "core/options.h"
#include "core/search_space.h"
#include "geometry/mesh.h"
#include "reducer/height_surface.h"

namespace spec2fab {

class Properties;

/// What the "caustics" simulator reads (its documented properties): the
/// tracer's setup, and where the slab sits in the subtree's coordinates.
struct CausticSlabConfig {
  CausticSetup setup;
  double thickness_mm = 10;  ///< highest the top may be (height search range)
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();  ///< the slab's bottom corner

  /// The properties as declared (core/options.h); read() turns them into the above.
  struct Options {
    std::array<double, 2> size_mm{50, 50};
    std::array<double, 3> origin_mm{0, 0, 0};
    double thickness_mm = 10;
    std::array<int, 2> vertices{121, 121};
    double refractive_index = 1.5;
    std::array<double, 3> light{0, 0, -1};
    std::array<double, 3> light_position_mm{kUnset, kUnset, kUnset};
    double distance_mm = 100;
    std::array<double, 2> receiver_mm{0, 0};  ///< 0: size_mm
    std::array<double, 2> receiver_centre_mm{0, 0};
    std::array<int, 2> image{240, 240};
    std::array<int, 2> rays{0, 0};  ///< 0: twice the image
    bool jitter = true, fresnel = false, image_from_behind = false, mirror = false;
    std::string aperture = "rectangle";
    std::string estimator = "rays";
    double seed = 1;

    template <class Declare, class Self>
    static void declare(Declare& d, Self& o) {
      d.number(o.size_mm, "size_mm", Range::above(0), "slab footprint (x, y); the subtree's (a, b) run from its corner");
      d.number(o.origin_mm, "origin_mm", Range::any(), "the subtree's coordinates (a, b, w) of the slab's bottom corner");
      d.number(o.thickness_mm, "thickness_mm", Range::closed(1e-3, 1e4), "highest the top may be (search range along w)");
      d.number(o.vertices, "vertices", Range::at_least(2), "top-surface mesh vertices (nx, ny), corners included");
      d.number(o.refractive_index, "refractive_index", Range::closed(1, 4), "of the slab's material");
      d.value(o.mirror, "mirror",
              "the slab's faces reflect (a print coated as a mirror): the receiver lies distance_mm above the slab's "
              "bottom, facing down; tilt `light` so that the beam misses it");
      d.number(o.light, "light", Range::any(), "direction (x, y, z) the light travels, z < 0");
      d.number(o.light_position_mm, "light_position_mm", Range::any(),
               "a point light instead, at (x, y) from the footprint's centre and z above the bottom, above the top; "
               "its intensity gives unit irradiance across the beam at distance z",
               Default{"none: collimated light along `light`"});
      d.number(o.distance_mm, "distance_mm", Range::closed(1e-3, 1e6),
               "receiver plane below the slab's bottom (a mirror's: above it)");
      d.number(o.receiver_mm, "receiver_mm", Range::above(0), "receiver extent (x, y) imaged", Default{"size_mm"});
      d.number(o.receiver_centre_mm, "receiver_centre_mm", Range::any(), "receiver centre below the slab's centre");
      d.number(o.image, "image", Range::at_least(1), "pixels (width, height); row 0 at +y");
      d.number(o.rays, "rays", Range::at_least(1), "stratified samples (nx, ny) over the footprint", Default{"2 × image"});
      d.value(o.jitter, "jitter", "jitter samples within their strata (hashed, deterministic)");
      d.value(o.fresnel, "fresnel", "weight transmissions by unpolarised Fresnel");
      d.value(o.image_from_behind, "image_from_behind",
              "the image as seen from the receiver's far side, looking back at the slab: columns run towards -x "
              "(a mirror's receiver, above, is seen from below unless this is set: columns towards -x)");
      d.choice(o.aperture, "aperture", {"rectangle", "disc"},
               "where light comes through: the whole footprint, or the disc (ellipse) inscribed in it");
      d.choice(o.estimator, "estimator", {"rays", "facets", "smooth"},
               "rays: stratified rays traced with Embree and splatted (walls, total internal reflection, an exit "
               "filter); facets: each flat top triangle's beam spread exactly over the area it lights (no noise); "
               "smooth: the caustic of the smooth surface through the vertices (vertex normals; no noise)");
      d.number(o.seed, "seed", Range::closed(0, 4294967295.0), "jitter pattern (an integer)");
    }
  };
  /// Reads the properties; every error names its key's JSON path.
  static CausticSlabConfig read(const Properties& properties, const Limits& limits);
  /// The same from options built in C++ (a translator's); a size past its
  /// resource limit is an InputError "key: problem", which the caller
  /// places (options_detail::fail_at_key).
  static CausticSlabConfig from(const Options& options, const Limits& limits);
};

/// Where the tracer's frame (footprint centred on the origin, bottom at
/// z = 0) sits in the subtree's coordinates when the slab's bottom corner is
/// at origin_mm: tracer point + offset = subtree point.
inline Eigen::Vector3d slab_offset(const CausticSetup& setup, const Eigen::Vector3d& origin_mm) {
  return origin_mm + Eigen::Vector3d(0.5 * setup.width_mm, 0.5 * setup.depth_mm, 0);
}

/// Calls visit(k, a, b) for every top vertex k of the setup's grid, (a, b)
/// its position in the subtree's coordinates: where the slab's heights are
/// read, their derivatives taken and its mesh written.
template <class Visit>
void for_each_slab_vertex(const CausticSetup& s, const Eigen::Vector3d& origin_mm, Visit&& visit) {
  const Eigen::Vector2d offset = slab_offset(s, origin_mm).head<2>();
  size_t k = 0;
  for (int j = 0; j < s.vertices_y; ++j)
    for (int i = 0; i < s.vertices_x; ++i, ++k) {
      const Eigen::Vector2d ab = slab_vertex_xy(s, i, j) + offset;
      visit(k, ab.x(), ab.y());
    }
}

/// ∂(top vertex height)/∂(free parameter), vertices × the search space's
/// entries, for a height surface (axis w) whose heights are linear in its
/// parameters (Plane, B-spline).
Eigen::SparseMatrix<double, Eigen::RowMajor> slab_height_jacobian(const CausticSetup& setup,
                                                                  const Eigen::Vector3d& origin_mm,
                                                                  const HeightSurface& surface,
                                                                  const SearchSpace& space);

/// The parameter values (the search space's order) whose surface passes
/// closest, in least squares, through the given top vertex heights (above
/// the slab's bottom), snapped to what each parameter admits; `clamped`
/// counts those that met a bound.
std::vector<double> fit_slab_surface(const CausticSetup& setup, const Eigen::Vector3d& origin_mm,
                                     const HeightSurface& surface, const SearchSpace& space,
                                     std::span<const double> heights_mm, int* clamped = nullptr);

/// The closed slab a height surface (axis w) describes, meshed exactly as
/// the caustics simulator meshes it (setup's footprint and vertex grid), in
/// the subtree's coordinates: what print/surface.stl holds.
Mesh caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface, const Eigen::Vector3d& origin_mm);

/// The same slab with its top meshed finer where the light spreads: each
/// cell of the setup's vertex grid is split into 2^L × 2^L quads, L from 0
/// to `max_level`, growing with how much wider the cell's light lands on the
/// receiver than the cell itself (the smooth surface's refraction at its
/// corners) over the pixel: a flat facet casts a sharp copy of itself, and
/// where the light spreads those copies leave a moiré unless they are small.
/// Neighbouring cells differ by at most one level, and a quad next to a
/// finer cell is fanned from its centre through the finer cell's vertices
/// on their shared edge, so that the top stays watertight (no vertex on
/// another triangle's edge). Walls and a fanned bottom close it as
/// caustic_slab_mesh does. `levels`, if given, gets each cell's level (row
/// by row from the lowest y).
Mesh adaptive_caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface,
                                const Eigen::Vector3d& origin_mm, int max_level, std::vector<int>* levels = nullptr);

/// What pixel_caustic_slab_mesh made, or why it could not.
struct PixelMeshReport {
  std::string why_not;         ///< empty when it made the mesh
  double worst_miss_px = 0;    ///< farthest a pulled-back corner's light lands from its pixel corner
  int corners_off = 0;         ///< corners whose light lands over 0.05 pixels off (where it folds over)
  int unlit_corners = 0;       ///< corners in a band along the image's edge that the lens's rim does not reach
  int refined_pixels = 0;      ///< pixels whose preimage was split (level > 0)
  int untangled_corners = 0;   ///< corner moves that made folded pixels' preimages convex
  int folded_facets = 0;       ///< top facets that would turn over still (then no mesh)
};

/// The slab with its top meshed on the receiver's pixel grid pulled back
/// to the lens: each corner of the image's pixels is moved to the point of
/// the top whose light the smooth surface sends to it (Levenberg–Marquardt
/// from its neighbour's, or from the top's points lighting the pixels
/// around it), so that each pixel's light comes from one quad of the file,
/// two flat facets split along the quad's shorter diagonal. A flat facet
/// casts a copy of itself; here the copy lands on its own pixel — inside
/// it where the light spreads (the quad is smaller than the pixel), over
/// its neighbours by a little where the light gathers once such quads are
/// split (up to 2^max_level times along x and along y apart, until a
/// quad's copy is at most `copy_pixels` pixels wide along each;
/// neighbours one level apart at most, fanned as adaptive_caustic_slab_mesh
/// fans them). So each pixel gets the light the smooth surface gives it, as
/// a halftone dot, with about two triangles a pixel where light spreads,
/// instead of the many facets a grid over the top needs to keep its
/// copies' gaps below a pixel. The receiver must be lit corner to corner by
/// the footprint (a rectangle aperture, the map keeping its orientation);
/// corners the lens's rim does not reach, in a band along the image's edge,
/// stay on the rim's side (slivers, dark as the smooth surface leaves them);
/// where the surface folds the light over, a corner may stay off its
/// pixel's corner (`report` counts them and gives the worst). Where a facet
/// would fold over after the folded pixels' corners were evened out, no
/// mesh is made and `report->why_not` says why.
std::optional<Mesh> pixel_caustic_slab_mesh(const CausticSetup& setup, const HeightSurface& surface,
                                            const Eigen::Vector3d& origin_mm, int max_level, double copy_pixels = 1,
                                            PixelMeshReport* report = nullptr);

/// Closes a slab whose top (already in `mesh`) has the given boundary
/// vertices, counter-clockwise seen from above: vertical walls from each
/// down to z = 0 and a bottom fanned from (0, 0, 0), the footprint's centre
/// in the tracer's frame.
void close_slab_below_rim(Mesh& mesh, const std::vector<int>& rim);

/// A slab whose top is nx × ny planar facets over the setup's footprint
/// (tracer frame: centred on the origin, flat bottom at z = 0), closed by
/// vertical walls wherever neighbouring facets meet at different heights and
/// around the sides: the surface facet caustics print, traced exactly.
/// `corner_heights[i + nx·j]` are facet (i, j)'s heights (> 0) at its
/// corners (x0, y0), (x1, y0), (x1, y1), (x0, y1); facet (0, 0) has the
/// lowest x and y. Triangles face outwards; vertices are not shared.
/// Where the two higher of four facets meeting at a corner are diagonal, the
/// higher of the other two is raised there to the lower of them, so that the
/// solid does not pinch to an edge four walls share (a 2-manifold file);
/// `pinches_filled` receives how many corners that raised. Facets meeting
/// at a corner within 0.02 µm take one height there first, so that no wall
/// is thinner than single precision tells apart.
Mesh faceted_slab_mesh(const CausticSetup& setup, int nx, int ny,
                       std::span<const std::array<double, 4>> corner_heights, int* pinches_filled = nullptr);

}  // namespace spec2fab

#pragma once
/// A slab top that casts a goal image, from optimal transport (Schwartzburg
/// et al. 2014): the uniform light through the aperture is transported to
/// the goal's irradiance (optimal_transport.h), each square of the top's
/// vertex grid is tilted by Snell's law so that its light heads for where
/// the transport sends it (through the top, the slab and the flat bottom;
/// for a mirror, by the law of reflection, straight up to the receiver),
/// and the tilts are integrated into heights by least squares. A point
/// light's rays are tilted from their own directions, but the transport
/// takes the light through the aperture as even: its falloff towards the
/// edges (cos³ of the angle off its axis) is left to the refinement.

#include <span>
#include <vector>

#include "caustics/caustic_tracer.h"
#include "caustics/optimal_transport.h"
#include "geometry/mesh.h"

namespace spec2fab {

struct TransportStart {
  std::vector<double> heights;  ///< the tracer's top vertices (CausticTracer::heights order), mm
  int sites = 0;                ///< goal pixels the light is transported to
  int newton_steps = 0;
  double worst_mass_error = 0;  ///< of the transport, over the mean mass
  double transport_seconds = 0, integration_seconds = 0;
  double relief_mm = 0;         ///< highest minus lowest vertex
  double largest_slope = 0;     ///< |∇h| of the steepest grid square
  double integration_rms_slope_error = 0;  ///< the tilts the heights could not follow (rms over squares)
};

/// Where the same transport sends the light of each square of an nx × ny
/// grid over the footprint (row by row from the lowest y, x fastest): its
/// mean and covariance on the receiver, in the tracer's frame (mm, the
/// footprint centred on the origin), each goal pixel's light spread evenly
/// over the pixel (its box variance added), and `mass` the square's share
/// of the aperture's area (in the footprint's half-size units: 4 in all
/// for the rectangle). For facets that each take a square's light
/// (facet_caustics "targets": "transport").
std::vector<TransportMoments> transport_square_targets(const CausticSetup& setup, std::span<const double> goal, int nx,
                                                       int ny);

/// The start for `setup` (its vertex grid, light, index, aperture, receiver)
/// and `goal` (the irradiance asked for, image_width × image_height, row 0
/// at +y; any scale), its heights averaging `mean_height_mm`. Throws
/// InputError for a goal with no light.
/// `keep`, if given, receives the transport (for transport_cells_slab_mesh).
TransportStart transport_start(const CausticSetup& setup, std::span<const double> goal, double mean_height_mm,
                               SemiDiscreteTransport* keep = nullptr);

/// What transport_cells_slab_mesh made.
struct TransportCellsMesh {
  Mesh mesh;                  ///< the closed slab, tracer frame (footprint centred on the origin, bottom z = 0)
  int cells = 0;              ///< transport cells meshed (a pixel each)
  size_t top_triangles = 0;
  int newton_steps = 0;
  double worst_mass_error = 0;
  double transport_seconds = 0, mesh_seconds = 0, integration_seconds = 0;
  double worst_facet_radius_px = 0;  ///< largest copy_radius of a top facet (receiver pixels)
  double rms_slope_error = 0;        ///< the facets' slopes against their aims (rms over the area, slivers left out)
  int open_edges = 0;                ///< top edges used once off the rim (0 for a watertight top)
  int pinched_cells = 0;             ///< cells whose boundary touched itself after short edges collapsed
  int collapsed_edges = 0;           ///< edges of the diagram collapsed to a point (short, or across a corner)
  double worst_area_error = 0;       ///< the worst cell's area off the transport's, over the mean, after the collapses
};

/// The slab whose top is the transport's own cells (Schwartzburg et al.
/// 2014's semi-discrete transport, meshed as it is instead of integrated
/// into a smooth surface): each pixel's power cell on the top becomes a
/// patch of flat facets, all aimed by Snell's law at the pixel's centre
/// (the heights integrated by least squares over the facets' edges, three
/// rounds for the slab's lateral shift), so that the pixel gets its cell's
/// light, which the transport made the goal's. A flat facet casts a copy of
/// itself centred where its centroid's light lands: cells are split
/// (a corner fan, else constrained Delaunay, with points inside on finer
/// lattices as needed, else rings about the centroid) until no facet
/// reaches further than `facet_radius_px` receiver pixels along x or y from
/// its centroid, so that at 1/2 each copy lands inside its pixel.
/// Edges under 0.02 pixel collapse, as do those under 0.8 pixel between
/// cells that meet across a corner of the pixel grid (the diagram's split
/// four-cell corners: hexagons become quadrilaterals, two facets instead of
/// four), each unless a cell it touches would be left with under three
/// corners, turn over or change its area by over 40 %; the corners then
/// move the least that gives every cell its area back (Gauss-Newton, three
/// rounds), so that each pixel still gets its light. Neighbouring cells
/// split their shared edge at the same points, so the top is watertight;
/// walls and a fanned bottom close the slab (tracer frame). A lens under collimated light
/// through its whole footprint only (InputError otherwise); `transport` is
/// transport_start's, to the image's pixels.
TransportCellsMesh transport_cells_slab_mesh(const CausticSetup& setup, const SemiDiscreteTransport& transport,
                                             double mean_height_mm, double facet_radius_px);
/// The same, solving the transport first (its time in transport_seconds).
TransportCellsMesh transport_cells_slab_mesh(const CausticSetup& setup, std::span<const double> goal,
                                             double mean_height_mm, double facet_radius_px);

}  // namespace spec2fab

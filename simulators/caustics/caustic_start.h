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
TransportStart transport_start(const CausticSetup& setup, std::span<const double> goal, double mean_height_mm);

}  // namespace spec2fab

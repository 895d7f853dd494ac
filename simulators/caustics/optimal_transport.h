#pragma once
/// Semi-discrete optimal transport for the quadratic cost: the uniform
/// density on a convex polygon is sent to point masses, each point taking
/// the source inside its Laguerre (power) cell. The cells' weights are found
/// by the damped Newton method of Kitagawa, Mérigot and Thibert (2019) on
/// the Kantorovich dual, the power diagrams computed as CGAL regular
/// triangulations and clipped to the polygon. What the caustic translators
/// start from (Schwartzburg et al. 2014 take the same route).

#include <span>
#include <vector>

#include <Eigen/Core>

namespace spec2fab {

struct SemiDiscreteTransport {
  /// Site i's weight ψ_i: its cell is {x : |x - y_i|² - ψ_i ≤ |x - y_j|² - ψ_j for all j}.
  std::vector<double> weights;
  /// Each site's cell inside the source polygon (counter-clockwise).
  std::vector<std::vector<Eigen::Vector2d>> cells;
  int newton_steps = 0;
  /// max_i |cell area_i - mass_i| over the mean mass, at the end.
  double worst_mass_error = 0;
};

/// Solves the transport from the uniform density on `source` (a convex
/// polygon, counter-clockwise) to `sites` carrying `masses` (> 0; scaled
/// to the polygon's area), until every cell's area is within `tolerance` of
/// the mean mass of its mass. Newton starts from weights whose cells are
/// the Voronoi cells of the sites shrunk into the source (none empty, as
/// the method needs), or, given `initial_weights` (a coarser solution
/// interpolated: transport_weights_guess), from those blended with the
/// former as little as leaves no cell empty (0, 1/4 or 1/2; else the
/// former alone). Throws InputError
/// when the sites or masses are unusable, std::runtime_error when Newton
/// stalls.
SemiDiscreteTransport solve_semi_discrete_transport(std::span<const Eigen::Vector2d> source,
                                                    std::span<const Eigen::Vector2d> sites,
                                                    std::span<const double> masses, double tolerance = 1e-3,
                                                    int max_steps = 60,
                                                    std::span<const double> initial_weights = {});

/// Weights for `sites` from a solution on `coarse_sites`, a coarse_nx ×
/// coarse_ny grid of sites (row by row from the lowest y): the weights
/// interpolated bilinearly (extrapolated linearly beyond the grid). Alone
/// they leave some cells empty along the source's edge (448 of 14,400 for
/// the 120 × 120 ring; interpolating the dual potential (|y|² − ψ)/2
/// instead left 427): solve_semi_discrete_transport blends them with its
/// safe start.
std::vector<double> transport_weights_guess(std::span<const Eigen::Vector2d> coarse_sites,
                                            std::span<const double> coarse_weights, int coarse_nx, int coarse_ny,
                                            std::span<const Eigen::Vector2d> sites);

/// The transport map averaged over each square of an nx × ny grid over
/// [lower, upper]: the mean of the sites that the square's points go to,
/// each weighted by the area of the square it sends there; NaN for a square
/// outside the source. Squares row by row from the lowest y, x fastest.
/// What one square of the source sends: the area it passes (`mass`), and
/// the mean and covariance (about the mean) of the sites it sends it to,
/// each site weighted by the area that goes there.
struct TransportMoments {
  double mass = 0;
  Eigen::Vector2d mean;
  Eigen::Matrix2d covariance;
};

/// The same per square as mean_transport_targets, with the spread: NaN mean
/// and covariance for a square outside the source.
std::vector<TransportMoments> transport_moments(const SemiDiscreteTransport& transport,
                                                std::span<const Eigen::Vector2d> sites, int nx, int ny,
                                                const Eigen::Vector2d& lower, const Eigen::Vector2d& upper);

std::vector<Eigen::Vector2d> mean_transport_targets(const SemiDiscreteTransport& transport,
                                                    std::span<const Eigen::Vector2d> sites, int nx, int ny,
                                                    const Eigen::Vector2d& lower, const Eigen::Vector2d& upper);

}  // namespace spec2fab

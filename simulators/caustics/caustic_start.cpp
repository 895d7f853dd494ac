#include "caustics/caustic_start.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <numbers>
#include <numeric>

#include <Eigen/SparseCore>

#include "caustics/optimal_transport.h"
#include "core/error.h"
#include "fem/cholmod_factor.h"

namespace spec2fab {
namespace {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The slope ∇h that sends light entering the top at (xy, h) to `target`
/// on the receiver: the direction in the slab that leaves the flat bottom
/// towards the target (its exit point found by fixed-point iteration), then
/// the normal that refracts the incident light into it (n ∝ l - η d).
constexpr double kTransportFloor = 0.02;  ///< least mass of a pixel, in units of the goal's mean

Vec2 slope_towards(const CausticSetup& s, const Vec2& xy, double h, const Vec2& target) {
  const Vec3 light = light_towards(s, Vec3(xy.x(), xy.y(), h));
  if (s.mirror) {
    // Reflected straight to the target above: the normal halves the turn (n ∝ d - l).
    const Vec3 out = Vec3(target.x() - xy.x(), target.y() - xy.y(), s.receiver_distance_mm - h).normalized();
    const Vec3 normal = out - light;
    return -normal.head<2>() / normal.z();
  }
  const double eta = s.refractive_index;
  Vec3 inside(0, 0, -1);
  for (int round = 0; round < 4; ++round) {
    const Vec2 exit = xy + h * inside.head<2>() / -inside.z();
    const Vec3 out = Vec3(target.x() - exit.x(), target.y() - exit.y(), -s.receiver_distance_mm).normalized();
    const Vec2 tangential = out.head<2>() / eta;
    inside = Vec3(tangential.x(), tangential.y(), -std::sqrt(std::max(0.0, 1 - tangential.squaredNorm())));
  }
  const Vec3 normal = light - eta * inside;  // points up for η > 1
  return -normal.head<2>() / normal.z();
}

/// Pixel centres of a width × height image in [-1, 1]² (row 0 at +y).
std::vector<Vec2> pixel_sites(int width, int height) {
  std::vector<Vec2> sites;
  sites.reserve(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) sites.emplace_back(2 * (col + 0.5) / width - 1, 1 - 2 * (row + 0.5) / height);
  return sites;
}

/// The transport to a width × height image's pixels (`sites` gets their
/// centres), started from the solution for the image halved — 2 × 2 blocks
/// summed — while both sides are even and at least 64: each level's Newton
/// then needs a few steps, where the full image from scratch needs tens.
SemiDiscreteTransport solve_multiscale(std::span<const Vec2> source, const std::vector<double>& masses, int width,
                                       int height, std::vector<Vec2>& sites) {
  sites = pixel_sites(width, height);
  std::vector<double> guess;
  if (width % 2 == 0 && height % 2 == 0 && width >= 64 && height >= 64) {
    const int w = width / 2, h = height / 2;
    std::vector<double> coarse(static_cast<size_t>(w) * static_cast<size_t>(h), 0.0);
    for (int row = 0; row < height; ++row)
      for (int col = 0; col < width; ++col)
        coarse[static_cast<size_t>(row / 2) * static_cast<size_t>(w) + static_cast<size_t>(col / 2)] +=
            masses[static_cast<size_t>(row) * static_cast<size_t>(width) + static_cast<size_t>(col)];
    std::vector<Vec2> coarse_sites;
    const SemiDiscreteTransport solved = solve_multiscale(source, coarse, w, h, coarse_sites);
    // transport_weights_guess wants rows from the lowest y: the image's rows run from +y.
    std::vector<Vec2> flipped_sites;
    std::vector<double> flipped_weights;
    for (int row = h - 1; row >= 0; --row)
      for (int col = 0; col < w; ++col) {
        flipped_sites.push_back(coarse_sites[static_cast<size_t>(row) * static_cast<size_t>(w) + static_cast<size_t>(col)]);
        flipped_weights.push_back(solved.weights[static_cast<size_t>(row) * static_cast<size_t>(w) + static_cast<size_t>(col)]);
      }
    guess = transport_weights_guess(flipped_sites, flipped_weights, w, h, sites);
  }
  return solve_semi_discrete_transport(source, sites, masses, 1e-2, 60, guess);
}

/// The aperture in the footprint's half-size units: [-1, 1]² or the unit disc.
std::vector<Vec2> aperture_outline(const CausticSetup& s) {
  std::vector<Vec2> source;
  if (s.disc_aperture) {
    constexpr int kSides = 256;
    for (int k = 0; k < kSides; ++k) {
      const double a = 2 * std::numbers::pi * k / kSides;
      source.emplace_back(std::cos(a), std::sin(a));
    }
  } else {
    source = {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)};
  }
  return source;
}

/// The goal's pixels as masses to transport to, on the receiver as it lies
/// (columns towards +x: an image whose columns run towards −x is mirrored
/// back first).
/// Every pixel gets at least a trace of light: where black regions get
/// none, the transport map jumps across them, which a smooth surface can
/// only follow with streaks of light through the black; the refinement then
/// darkens them again as far as the surface allows.
std::vector<double> transport_masses(const CausticSetup& s, std::span<const double> goal) {
  const int width = s.image_width;
  const double peak = *std::max_element(goal.begin(), goal.end());
  if (!(peak > 0) || !std::isfinite(peak)) throw InputError("caustics: the goal image has no light to transport");
  const double mean = std::accumulate(goal.begin(), goal.end(), 0.0) / static_cast<double>(goal.size());
  const double floor = kTransportFloor * mean;
  std::vector<double> masses(goal.size());
  for (size_t k = 0; k < goal.size(); ++k) {
    if (!std::isfinite(goal[k]) || goal[k] < 0) throw InputError("caustics: the goal image has a negative or undefined pixel");
    const size_t row = k / static_cast<size_t>(width), col = k % static_cast<size_t>(width);
    const size_t at = columns_towards_minus_x(s) ? row * static_cast<size_t>(width) + static_cast<size_t>(width) - 1 - col : k;
    masses[at] = std::max(goal[k], floor);
  }
  return masses;
}

/// The grid's vertices and squares, row by row.
struct HeightGrid {
  int nx, ny, squares_x, squares_y;
  double dx, dy;
  int vertex(int i, int j) const { return j * nx + i; }
  size_t square(int i, int j) const { return static_cast<size_t>(j) * static_cast<size_t>(squares_x) + static_cast<size_t>(i); }
};

/// The least squares for the heights: each square's two triangles (as the
/// tracer meshes it) should take its slope — x then y of triangle (i, j),
/// (i+1, j), (i+1, j+1), then of (i, j), (i+1, j+1), (i, j+1); squares the
/// aperture stops weakly (`weight`); h_0 = 0.
Eigen::SparseMatrix<double> slope_equations(const HeightGrid& g, const std::function<double(size_t)>& weight) {
  const Eigen::Index rows = 4 * static_cast<Eigen::Index>(g.squares_x) * g.squares_y;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(2 * static_cast<size_t>(rows) + 1);
  int row = 0;
  const auto difference = [&](int a, int b, double step, double w) {
    entries.emplace_back(row, b, w / step);
    entries.emplace_back(row++, a, -w / step);
  };
  for (int j = 0; j < g.squares_y; ++j)
    for (int i = 0; i < g.squares_x; ++i) {
      const double w = weight(g.square(i, j));
      difference(g.vertex(i, j), g.vertex(i + 1, j), g.dx, w);
      difference(g.vertex(i + 1, j), g.vertex(i + 1, j + 1), g.dy, w);
      difference(g.vertex(i, j + 1), g.vertex(i + 1, j + 1), g.dx, w);
      difference(g.vertex(i, j), g.vertex(i, j + 1), g.dy, w);
    }
  entries.emplace_back(row, 0, 1.0);  // h_0 = 0
  Eigen::SparseMatrix<double> a(rows + 1, static_cast<Eigen::Index>(g.nx) * g.ny);
  a.setFromTriplets(entries.begin(), entries.end());
  return a;
}

/// Heights whose squares send their light to `targets` (receiver half-size
/// units, one per square; NaN where the aperture stops it), about
/// `mean_height_mm`. The equations stay; their right-hand sides change with
/// the heights (the slab's lateral shift), three rounds. Sets the start's
/// heights and what they could not follow.
void integrate_heights(const CausticSetup& s, const HeightGrid& g, const std::vector<Vec2>& targets,
                       double mean_height_mm, TransportStart& start) {
  const auto weight = [&](size_t k) { return targets[k].allFinite() ? 1.0 : 1e-3; };
  const Eigen::SparseMatrix<double> a = slope_equations(g, weight);
  const Eigen::Index rows = a.rows() - 1;
  const Eigen::SparseMatrix<double> at = a.transpose();
  fem::CholmodFactor solver;  // supernodal: at 512 x 512 Eigen's simplicial LDLT took seconds
  if (!solver.analyze_and_factorize(at * a)) throw std::runtime_error("transport_start: the integration is singular");
  start.heights.assign(static_cast<size_t>(g.nx) * static_cast<size_t>(g.ny), mean_height_mm);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(rows + 1), h;
  const auto at_vertex = [&](int i, int j) { return start.heights[static_cast<size_t>(g.vertex(i, j))]; };
  for (int round = 0; round < 3; ++round) {
    for (int j = 0; j < g.squares_y; ++j)
      for (int i = 0; i < g.squares_x; ++i) {
        const size_t k = g.square(i, j);
        Vec2 slope = Vec2::Zero();
        if (targets[k].allFinite()) {
          const Vec2 centre(-0.5 * s.width_mm + (i + 0.5) * g.dx, -0.5 * s.depth_mm + (j + 0.5) * g.dy);
          const Vec2 target = s.receiver_centre_mm + Vec2(0.5 * s.receiver_width_mm * targets[k].x(),
                                                           0.5 * s.receiver_depth_mm * targets[k].y());
          const double here = 0.25 * (at_vertex(i, j) + at_vertex(i + 1, j) + at_vertex(i, j + 1) + at_vertex(i + 1, j + 1));
          slope = slope_towards(s, centre, here, target);
        }
        const double w = weight(k);
        const Eigen::Index row = 4 * static_cast<Eigen::Index>(k);
        rhs.segment<4>(row) << w * slope.x(), w * slope.y(), w * slope.x(), w * slope.y();
      }
    solver.solve(at * rhs, h);
    const Eigen::VectorXd shifted = h.array() + (mean_height_mm - h.mean());
    std::copy(shifted.begin(), shifted.end(), start.heights.begin());
  }
  // What the heights could not follow, over the slope equations (not the pin).
  start.integration_rms_slope_error = std::sqrt((a * h - rhs).head(rows).squaredNorm() / static_cast<double>(rows));
}

/// |∇h| of the steepest grid square.
double largest_slope(const HeightGrid& g, const std::vector<double>& heights) {
  double largest = 0;
  for (int j = 0; j < g.squares_y; ++j)
    for (int i = 0; i < g.squares_x; ++i) {
      const auto h = [&](int a, int b) { return heights[static_cast<size_t>(g.vertex(a, b))]; };
      const Vec2 slope(0.5 * (h(i + 1, j) - h(i, j) + h(i + 1, j + 1) - h(i, j + 1)) / g.dx,
                       0.5 * (h(i, j + 1) - h(i, j) + h(i + 1, j + 1) - h(i + 1, j)) / g.dy);
      largest = std::max(largest, slope.norm());
    }
  return largest;
}

}  // namespace

std::vector<TransportMoments> transport_square_targets(const CausticSetup& s, std::span<const double> goal, int nx,
                                                       int ny) {
  if (goal.size() != static_cast<size_t>(s.image_width) * static_cast<size_t>(s.image_height))
    throw std::invalid_argument("transport_square_targets: the goal has the wrong size");
  std::vector<Vec2> sites;
  const SemiDiscreteTransport transport =
      solve_multiscale(aperture_outline(s), transport_masses(s, goal), s.image_width, s.image_height, sites);
  std::vector<TransportMoments> squares = transport_moments(transport, sites, nx, ny, Vec2(-1, -1), Vec2(1, 1));
  // Half-size units to the receiver's millimetres, and each pixel's own box.
  const Eigen::Matrix2d scale = Vec2(0.5 * s.receiver_width_mm, 0.5 * s.receiver_depth_mm).asDiagonal();
  const Eigen::Matrix2d pixel =
      Vec2(std::pow(s.receiver_width_mm / s.image_width, 2) / 12, std::pow(s.receiver_depth_mm / s.image_height, 2) / 12)
          .asDiagonal();
  for (TransportMoments& m : squares) {
    m.mean = s.receiver_centre_mm + scale * m.mean;
    m.covariance = scale * m.covariance * scale + pixel;
  }
  return squares;
}

TransportStart transport_start(const CausticSetup& s, std::span<const double> goal, double mean_height_mm) {
  const int width = s.image_width, height = s.image_height;
  if (goal.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
    throw std::invalid_argument("transport_start: the goal has the wrong size");
  TransportStart start;
  const auto began = Clock::now();
  // The transport in the footprint's and the receiver's half-size units:
  // the aperture to the goal's lit pixels.
  const std::vector<Vec2> source = aperture_outline(s);
  const std::vector<double> masses = transport_masses(s, goal);
  std::vector<Vec2> sites;
  const SemiDiscreteTransport transport = solve_multiscale(source, masses, width, height, sites);
  start.sites = static_cast<int>(sites.size());
  start.newton_steps = transport.newton_steps;
  start.worst_mass_error = transport.worst_mass_error;
  const int nx = s.vertices_x, ny = s.vertices_y;
  const HeightGrid grid{nx, ny, nx - 1, ny - 1, s.width_mm / (nx - 1), s.depth_mm / (ny - 1)};
  const std::vector<Vec2> targets =
      mean_transport_targets(transport, sites, grid.squares_x, grid.squares_y, Vec2(-1, -1), Vec2(1, 1));
  start.transport_seconds = seconds_since(began);

  const auto integrated = Clock::now();
  integrate_heights(s, grid, targets, mean_height_mm, start);
  start.integration_seconds = seconds_since(integrated);
  const auto [low, high] = std::minmax_element(start.heights.begin(), start.heights.end());
  start.relief_mm = *high - *low;
  start.largest_slope = largest_slope(grid, start.heights);
  return start;
}

}  // namespace spec2fab

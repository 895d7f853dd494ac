// Semi-discrete optimal transport against what is known without a solver —
// equal masses on a grid over the square take exactly the grid's squares;
// masses varying along x only are served by the monotone rearrangement
// T(x) = F_target⁻¹(F_source(x)); every cell's area is its mass — and the
// caustic start built on it: the smooth estimator's image of the start
// resembles the goal far better than a flat slab's.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numeric>
#include <vector>

#include "caustics/caustic_parts.h"
#include "caustics/caustic_start.h"
#include "caustics/caustic_tracer.h"
#include "caustics/optimal_transport.h"
#include "core/distance.h"
#include "core/error.h"

namespace spec2fab {
namespace {

using Vec2 = Eigen::Vector2d;

const std::vector<Vec2> kSquare = {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)};

double area(const std::vector<Vec2>& p) {
  double twice = 0;
  for (size_t k = 0; k < p.size(); ++k) twice += p[k].x() * p[(k + 1) % p.size()].y() - p[k].y() * p[(k + 1) % p.size()].x();
  return 0.5 * twice;
}

std::vector<Vec2> grid_sites(int n) {
  std::vector<Vec2> sites;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) sites.emplace_back(2 * (i + 0.5) / n - 1, 2 * (j + 0.5) / n - 1);
  return sites;
}

TEST(OptimalTransport, EqualMassesOnAGridTakeTheGridsSquares) {
  const int n = 16;
  const std::vector<Vec2> sites = grid_sites(n);
  const std::vector<double> masses(sites.size(), 1.0);
  const SemiDiscreteTransport t = solve_semi_discrete_transport(kSquare, sites, masses, 1e-9);
  for (size_t i = 0; i < sites.size(); ++i) {
    EXPECT_NEAR(area(t.cells[i]), 4.0 / (n * n), 1e-9);
    // Each cell is the site's own square: its centroid is the site.
    const std::vector<Vec2>& p = t.cells[i];
    Vec2 centroid = Vec2::Zero();
    for (size_t k = 0; k < p.size(); ++k) {
      const Vec2& a = p[k];
      const Vec2& b = p[(k + 1) % p.size()];
      centroid += (a + b) * (a.x() * b.y() - a.y() * b.x());
    }
    centroid /= 6 * area(p);
    EXPECT_LT((centroid - sites[i]).norm(), 1e-9);
  }
}

TEST(OptimalTransport, MassesAlongXGetTheMonotoneRearrangement) {
  // Target density ∝ 1 + 0.8 x on [-1, 1] (along x; uniform along y):
  // F(t) = (t + 1 + 0.4 (t² - 1)) / 2, and the source's F is (x + 1) / 2.
  const int n = 24;
  const std::vector<Vec2> sites = grid_sites(n);
  std::vector<double> masses;
  for (const Vec2& y : sites) masses.push_back(1 + 0.8 * y.x());
  const SemiDiscreteTransport t = solve_semi_discrete_transport(kSquare, sites, masses, 1e-8);
  EXPECT_LE(t.worst_mass_error, 1e-8);
  double total = std::accumulate(masses.begin(), masses.end(), 0.0);
  for (size_t i = 0; i < sites.size(); ++i) EXPECT_NEAR(area(t.cells[i]), 4 * masses[i] / total, 1e-8);
  // Squares of a coarse grid: their mean target's x against the exact map
  // averaged over the square (the map is exact between the sites' columns,
  // a step function at the sites: compare to a site's spacing).
  const int m = 8;
  const std::vector<Vec2> targets = mean_transport_targets(t, sites, m, m, Vec2(-1, -1), Vec2(1, 1));
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      double exact = 0;
      const int samples = 200;
      for (int k = 0; k < samples; ++k) {
        const double x = -1 + 2.0 * (i + (k + 0.5) / samples) / m;
        // Solve (t + 1 + 0.4 (t² - 1)) / 2 = (x + 1) / 2 for t in [-1, 1].
        const double c = -(x + 1) - 0.4 + 1;  // 0.4 t² + t + c = 0
        exact += (-1 + std::sqrt(1 - 4 * 0.4 * c)) / (2 * 0.4);
      }
      exact /= samples;
      const Vec2& mean = targets[static_cast<size_t>(j * m + i)];
      EXPECT_NEAR(mean.x(), exact, 0.5 * 2.0 / n) << i << ", " << j;
      EXPECT_NEAR(mean.y(), -1 + 2.0 * (j + 0.5) / m, 1e-6) << i << ", " << j;
    }
}

TEST(OptimalTransport, DiscSourceFeedsASquareOfSites) {
  std::vector<Vec2> disc;
  for (int k = 0; k < 128; ++k) disc.emplace_back(std::cos(2 * M_PI * k / 128), std::sin(2 * M_PI * k / 128));
  const std::vector<Vec2> sites = grid_sites(12);
  std::vector<double> masses;
  for (const Vec2& y : sites) masses.push_back(std::exp(-y.squaredNorm()));
  const SemiDiscreteTransport t = solve_semi_discrete_transport(disc, sites, masses, 1e-6);
  const double total = std::accumulate(masses.begin(), masses.end(), 0.0);
  for (size_t i = 0; i < sites.size(); ++i) EXPECT_NEAR(area(t.cells[i]), area(disc) * masses[i] / total, 1e-6 * area(disc) / 144);
}

TEST(OptimalTransport, RefusesUnusableMasses) {
  const std::vector<Vec2> sites = grid_sites(2);
  EXPECT_THROW(solve_semi_discrete_transport(kSquare, sites, std::vector<double>{1, 0, 1, 1}), InputError);
  EXPECT_THROW(solve_semi_discrete_transport(kSquare, sites, std::vector<double>{1, 1}), InputError);
}

// What each square of the footprint sends (facet_caustics "targets":
// "transport"): for a goal of density ∝ 1 + 0.8 u across and even along y,
// the monotone map's mean and its local stretch. A square of side s sends
// its light spread as s/√12 times the map's derivative across (1/(1 + 0.8
// t) in the receiver's half-size units, the pixels' boxes included) and
// s/√12 along y, where the map is the identity; in millimetres.
TEST(CausticStart, SquareTargetsAreTheTransportsMeanAndLocalStretch) {
  CausticSetup s;
  s.width_mm = s.depth_mm = 20;
  s.receiver_width_mm = s.receiver_depth_mm = 20;
  s.receiver_centre_mm = Vec2(3, -1);
  s.image_width = s.image_height = 48;
  std::vector<double> goal;
  for (int row = 0; row < 48; ++row)
    for (int col = 0; col < 48; ++col) goal.push_back(1 + 0.8 * (2 * (col + 0.5) / 48 - 1));
  const int m = 8;
  const std::vector<TransportMoments> squares = transport_square_targets(s, goal, m, m);
  ASSERT_EQ(squares.size(), 64u);
  const double side = 20.0 / m;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      SCOPED_TRACE(testing::Message() << i << ", " << j);
      const TransportMoments& q = squares[static_cast<size_t>(j * m + i)];
      // The map across at the square's centre x: (t + 1 + 0.4 (t² − 1)) = (x + 1), half-size units.
      const double x = -1 + 2.0 * (i + 0.5) / m, c = -(x + 1) - 0.4 + 1;
      const double t = (-1 + std::sqrt(1 - 4 * 0.4 * c)) / (2 * 0.4), stretch = 1 / (1 + 0.8 * t);
      EXPECT_NEAR(q.mean.x(), 3 + 10 * t, 0.3);
      EXPECT_NEAR(q.mean.y(), -1 - 10 + (j + 0.5) * side, 0.05);
      EXPECT_NEAR(std::sqrt(q.covariance(1, 1)), side / std::sqrt(12.0), 0.02 * side / std::sqrt(12.0));
      EXPECT_NEAR(std::sqrt(q.covariance(0, 0)), stretch * side / std::sqrt(12.0), 0.1 * stretch * side / std::sqrt(12.0));
      EXPECT_LT(std::abs(q.covariance(0, 1)), 0.05 * q.covariance(1, 1));
      EXPECT_NEAR(q.mass, 4.0 / 64, 1e-9);
    }
}

TEST(CausticStart, TransportStartCastsTheGoal) {
  // A ring and a dot on 120 × 120 pixels, 60 mm slab, receiver 200 mm
  // below: the smooth estimator's image of the start against the goal.
  CausticSetup s;
  s.width_mm = s.depth_mm = 60;
  s.vertices_x = s.vertices_y = 241;
  s.receiver_distance_mm = 200;
  s.receiver_width_mm = s.receiver_depth_mm = 60;
  s.image_width = s.image_height = 120;
  s.estimator = CausticSetup::Estimator::smooth;
  std::vector<double> goal(120 * 120);
  for (int row = 0; row < 120; ++row)
    for (int col = 0; col < 120; ++col) {
      const double x = (col + 0.5) / 2 - 30, y = 30 - (row + 0.5) / 2;
      const double r = std::hypot(x, y);
      goal[static_cast<size_t>(row * 120 + col)] = 0.05 + std::exp(-std::pow((r - 18) / 2.5, 2)) + std::exp(-std::pow(r / 3, 2));
    }
  const double mean = std::accumulate(goal.begin(), goal.end(), 0.0) / static_cast<double>(goal.size());
  for (double& g : goal) g /= mean;  // the slab's light, all on the receiver
  const auto began = std::chrono::steady_clock::now();
  const TransportStart start = transport_start(s, goal, 5.0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  CausticTracer tracer(s);
  std::vector<double> image(goal.size()), flat(goal.size());
  tracer.render(flat);
  tracer.set_heights(start.heights);
  tracer.render(image);
  const double ssim = image_ssim(image, goal, 120, 120), flat_ssim = image_ssim(flat, goal, 120, 120);
  const double error = rms_difference(image, goal) / std::sqrt(std::inner_product(goal.begin(), goal.end(), goal.begin(), 0.0) / static_cast<double>(goal.size()));
  RecordProperty("ssim", std::to_string(ssim));
  std::printf("transport start: %d sites, %d Newton steps, %.2f s; SSIM %.3f (flat %.3f), relative RMSE %.3f, relief %.2f mm, slope %.3f\n",
              start.sites, start.newton_steps, seconds, ssim, flat_ssim, error, start.relief_mm, start.largest_slope);
  EXPECT_GT(ssim, 0.8);
  EXPECT_LT(error, 0.2);
  EXPECT_GT(start.relief_mm, 0.1);
}

// A goal seen from behind the receiver is the mirror image of the goal on
// the receiver as it lies: the start for it is the start for the mirrored
// goal, surface for surface (a lopsided goal, so that mirroring matters).
TEST(CausticStart, GoalSeenFromBehindStartsAsItsMirrorImage) {
  CausticSetup s;
  s.width_mm = s.depth_mm = 30;
  s.vertices_x = s.vertices_y = 41;
  s.receiver_distance_mm = 100;
  s.receiver_width_mm = s.receiver_depth_mm = 30;
  s.image_width = 24;
  s.image_height = 20;
  std::vector<double> goal(24 * 20), mirrored(goal.size());
  for (int row = 0; row < 20; ++row)
    for (int col = 0; col < 24; ++col)
      goal[static_cast<size_t>(row * 24 + col)] = 0.2 + std::exp(-std::pow((col - 6.0) / 3, 2) - std::pow((row - 12.0) / 4, 2));
  for (int row = 0; row < 20; ++row)
    for (int col = 0; col < 24; ++col)
      mirrored[static_cast<size_t>(row * 24 + col)] = goal[static_cast<size_t>(row * 24 + 23 - col)];
  CausticSetup behind = s;
  behind.image_from_behind = true;
  const TransportStart from_behind = transport_start(behind, goal, 5.0), as_lying = transport_start(s, mirrored, 5.0);
  EXPECT_EQ(from_behind.heights, as_lying.heights);
  EXPECT_NE(as_lying.heights, transport_start(s, goal, 5.0).heights);
}

}  // namespace
}  // namespace spec2fab

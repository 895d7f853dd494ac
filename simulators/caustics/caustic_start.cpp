#include "caustics/caustic_start.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <Eigen/SparseCore>
#include <fmt/format.h>

#include "caustics/caustic_slab.h"
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

TransportStart transport_start(const CausticSetup& s, std::span<const double> goal, double mean_height_mm,
                               SemiDiscreteTransport* keep) {
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
  SemiDiscreteTransport transport = solve_multiscale(source, masses, width, height, sites);
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
  if (keep) *keep = std::move(transport);
  return start;
}

namespace {

/// Cell corners merged by position: two cells compute a shared corner of
/// the power diagram apart (each clips its own polygon), so corners within
/// `quantum` of one another become one vertex, and edges shorter than that
/// vanish.
class CornerWelder {
 public:
  explicit CornerWelder(double quantum) : quantum_(quantum) {}
  int operator()(const Vec2& p, std::vector<Vec2>& points) {
    const long long ix = std::llround(p.x() / quantum_), iy = std::llround(p.y() / quantum_);
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy) {
        const auto [begin, end] = buckets_.equal_range(key(ix + dx, iy + dy));
        for (auto at = begin; at != end; ++at) {
          Vec2& kept = points[static_cast<size_t>(at->second)];
          if ((kept - p).norm() > quantum_) continue;
          // The footprint's rim stays where it is: a corner on it wins.
          if (rim_rank(p) > rim_rank(kept)) kept = p;
          return at->second;
        }
      }
    const int id = static_cast<int>(points.size());
    points.push_back(p);
    buckets_.emplace(key(ix, iy), id);
    return id;
  }

 private:
  static long long key(long long ix, long long iy) { return ix * 4'000'000'007LL + iy; }
  /// 2 on a corner of the footprint [-1, 1]², 1 on an edge, 0 inside.
  static int rim_rank(const Vec2& p) { return (std::abs(p.x()) == 1.0) + (std::abs(p.y()) == 1.0); }
  double quantum_;
  std::unordered_multimap<long long, int> buckets_;
};

/// How far a flat facet's copy reaches along x or y from where its centroid's
/// light lands (corners in receiver pixels): aimed at its pixel's centre,
/// the copy stays in the pixel at 1/2. (Aiming each facet's box centre
/// instead, and bounding the box, was tried: more facets for the same
/// image, benchmarks/RESULTS.md.)
/// Edge (a, b) as one integer; (min, max) for an edge either way round.
long long edge_key(int a, int b) { return static_cast<long long>(a) * 0x100000000LL + b; }
long long undirected_edge_key(int a, int b) { return edge_key(std::min(a, b), std::max(a, b)); }

double copy_radius(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Vec2 centroid = (a + b + c) / 3;
  return std::max({(a - centroid).cwiseAbs().maxCoeff(), (b - centroid).cwiseAbs().maxCoeff(),
                   (c - centroid).cwiseAbs().maxCoeff()});
}

/// The area inside a loop of points (counter-clockwise: positive), each
/// scaled by `scale` first.
double loop_area(const std::vector<int>& loop, const std::vector<Vec2>& points, const Vec2& scale) {
  double twice = 0;
  for (size_t k = 0; k < loop.size(); ++k) {
    const Vec2 p = points[static_cast<size_t>(loop[k])].cwiseProduct(scale);
    const Vec2 q = points[static_cast<size_t>(loop[(k + 1) % loop.size()])].cwiseProduct(scale);
    twice += p.x() * q.y() - p.y() * q.x();
  }
  return 0.5 * twice;
}

/// Moves the cells' corners (the least move, Gauss-Newton) until each
/// cell's area is `area_px` again (pixels², `to_px` scaling the points
/// there): what collapsing edges took from one cell and gave its
/// neighbour. Corners of the footprint stay; corners on its sides slide
/// along them. Three rounds (each takes the error down about tenfold or
/// more); returns the largest error left, over the mean area.
double restore_cell_areas(const std::vector<std::vector<int>>& loops, const std::vector<double>& area_px,
                          std::vector<Vec2>& points, const Vec2& to_px) {
  // Each corner's free coordinates as unknowns (2 inside, 1 on a side, 0 at a corner of the footprint).
  std::vector<std::array<int, 2>> unknown(points.size(), {-1, -1});
  int count = 0;
  for (const std::vector<int>& loop : loops)
    for (int v : loop) {
      std::array<int, 2>& u = unknown[static_cast<size_t>(v)];
      if (u[0] != -1 || u[1] != -1) continue;
      const Vec2& p = points[static_cast<size_t>(v)];
      u = {-2, -2};  // seen, fixed
      if (std::abs(p.x()) != 1.0) u[0] = count++;
      if (std::abs(p.y()) != 1.0) u[1] = count++;
    }
  double mean = 0;
  int cells = 0;
  for (size_t i = 0; i < loops.size(); ++i)
    if (!loops[i].empty()) mean += area_px[i], ++cells;
  mean /= std::max(cells, 1);
  const auto worst = [&]() {
    double w = 0;
    for (size_t i = 0; i < loops.size(); ++i)
      if (!loops[i].empty()) w = std::max(w, std::abs(loop_area(loops[i], points, to_px) - area_px[i]));
    return w / mean;
  };
  if (count == 0) return worst();
  const Vec2 from_px = to_px.cwiseInverse();
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd residual(cells);  // a row per cell with corners
  for (int round = 0; round < 3; ++round) {
    entries.clear();
    int row = 0;
    for (size_t i = 0; i < loops.size(); ++i) {
      const std::vector<int>& loop = loops[i];
      if (loop.empty()) continue;
      const size_t n = loop.size();
      double twice = 0;
      for (size_t k = 0; k < n; ++k) {
        const Vec2 prev = points[static_cast<size_t>(loop[(k + n - 1) % n])].cwiseProduct(to_px);
        const Vec2 here = points[static_cast<size_t>(loop[k])].cwiseProduct(to_px);
        const Vec2 next = points[static_cast<size_t>(loop[(k + 1) % n])].cwiseProduct(to_px);
        twice += here.x() * next.y() - here.y() * next.x();
        // ∂A/∂x = (y_next - y_prev)/2, ∂A/∂y = (x_prev - x_next)/2.
        const std::array<int, 2>& u = unknown[static_cast<size_t>(loop[k])];
        if (u[0] >= 0) entries.emplace_back(row, u[0], 0.5 * (next.y() - prev.y()));
        if (u[1] >= 0) entries.emplace_back(row, u[1], 0.5 * (prev.x() - next.x()));
      }
      residual[row++] = 0.5 * twice - area_px[i];
    }
    Eigen::SparseMatrix<double> jacobian(row, count);
    jacobian.setFromTriplets(entries.begin(), entries.end());
    // The least move that takes the areas' error away: J^T (J J^T)^-1 r.
    Eigen::SparseMatrix<double> normal = jacobian * jacobian.transpose();
    // A whisper on the diagonal: a cell with no free corner would make it singular.
    Eigen::SparseMatrix<double> whisper(normal.rows(), normal.cols());
    whisper.setIdentity();
    normal += (1e-9 * normal.diagonal().sum() / static_cast<double>(normal.rows())) * whisper;
    fem::CholmodFactor solver;
    if (!solver.analyze_and_factorize(normal)) break;
    Eigen::VectorXd multipliers;
    solver.solve(residual, multipliers);
    const Eigen::VectorXd move = jacobian.transpose() * multipliers;
    for (size_t v = 0; v < points.size(); ++v) {
      const std::array<int, 2>& u = unknown[v];
      if (u[0] >= 0) points[v].x() -= move[u[0]] * from_px.x();
      if (u[1] >= 0) points[v].y() -= move[u[1]] * from_px.y();
    }
  }
  return worst();
}

/// Triangulates the convex polygon `ring` (vertex ids into `points`, counter-
/// clockwise) by constrained Delaunay, first alone, then with points inside
/// on square lattices of the given spacings (receiver pixels; `px` maps a
/// point there, `from_px` scales one back), until every facet's copy_radius is at most `radius`; the
/// lattice points are appended to `points`. False (nothing appended) when
/// no spacing does.
template <class ToPx, class Emit>
bool delaunay_cell(const std::vector<int>& ring, const std::vector<double>& spacings, double radius,
                   std::vector<Vec2>& points, const ToPx& px, const Vec2& from_px, const Emit& emit) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel>;
  using FaceBase = CGAL::Constrained_triangulation_face_base_2<Kernel>;
  using Cdt = CGAL::Constrained_Delaunay_triangulation_2<
      Kernel, CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>, CGAL::Exact_predicates_tag>;
  const size_t n = ring.size();
  std::vector<Vec2> corner(n);
  Vec2 low = Vec2::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (size_t k = 0; k < n; ++k) {
    corner[k] = px(points[static_cast<size_t>(ring[k])]);
    low = low.cwiseMin(corner[k]);
    high = high.cwiseMax(corner[k]);
  }
  // Signed distance inside each edge (the ring is counter-clockwise).
  const auto inside_by = [&](const Vec2& p) {
    double least = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < n; ++k) {
      const Vec2 e = corner[(k + 1) % n] - corner[k];
      const double length = e.norm();
      if (!(length > 0)) continue;
      least = std::min(least, (e.x() * (p - corner[k]).y() - e.y() * (p - corner[k]).x()) / length);
    }
    return least;
  };
  std::vector<Eigen::Vector3i> facets;
  for (double spacing : spacings) {
    std::vector<Vec2> inner;
    if (spacing < 1e8) {
      const Vec2 centre = 0.5 * (low + high);
      const int half_x = static_cast<int>(std::ceil(0.5 * (high.x() - low.x()) / spacing)) + 1;
      const int half_y = static_cast<int>(std::ceil(0.5 * (high.y() - low.y()) / spacing)) + 1;
      for (int j = -half_y; j <= half_y; ++j)
        for (int i = -half_x; i <= half_x; ++i) {
          const Vec2 p = centre + spacing * Vec2(i + 0.5 * (j & 1), j);
          if (inside_by(p) >= 0.4 * spacing) inner.push_back(p);
        }
    }
    Cdt cdt;
    std::vector<Cdt::Vertex_handle> handles(n);
    for (size_t k = 0; k < n; ++k) {
      handles[k] = cdt.insert(Cdt::Point(corner[k].x(), corner[k].y()));
      handles[k]->info() = ring[k];
    }
    for (size_t k = 0; k < n; ++k) cdt.insert_constraint(handles[k], handles[(k + 1) % n]);
    for (size_t m = 0; m < inner.size(); ++m) cdt.insert(Cdt::Point(inner[m].x(), inner[m].y()))->info() = -1 - static_cast<int>(m);
    if (cdt.number_of_vertices() != n + inner.size()) continue;  // a point fell on another
    // Faces outside the boundary (between it and the hull, where rounding
    // bent it inwards) are those reached from the infinite face without
    // crossing a constrained edge.
    std::unordered_map<Cdt::Face_handle, bool> outside;
    std::vector<Cdt::Face_handle> stack{cdt.infinite_face()};
    outside[cdt.infinite_face()] = true;
    while (!stack.empty()) {
      const Cdt::Face_handle f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const Cdt::Face_handle g = f->neighbor(k);
        if (f->is_constrained(k) || outside.contains(g)) continue;
        outside[g] = true;
        stack.push_back(g);
      }
    }
    facets.clear();
    bool small = true;
    for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end() && small; ++f) {
      if (outside.contains(f)) continue;
      Vec2 v[3];
      int id[3];
      for (int k = 0; k < 3; ++k) {
        v[k] = Vec2(f->vertex(k)->point().x(), f->vertex(k)->point().y());
        id[k] = f->vertex(k)->info();
      }
      small = copy_radius(v[0], v[1], v[2]) <= radius;
      facets.emplace_back(id[0], id[1], id[2]);
    }
    if (!small) continue;
    const int first = static_cast<int>(points.size());
    for (const Vec2& p : inner) points.push_back(p.cwiseProduct(from_px));
    for (Eigen::Vector3i& f : facets) {
      for (int k = 0; k < 3; ++k)
        if (f[k] < 0) f[k] = first + (-1 - f[k]);
    }
    emit(facets);
    return true;
  }
  return false;
}

}  // namespace

TransportCellsMesh transport_cells_slab_mesh(const CausticSetup& s, std::span<const double> goal,
                                             double mean_height_mm, double facet_radius_px) {
  const int width = s.image_width, height = s.image_height;
  if (goal.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
    throw std::invalid_argument("transport_cells_slab_mesh: the goal has the wrong size");
  const auto began = Clock::now();
  std::vector<Vec2> sites;
  const SemiDiscreteTransport transport =
      solve_multiscale(aperture_outline(s), transport_masses(s, goal), width, height, sites);
  const double seconds = seconds_since(began);
  TransportCellsMesh made = transport_cells_slab_mesh(s, transport, mean_height_mm, facet_radius_px);
  made.transport_seconds = seconds;
  return made;
}

TransportCellsMesh transport_cells_slab_mesh(const CausticSetup& s, const SemiDiscreteTransport& transport,
                                             double mean_height_mm, double facet_radius_px) {
  const int width = s.image_width, height = s.image_height;
  if (transport.cells.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
    throw std::invalid_argument("transport_cells_slab_mesh: the transport is not to the image's pixels");
  if (s.disc_aperture || s.mirror || s.point_light)
    throw InputError("print_mesh \"cells\": a lens under collimated light through its whole footprint only "
                     "(no disc aperture, mirror or point light)");
  TransportCellsMesh made;
  made.newton_steps = transport.newton_steps;
  made.worst_mass_error = transport.worst_mass_error;
  const std::vector<Vec2> sites = pixel_sites(width, height);
  auto began = Clock::now();
  // Half-size units (the transport's) to receiver pixels, along x and y.
  const Vec2 to_px(0.5 * s.width_mm * width / s.receiver_width_mm, 0.5 * s.depth_mm * height / s.receiver_depth_mm);
  const auto px = [&](const Vec2& u) -> Vec2 { return u.cwiseProduct(to_px); };
  const Vec2 from_px = to_px.cwiseInverse();
  constexpr double weld_px = 1e-6;
  std::vector<Vec2> points;  // half-size units
  CornerWelder weld(weld_px * 2.0 / std::max(width, height));
  std::vector<std::vector<int>> loops(transport.cells.size());
  for (size_t i = 0; i < transport.cells.size(); ++i) {
    std::vector<int>& loop = loops[i];
    for (const Vec2& p : transport.cells[i]) {
      const int v = weld(p, points);
      if (loop.empty() || loop.back() != v) loop.push_back(v);
    }
    while (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();
    if (loop.size() < 3) loop.clear();
  }
  // Each cell's area as the transport made it (its pixel's light), in pixels².
  std::vector<double> light_px(loops.size(), 0.0);
  for (size_t i = 0; i < loops.size(); ++i) light_px[i] = loop_area(loops[i], points, to_px);
  // Edges collapse to a point, shortest first, in every cell that has them
  // (a vertex's id replaced by the other's, both moved to their midpoint),
  // so that no facet is spent on them: those under `collapse_px`, and those
  // under `corner_px` that part two pixels' cells meeting at a corner of
  // the pixel grid (not side by side). The diagram of a near-square grid of
  // sites splits each four-cell corner into two three-cell ones, so that
  // its cells are hexagons, four facets each; merged, they are mostly
  // quadrilaterals of two (5.7 corners a cell on average before, 4.2
  // after, for the 240² portrait). A collapse is skipped when a cell it
  // touches would be left with under three corners (its light lost),
  // turned over, or off its area by more than `area_slack` of it; the
  // areas are then restored exactly (restore_cell_areas). The 240²
  // portrait at print_copy_pixels 1.5: 298,716 facets and SSIM 0.936
  // before, 227,541 and 0.940 after (benchmarks/RESULTS.md). (Edges
  // under 0.1 pixel only, unchecked and not restored: 2,300 dark cells
  // dropped, 0.008 SSIM lost.)
  constexpr double collapse_px = 0.02, corner_px = 0.8, area_slack = 0.4;
  std::vector<int> merged(points.size());
  std::iota(merged.begin(), merged.end(), 0);
  const auto root = [&](int v) {
    while (merged[static_cast<size_t>(v)] != v) v = merged[static_cast<size_t>(v)] = merged[static_cast<size_t>(merged[static_cast<size_t>(v)])];
    return v;
  };
  // A loop's corners as they stand merged (and `from` taken for `to`), none twice in a row.
  const auto merged_loop = [&](const std::vector<int>& loop, int from, int to, std::vector<int>& out) {
    out.clear();
    for (int v : loop) {
      int r = root(v);
      if (r == from) r = to;
      if (out.empty() || out.back() != r) out.push_back(r);
    }
    while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  };
  // 2 on a corner of the footprint, 1 on a side, 0 inside; the rim's
  // vertices stay on it.
  const auto rim_rank = [&](int v) {
    const Vec2& p = points[static_cast<size_t>(v)];
    return (std::abs(p.x()) == 1.0) + (std::abs(p.y()) == 1.0);
  };
  {
    std::vector<std::vector<int>> cells_at(points.size());  // per root: the cells with a corner in its group
    std::unordered_map<long long, std::array<int, 2>> parted;  // per edge: the cells on its two sides
    for (size_t i = 0; i < loops.size(); ++i)
      for (size_t k = 0; k < loops[i].size(); ++k) {
        cells_at[static_cast<size_t>(loops[i][k])].push_back(static_cast<int>(i));
        const auto [at, added] = parted.try_emplace(undirected_edge_key(loops[i][k], loops[i][(k + 1) % loops[i].size()]),
                                                    std::array<int, 2>{static_cast<int>(i), -1});
        if (!added) at->second[1] = static_cast<int>(i);
      }
    const auto side_by_side = [&](int i, int j) {
      if (j < 0) return true;  // the rim
      return std::abs(i / width - j / width) + std::abs(i % width - j % width) == 1;
    };
    struct Candidate {
      double length;
      long long key;
    };
    std::vector<Candidate> candidates;
    for (const auto& [key, cells] : parted) {
      const int a = static_cast<int>(key / 0x100000000LL), b = static_cast<int>(key % 0x100000000LL);
      const double length = (px(points[static_cast<size_t>(a)]) - px(points[static_cast<size_t>(b)])).norm();
      if (length <= collapse_px || (length <= corner_px && !side_by_side(cells[0], cells[1])))
        candidates.push_back({length, key});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return x.length != y.length ? x.length < y.length : x.key < y.key;
    });
    std::vector<int> loop_now;
    for (const Candidate& c : candidates) {
      const int a = root(static_cast<int>(c.key / 0x100000000LL)), b = root(static_cast<int>(c.key % 0x100000000LL));
      if (a == b) continue;
      const int rank_a = rim_rank(a), rank_b = rim_rank(b);
      // Both on the rim but on different sides (or two corners): the midpoint would leave it.
      if (rank_a > 0 && rank_b > 0 && (rank_a == 2 || rank_b == 2 || ((std::abs(points[static_cast<size_t>(a)].x()) == 1.0) !=
                                                                      (std::abs(points[static_cast<size_t>(b)].x()) == 1.0))))
        continue;
      const Vec2 was = points[static_cast<size_t>(a)];
      points[static_cast<size_t>(a)] = rank_a == rank_b ? Vec2(0.5 * (was + points[static_cast<size_t>(b)]))
                                       : rank_a > rank_b ? was : points[static_cast<size_t>(b)];
      // Tried with a in its new place and b merged into it.
      const auto keeps = [&](int cell) {
        merged_loop(loops[static_cast<size_t>(cell)], b, a, loop_now);
        const double area = loop_area(loop_now, points, to_px), light = light_px[static_cast<size_t>(cell)];
        return loop_now.size() >= 3 && area > 0 && std::abs(area - light) <= area_slack * light;
      };
      if (!std::all_of(cells_at[static_cast<size_t>(a)].begin(), cells_at[static_cast<size_t>(a)].end(), keeps) ||
          !std::all_of(cells_at[static_cast<size_t>(b)].begin(), cells_at[static_cast<size_t>(b)].end(), keeps)) {
        points[static_cast<size_t>(a)] = was;
        continue;
      }
      merged[static_cast<size_t>(b)] = a;
      ++made.collapsed_edges;
      std::vector<int>& into = cells_at[static_cast<size_t>(a)];
      into.insert(into.end(), cells_at[static_cast<size_t>(b)].begin(), cells_at[static_cast<size_t>(b)].end());
      std::sort(into.begin(), into.end());
      into.erase(std::unique(into.begin(), into.end()), into.end());
      cells_at[static_cast<size_t>(b)] = {};
    }
  }
  int pinched = 0;
  std::vector<int> kept;
  for (std::vector<int>& loop : loops) {
    merged_loop(loop, -1, -1, kept);
    std::vector<int> sorted = kept;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) ++pinched;
    loop = kept.size() >= 3 ? kept : std::vector<int>{};
  }
  made.pinched_cells = pinched;
  made.worst_area_error = restore_cell_areas(loops, light_px, points, to_px);
  // Each edge split into pieces at most 1.5 radii long along x and y (a
  // facet along it can then keep the radius), the same points for both
  // cells that share it (numbered from its lower vertex).
  const double edge_px = 1.5 * facet_radius_px;
  std::unordered_map<long long, std::vector<int>> splits;
  const auto edge_points = [&](int a, int b) -> const std::vector<int>& {
    const int low = std::min(a, b), high = std::max(a, b);
    const auto [at, added] = splits.try_emplace(undirected_edge_key(a, b));
    if (added) {
      const Vec2 p = points[static_cast<size_t>(low)], q = points[static_cast<size_t>(high)];
      const int pieces = std::max(1, static_cast<int>(std::ceil((px(q) - px(p)).cwiseAbs().maxCoeff() / edge_px)));
      for (int k = 1; k < pieces; ++k) {
        at->second.push_back(static_cast<int>(points.size()));
        points.push_back(p + (q - p) * (static_cast<double>(k) / pieces));
      }
    }
    return at->second;
  };
  std::vector<Eigen::Vector3i> top;
  std::vector<int> cell_of;  // per top triangle
  std::vector<int> ring;
  // Lattice spacings delaunay_cell tries (1e9: the boundary alone).
  const std::vector<double> lattice_spacings{1e9, 1.4 * facet_radius_px, 1.1 * facet_radius_px, 0.8 * facet_radius_px};
  for (size_t i = 0; i < loops.size(); ++i) {
    if (loops[i].empty()) continue;
    ++made.cells;
    ring.clear();
    for (size_t k = 0; k < loops[i].size(); ++k) {
      const int a = loops[i][k], b = loops[i][(k + 1) % loops[i].size()];
      ring.push_back(a);
      const std::vector<int>& between = edge_points(a, b);
      if (a < b) ring.insert(ring.end(), between.begin(), between.end());
      else ring.insert(ring.end(), between.rbegin(), between.rend());
    }
    const size_t n = ring.size();
    const auto at = [&](int v) { return px(points[static_cast<size_t>(v)]); };
    const auto emit = [&](int a, int b, int c) {
      top.emplace_back(a, b, c);
      cell_of.push_back(static_cast<int>(i));
      made.worst_facet_radius_px = std::max(made.worst_facet_radius_px, copy_radius(at(a), at(b), at(c)));
    };
    const auto emit_all = [&](const std::vector<Eigen::Vector3i>& facets) {
      for (const Eigen::Vector3i& f : facets) emit(f[0], f[1], f[2]);
    };
    // A fan from one of its corners if some fan's facets are all small enough.
    if (n <= 12) {
      int best = -1;
      double best_radius = std::numeric_limits<double>::infinity();
      for (size_t start = 0; start < n; ++start) {
        double worst = 0;
        for (size_t k = 1; k + 1 < n; ++k)
          worst = std::max(worst, copy_radius(at(ring[start]), at(ring[(start + k) % n]), at(ring[(start + k + 1) % n])));
        if (worst < best_radius) best_radius = worst, best = static_cast<int>(start);
      }
      if (best_radius <= facet_radius_px) {
        for (size_t k = 1; k + 1 < n; ++k)
          emit(ring[static_cast<size_t>(best)], ring[(static_cast<size_t>(best) + k) % n],
               ring[(static_cast<size_t>(best) + k + 1) % n]);
        continue;
      }
    }
    // Else a Delaunay triangulation of the boundary and, if need be, of
    // points inside on a square lattice, finer until the facets are small.
    if (delaunay_cell(ring, lattice_spacings, facet_radius_px, points, px, from_px, emit_all)) {
      continue;
    }
    // Else rings about the centroid, as many as keep the facets small.
    Vec2 centre = Vec2::Zero();
    for (int v : ring) centre += points[static_cast<size_t>(v)];
    centre /= static_cast<double>(n);
    int rings = 1;
    const auto ring_point = [&](size_t k, int r, int of) {
      return centre + (points[static_cast<size_t>(ring[k])] - centre) * (static_cast<double>(r) / of);
    };
    for (; rings < 16; ++rings) {
      double worst = 0;
      for (size_t k = 0; k < n; ++k) {
        worst = std::max(worst, copy_radius(px(centre), px(ring_point(k, 1, rings)), px(ring_point((k + 1) % n, 1, rings))));
        for (int r = 2; r <= rings; ++r) {
          const Vec2 i0 = px(ring_point(k, r - 1, rings)), i1 = px(ring_point((k + 1) % n, r - 1, rings));
          const Vec2 o0 = px(ring_point(k, r, rings)), o1 = px(ring_point((k + 1) % n, r, rings));
          if ((o0 - i1).squaredNorm() < (o1 - i0).squaredNorm())
            worst = std::max({worst, copy_radius(i0, o0, i1), copy_radius(o0, o1, i1)});
          else
            worst = std::max({worst, copy_radius(i0, o0, o1), copy_radius(i0, o1, i1)});
        }
      }
      if (worst <= facet_radius_px) break;
    }
    const int centre_id = static_cast<int>(points.size());
    points.push_back(centre);
    std::vector<int> inner(n, centre_id), outer(n);
    for (int r = 1; r <= rings; ++r) {
      for (size_t k = 0; k < n; ++k) {
        if (r == rings) {
          outer[k] = ring[k];
        } else {
          outer[k] = static_cast<int>(points.size());
          points.push_back(ring_point(k, r, rings));
        }
      }
      for (size_t k = 0; k < n; ++k) {
        const size_t next = (k + 1) % n;
        if (r == 1) {
          emit(centre_id, outer[k], outer[next]);
        } else if ((at(outer[k]) - at(inner[next])).squaredNorm() < (at(outer[next]) - at(inner[k])).squaredNorm()) {
          emit(inner[k], outer[k], inner[next]);
          emit(outer[k], outer[next], inner[next]);
        } else {
          emit(inner[k], outer[k], outer[next]);
          emit(inner[k], outer[next], inner[next]);
        }
      }
      inner = outer;
    }
  }
  made.top_triangles = top.size();
  made.mesh_seconds = seconds_since(began);

  // Heights: each facet's slope should send its centroid's light to its
  // pixel's centre; least squares over the facets' edges (below), three
  // rounds (the slab's lateral shift depends on the heights).
  began = Clock::now();
  const size_t vertex_count = points.size();
  const Vec2 to_mm(0.5 * s.width_mm, 0.5 * s.depth_mm);
  std::vector<Vec2> xy(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) xy[v] = points[v].cwiseProduct(to_mm);
  // Each facet's three edges should rise as its aimed slope says:
  // (h_b - h_a) = slope . (x_b - x_a), weighted by the facet's area over its
  // edges' squared lengths (for a well-shaped facet the same as its area
  // times the squared slope error; a sliver's huge ∇ does not take over).
  struct Facet {
    double weight = 0, area = 0;
  };
  std::vector<Facet> facets(top.size());
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(12 * top.size() + vertex_count);
  const auto corner = [&](size_t t, int k) { return static_cast<size_t>(top[t][k]); };
  for (size_t t = 0; t < top.size(); ++t) {
    const Vec2 a = xy[corner(t, 0)], b = xy[corner(t, 1)], c = xy[corner(t, 2)];
    Facet& f = facets[t];
    f.area = 0.5 * std::abs((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    const double edges = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    f.weight = edges > 0 ? f.area / edges : 0;
    for (int k = 0; k < 3; ++k) {
      const int p = top[t][k], q = top[t][(k + 1) % 3];
      entries.emplace_back(p, p, f.weight);
      entries.emplace_back(q, q, f.weight);
      entries.emplace_back(p, q, -f.weight);
      entries.emplace_back(q, p, -f.weight);
    }
  }
  // A whisper of the previous heights pins the level (and vertices only
  // zero-area facets touch).
  double trace = 0;
  for (const Eigen::Triplet<double>& e : entries) trace += e.row() == e.col() ? e.value() : 0;
  const double tie = 1e-8 * trace / static_cast<double>(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) entries.emplace_back(static_cast<int>(v), static_cast<int>(v), tie);
  Eigen::SparseMatrix<double> normal(static_cast<Eigen::Index>(vertex_count), static_cast<Eigen::Index>(vertex_count));
  normal.setFromTriplets(entries.begin(), entries.end());
  entries = {};
  fem::CholmodFactor solver;
  if (!solver.analyze_and_factorize(normal)) throw std::runtime_error("transport_cells_slab_mesh: the integration is singular");
  Eigen::VectorXd h = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(vertex_count), mean_height_mm), rhs;
  std::vector<Vec2> aims(top.size());
  for (int round = 0; round < 3; ++round) {
    rhs = tie * h;
    for (size_t t = 0; t < top.size(); ++t) {
      const Facet& f = facets[t];
      const Vec2 centroid = (xy[corner(t, 0)] + xy[corner(t, 1)] + xy[corner(t, 2)]) / 3;
      const double here = (h[top[t][0]] + h[top[t][1]] + h[top[t][2]]) / 3;
      const Vec2& y = sites[static_cast<size_t>(cell_of[t])];
      const Vec2 target = s.receiver_centre_mm + Vec2(0.5 * s.receiver_width_mm * y.x(), 0.5 * s.receiver_depth_mm * y.y());
      aims[t] = slope_towards(s, centroid, here, target);
      for (int k = 0; k < 3; ++k) {
        const int p = top[t][k], q = top[t][(k + 1) % 3];
        const double rise = f.weight * aims[t].dot(xy[static_cast<size_t>(q)] - xy[static_cast<size_t>(p)]);
        rhs[q] += rise;
        rhs[p] -= rise;
      }
    }
    solver.solve(rhs, h);
    h.array() += mean_height_mm - h.mean();
  }
  // The facets' slopes against their aims, over the top's area.
  double squared = 0, counted_area = 0;
  for (size_t t = 0; t < top.size(); ++t) {
    const Vec2 a = xy[corner(t, 0)], b = xy[corner(t, 1)], c = xy[corner(t, 2)];
    const double twice = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    // Slivers (area under 1 % of the longest edge squared) carry almost no
    // light, and their slopes are ill-defined: left out of the figure.
    const double longest = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    if (!(0.5 * std::abs(twice) >= 0.01 * longest)) continue;
    const auto perp = [](const Vec2& e) { return Vec2(-e.y(), e.x()); };
    const Vec2 slope = (h[top[t][0]] * perp(c - b) + h[top[t][1]] * perp(a - c) + h[top[t][2]] * perp(b - a)) / twice;
    squared += facets[t].area * (slope - aims[t]).squaredNorm();
    counted_area += facets[t].area;
  }
  made.rms_slope_error = std::sqrt(squared / std::max(counted_area, 1e-300));
  made.integration_seconds = seconds_since(began);

  // The closed slab: the top, walls down its rim, a bottom fanned from the centre.
  Mesh& mesh = made.mesh;
  mesh.vertices.resize(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    if (!(h[static_cast<Eigen::Index>(v)] > 0))
      throw InputError("caustics: the slab's top surface must stay above its bottom (heights > 0 mm)");
    mesh.vertices[v] = Vec3(xy[v].x(), xy[v].y(), h[static_cast<Eigen::Index>(v)]);
  }
  mesh.triangles = top;
  std::unordered_map<long long, int> directed;  // (a, b) -> uses
  for (const Eigen::Vector3i& t : top)
    for (int k = 0; k < 3; ++k) ++directed[edge_key(t[k], t[(k + 1) % 3])];
  std::unordered_map<int, int> rim_next;
  const double rim_tolerance = 1e-9 * (s.width_mm + s.depth_mm);
  const auto on_rim = [&](int v) {
    const Vec2& p = xy[static_cast<size_t>(v)];
    return std::abs(std::abs(p.x()) - 0.5 * s.width_mm) <= rim_tolerance ||
           std::abs(std::abs(p.y()) - 0.5 * s.depth_mm) <= rim_tolerance;
  };
  for (const auto& [key, uses] : directed) {
    const int a = static_cast<int>(key / 0x100000000LL), b = static_cast<int>(key % 0x100000000LL);
    if (directed.contains(edge_key(b, a))) continue;
    if (on_rim(a) && on_rim(b)) rim_next[a] = b;
    else ++made.open_edges;
  }
  if (rim_next.empty()) throw std::runtime_error("transport_cells_slab_mesh: the top has no rim");
  std::vector<int> rim;
  int v = rim_next.begin()->first;
  // Start at the rim vertex nearest the footprint's lowest corner, so that the walk is deterministic.
  for (const auto& [from, to] : rim_next)
    if (xy[static_cast<size_t>(from)].sum() < xy[static_cast<size_t>(v)].sum() ||
        (xy[static_cast<size_t>(from)].sum() == xy[static_cast<size_t>(v)].sum() && from < v))
      v = from;
  const int first = v;
  do {
    rim.push_back(v);
    const auto next = rim_next.find(v);
    if (next == rim_next.end() || rim.size() > rim_next.size())
      throw std::runtime_error(fmt::format("transport_cells_slab_mesh: the top's rim is not one loop ({} of {} rim edges walked, {} open edges, at ({}, {}))", rim.size(), rim_next.size(), made.open_edges, xy[static_cast<size_t>(v)].x(), xy[static_cast<size_t>(v)].y()));
    v = next->second;
  } while (v != first);
  close_slab_below_rim(mesh, rim);
  return made;
}

}  // namespace spec2fab

#include "caustics/optimal_transport.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Regular_triangulation_face_base_2.h>
#include <CGAL/Regular_triangulation_vertex_base_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <Eigen/SparseCore>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "fem/cholmod_factor.h"

namespace spec2fab {
namespace {

using Vec2 = Eigen::Vector2d;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int, Kernel, CGAL::Regular_triangulation_vertex_base_2<Kernel>>;
using FaceBase = CGAL::Regular_triangulation_face_base_2<Kernel>;
using Regular = CGAL::Regular_triangulation_2<Kernel, CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>>;

/// A convex polygon whose edge k runs from corner k to corner k + 1 and lies
/// on the bisector shared with site label[k] (-1: the source's boundary).
struct LabelledPolygon {
  std::vector<Vec2> corners;
  std::vector<int> labels;
};

/// Keeps the part of `in` where normal · x <= offset; the new edge along
/// the line gets `label`.
void clip(const LabelledPolygon& in, const Vec2& normal, double offset, int label, LabelledPolygon& out) {
  out.corners.clear();
  out.labels.clear();
  const size_t n = in.corners.size();
  for (size_t k = 0; k < n; ++k) {
    const Vec2& p = in.corners[k];
    const Vec2& q = in.corners[(k + 1) % n];
    const double sp = normal.dot(p) - offset, sq = normal.dot(q) - offset;
    if (sp <= 0) {
      out.corners.push_back(p);
      out.labels.push_back(in.labels[k]);
      if (sq > 0) {
        out.corners.push_back(p + sp / (sp - sq) * (q - p));
        out.labels.push_back(label);
      }
    } else if (sq <= 0) {
      out.corners.push_back(p + sp / (sp - sq) * (q - p));
      out.labels.push_back(in.labels[k]);
    }
  }
  if (out.corners.size() < 3) {
    out.corners.clear();
    out.labels.clear();
  }
}

double polygon_area(const std::vector<Vec2>& p) {
  double twice = 0;
  for (size_t k = 0; k < p.size(); ++k) {
    const Vec2& a = p[k];
    const Vec2& b = p[(k + 1) % p.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

/// The power diagram of the sites with the given weights, clipped to the
/// source (centred on the origin; `inner`: the radius of a disc about the
/// origin inside it): each cell's area and corners, and the length of every
/// edge between two cells. Built once per Newton trial, for up to a quarter
/// million sites: the neighbours and the edges live in flat arrays and the
/// clipping in two polygons per task, so that a cell costs one allocation
/// (its corners) rather than a dozen (at 512 x 512 sites malloc and free
/// had been ~30 % of the transport).
struct PowerDiagram {
  std::vector<double> areas;
  std::vector<std::vector<Vec2>> corners;  ///< each cell's, counter-clockwise (empty: no cell)
  std::vector<Eigen::Triplet<double>> edges;  ///< (i, j, length / (2 |y_i - y_j|)), each pair once per side

  PowerDiagram(std::span<const Vec2> source, double inner, std::span<const Vec2> sites, const std::vector<double>& weights) {
    const size_t n = sites.size();
    std::vector<std::pair<Regular::Weighted_point, int>> points;
    points.reserve(n);
    for (size_t i = 0; i < n; ++i)
      points.emplace_back(Regular::Weighted_point(Regular::Bare_point(sites[i].x(), sites[i].y()), weights[i]),
                          static_cast<int>(i));
    Regular regular;
    regular.insert(points.begin(), points.end());
    // Each site's neighbours in the triangulation, in the order its vertex's
    // circulator gives them: `neighbours[first[i]]` on, `degree[i]` of them.
    // A hidden site (no vertex) has none and no cell.
    std::vector<size_t> first(n, 0);
    std::vector<int> degree(n, 0), neighbours;
    neighbours.reserve(6 * n + 16);  // a planar triangulation's vertices average < 6 neighbours
    std::vector<char> visible(n, 0);
    for (auto v = regular.finite_vertices_begin(); v != regular.finite_vertices_end(); ++v) {
      const auto i = static_cast<size_t>(v->info());
      visible[i] = 1;
      first[i] = neighbours.size();
      auto around = regular.incident_vertices(v), done = around;
      if (around == nullptr) continue;
      do {
        if (!regular.is_infinite(around)) neighbours.push_back(around->info());
      } while (++around != done);
      degree[i] = static_cast<int>(neighbours.size() - first[i]);
    }
    areas.assign(n, 0.0);
    corners.assign(n, {});
    // A cell has at most one edge on each neighbour's bisector: its edges
    // go to its neighbours' slots, `edge_count[i]` of them used.
    std::vector<Eigen::Triplet<double>> slots(neighbours.size());
    std::vector<int> edge_count(n, 0);
    Vec2 low = source[0], high = source[0];
    for (const Vec2& p : source) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 512), [&](const tbb::blocked_range<size_t>& range) {
      LabelledPolygon cell, work;
      for (size_t i = range.begin(); i != range.end(); ++i) {
        if (!visible[i]) continue;
        // The cell within the source's bounding box, then, only where it
        // reaches beyond the inner disc, within the source itself.
        cell.corners.assign({low, Vec2(high.x(), low.y()), high, Vec2(low.x(), high.y())});
        cell.labels.assign(4, -1);
        const Vec2& yi = sites[i];
        for (size_t k = first[i]; k < first[i] + static_cast<size_t>(degree[i]); ++k) {
          const int j = neighbours[k];
          const Vec2& yj = sites[static_cast<size_t>(j)];
          // |x - y_i|² - ψ_i <= |x - y_j|² - ψ_j
          const Vec2 normal = 2 * (yj - yi);
          const double offset = weights[i] - weights[static_cast<size_t>(j)] - yi.squaredNorm() + yj.squaredNorm();
          clip(cell, normal, offset, j, work);
          std::swap(cell, work);
          if (cell.corners.empty()) break;
        }
        bool inside = true;
        for (const Vec2& p : cell.corners) inside = inside && p.norm() <= inner;
        for (size_t k = 0; k < source.size() && !inside && !cell.corners.empty(); ++k) {
          const Vec2& a = source[k];
          const Vec2& b = source[(k + 1) % source.size()];
          const Vec2 outward(b.y() - a.y(), a.x() - b.x());  // counter-clockwise polygon
          clip(cell, outward, outward.dot(a), -1, work);
          std::swap(cell, work);
        }
        areas[i] = polygon_area(cell.corners);
        Eigen::Triplet<double>* edge = slots.data() + first[i];
        Eigen::Triplet<double>* const end = slots.data() + first[i] + degree[i];
        for (size_t k = 0; k < cell.corners.size(); ++k) {
          const int j = cell.labels[k];
          if (j < 0) continue;
          if (edge == end) throw std::logic_error("optimal transport: a cell has more edges than neighbours");
          const double length = (cell.corners[(k + 1) % cell.corners.size()] - cell.corners[k]).norm();
          *edge++ = {static_cast<int>(i), j, length / (2 * (sites[static_cast<size_t>(j)] - yi).norm())};
        }
        edge_count[i] = static_cast<int>(edge - (slots.data() + first[i]));
        corners[i].assign(cell.corners.begin(), cell.corners.end());
      }
    });
    edges.reserve(neighbours.size());
    for (size_t i = 0; i < n; ++i)
      edges.insert(edges.end(), slots.begin() + static_cast<std::ptrdiff_t>(first[i]),
                   slots.begin() + static_cast<std::ptrdiff_t>(first[i]) + edge_count[i]);
  }
};

/// The source and sites about the source's centre, where the start below
/// holds: ψ_i = (1 - λ)|y_i|² makes the cells the Voronoi cells of the sites
/// shrunk by λ about the origin, all inside the source when λ is small
/// enough (the source holds the origin).
struct CentredProblem {
  Vec2 centre = Vec2::Zero();
  std::vector<Vec2> source, sites;
  double inner = std::numeric_limits<double>::infinity();  ///< the source's edges' least distance from the centre
  std::vector<double> start;                                ///< ψ of the shrunk Voronoi cells

  CentredProblem(const std::vector<Vec2>& polygon, std::span<const Vec2> targets) : source(polygon), sites(targets.size()) {
    for (const Vec2& p : polygon) centre += p;
    centre /= static_cast<double>(polygon.size());
    for (size_t i = 0; i < sites.size(); ++i) sites[i] = targets[i] - centre;
    for (Vec2& p : source) p -= centre;
    double reach = 0;
    for (const Vec2& y : sites) reach = std::max(reach, y.norm());
    for (size_t k = 0; k < source.size(); ++k) {
      const Vec2 a = source[k], b = source[(k + 1) % source.size()];
      const Vec2 edge = (b - a).normalized();
      inner = std::min(inner, std::abs(a.x() * edge.y() - a.y() * edge.x()));  // distance of the line from the centre
    }
    const double lambda = std::min(1.0, 0.9 * inner / std::max(reach, 1e-300));
    start.resize(sites.size());
    for (size_t i = 0; i < sites.size(); ++i) start[i] = (1 - lambda) * sites[i].squaredNorm();
  }
  std::unique_ptr<PowerDiagram> diagram(const std::vector<double>& psi) const {
    return std::make_unique<PowerDiagram>(source, inner, sites, psi);
  }
};

size_t empty_cells(const PowerDiagram& diagram) {
  return static_cast<size_t>(std::count_if(diagram.areas.begin(), diagram.areas.end(), [](double a) { return !(a > 0); }));
}

/// The first diagram: from the guessed weights where they leave no cell
/// empty; else blended towards the start as little as leaves none (1/4,
/// 1/2); else from the start. The blend costs the guess much of its worth:
/// a 512 x 512 photograph's guess leaves 1,588 cells empty (dark pixels
/// beside bright ones), blended by 1/4 none, but its worst cell starts 338
/// mean masses off and Newton takes 21 steps. (Blends of 1/16 and 1/8 left
/// 127 and 22 empty; giving each empty cell a small one where its nearest
/// site's lies emptied more cells than it filled.) The weights do not
/// change with the shift of origin: |x - y|² - ψ compares the same way for
/// x and y moved together. Sets `psi` to its.
std::unique_ptr<PowerDiagram> first_diagram(const CentredProblem& problem, std::span<const double> initial_weights,
                                            std::vector<double>& psi) {
  const size_t n = problem.sites.size();
  psi = problem.start;
  if (initial_weights.size() == n) {
    for (double blend : {0.0, 0.25, 0.5}) {
      std::vector<double> guess(n);
      for (size_t i = 0; i < n; ++i) guess[i] = (1 - blend) * initial_weights[i] + blend * psi[i];
      std::unique_ptr<PowerDiagram> diagram = problem.diagram(guess);
      const size_t empty = empty_cells(*diagram);
      spdlog::debug("optimal transport, {} sites: the guess blended {:g} towards the start leaves {} cell(s) empty", n,
                    blend, empty);
      if (empty == 0) {
        psi = std::move(guess);
        return diagram;
      }
    }
  }
  return problem.diagram(psi);
}

/// ∂area_i/∂ψ: a graph Laplacian over neighbouring cells, ψ_0 held (the
/// weights are defined up to a constant).
Eigen::SparseMatrix<double> area_hessian(const PowerDiagram& diagram, size_t n) {
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(2 * diagram.edges.size() + n);
  std::vector<double> diagonal(n, 0.0);
  for (const auto& e : diagram.edges) {
    diagonal[static_cast<size_t>(e.row())] += e.value();
    if (e.row() > 0 && e.col() > 0) entries.emplace_back(e.row() - 1, e.col() - 1, -e.value());
  }
  for (size_t i = 1; i < n; ++i) entries.emplace_back(static_cast<int>(i) - 1, static_cast<int>(i) - 1, diagonal[i]);
  Eigen::SparseMatrix<double> hessian(static_cast<Eigen::Index>(n - 1), static_cast<Eigen::Index>(n - 1));
  hessian.setFromTriplets(entries.begin(), entries.end());
  return hessian;
}

/// The masses as areas of the source (they sum to its area).
std::vector<double> target_areas(std::span<const double> masses, double source_area) {
  double total = 0;
  for (double m : masses) {
    if (!(m > 0) || !std::isfinite(m)) throw InputError("optimal transport: every mass must be positive and finite");
    total += m;
  }
  std::vector<double> nu(masses.size());
  for (size_t i = 0; i < masses.size(); ++i) nu[i] = masses[i] * source_area / total;
  return nu;
}

}  // namespace

SemiDiscreteTransport solve_semi_discrete_transport(std::span<const Vec2> source, std::span<const Vec2> sites,
                                                    std::span<const double> masses, double tolerance, int max_steps,
                                                    std::span<const double> initial_weights) {
  const size_t n = sites.size();
  if (n < 2 || masses.size() != n) throw InputError("optimal transport: needs two or more sites, one mass each");
  std::vector<Vec2> polygon(source.begin(), source.end());
  const double source_area = polygon_area(polygon);
  if (polygon.size() < 3 || !(source_area > 0)) throw InputError("optimal transport: the source must be a counter-clockwise polygon");
  const std::vector<double> nu = target_areas(masses, source_area);
  const double mean_mass = source_area / static_cast<double>(n);
  const CentredProblem problem(polygon, sites);

  SemiDiscreteTransport result;
  std::vector<double> psi;
  std::unique_ptr<PowerDiagram> diagram = first_diagram(problem, initial_weights, psi);
  const auto residual = [&](const PowerDiagram& d) {
    Eigen::VectorXd g(static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i) g[static_cast<Eigen::Index>(i)] = nu[i] - d.areas[i];
    return g;
  };
  const double floor_area = 0.5 * std::min(*std::min_element(nu.begin(), nu.end()),
                                           *std::min_element(diagram->areas.begin(), diagram->areas.end()));
  if (!(floor_area > 0)) throw std::runtime_error("optimal transport: a starting cell is empty");
  Eigen::VectorXd g = residual(*diagram);
  // The Newton system is a graph Laplacian over the diagram's neighbours
  // (planar: ~7 entries a row), its pattern new at each step. CHOLMOD's
  // supernodal factor (the FEM's): Eigen's simplicial LDLT was ~40 % of a
  // 512 x 512 photograph's run (262,143 rows), most of the transport.
  fem::CholmodFactor solver;
  Eigen::VectorXd direction;
  for (int step = 0;; ++step) {
    result.worst_mass_error = g.cwiseAbs().maxCoeff() / mean_mass;
    if (result.worst_mass_error <= tolerance) break;
    if (step == max_steps)
      throw std::runtime_error("optimal transport: Newton did not converge in " + std::to_string(max_steps) +
                               " steps (worst cell " + std::to_string(result.worst_mass_error) + " of the mean mass off)");
    // (Analysed anew: the pattern follows the diagram's adjacency.)
    if (!solver.analyze_and_factorize(area_hessian(*diagram, n)))
      throw std::runtime_error("optimal transport: the Newton system is singular");
    solver.solve(g.tail(static_cast<Eigen::Index>(n - 1)).eval(), direction);
    // Damping: halve the step until no cell shrinks below the floor and the
    // error falls (Kitagawa, Mérigot, Thibert, Algorithm 1).
    const double error = g.norm();
    int trials = 0;
    for (double t = 1;; t *= 0.5) {
      ++trials;
      if (t < 1e-10) throw std::runtime_error("optimal transport: the Newton step cannot be damped enough");
      std::vector<double> trial = psi;
      for (size_t i = 1; i < n; ++i) trial[i] += t * direction[static_cast<Eigen::Index>(i - 1)];
      auto next = problem.diagram(trial);
      const Eigen::VectorXd trial_g = residual(*next);
      if (*std::min_element(next->areas.begin(), next->areas.end()) >= floor_area &&
          trial_g.norm() <= (1 - 0.5 * t) * error) {
        psi = std::move(trial);
        diagram = std::move(next);
        g = trial_g;
        // A large transport's steps take seconds each: what each did, with -v.
        spdlog::debug("optimal transport, {} sites: Newton step {}, step length {:g} ({} diagram(s)); worst cell {:.3g} of the mean mass off",
                      n, step + 1, t, trials, g.cwiseAbs().maxCoeff() / mean_mass);
        break;
      }
    }
    result.newton_steps = step + 1;
  }
  result.weights = psi;
  result.cells.resize(n);
  for (size_t i = 0; i < n; ++i) {
    result.cells[i] = std::move(diagram->corners[i]);
    for (Vec2& p : result.cells[i]) p += problem.centre;
  }
  return result;
}

std::vector<double> transport_weights_guess(std::span<const Vec2> coarse_sites, std::span<const double> coarse_weights,
                                            int coarse_nx, int coarse_ny, std::span<const Vec2> sites) {
  if (coarse_sites.size() != static_cast<size_t>(coarse_nx) * static_cast<size_t>(coarse_ny) ||
      coarse_weights.size() != coarse_sites.size() || coarse_nx < 2 || coarse_ny < 2)
    throw std::invalid_argument("transport_weights_guess: a coarse grid of sites with one weight each expected");
  const auto at = [&](int i, int j) { return static_cast<size_t>(j) * static_cast<size_t>(coarse_nx) + static_cast<size_t>(i); };
  const auto potential = [&](size_t k) { return coarse_weights[k]; };
  const Vec2 origin = coarse_sites[at(0, 0)];
  const Vec2 step(coarse_sites[at(1, 0)].x() - origin.x(), coarse_sites[at(0, 1)].y() - origin.y());
  std::vector<double> weights;
  weights.reserve(sites.size());
  for (const Vec2& y : sites) {
    // Bilinear within the coarse grid, linear extrapolation beyond it.
    const double u = (y.x() - origin.x()) / step.x(), v = (y.y() - origin.y()) / step.y();
    const int i = std::clamp(static_cast<int>(std::floor(u)), 0, coarse_nx - 2);
    const int j = std::clamp(static_cast<int>(std::floor(v)), 0, coarse_ny - 2);
    const double fu = u - i, fv = v - j;
    const double value = (1 - fu) * (1 - fv) * potential(at(i, j)) + fu * (1 - fv) * potential(at(i + 1, j)) +
                         (1 - fu) * fv * potential(at(i, j + 1)) + fu * fv * potential(at(i + 1, j + 1));
    weights.push_back(value);
  }
  return weights;
}

std::vector<Vec2> mean_transport_targets(const SemiDiscreteTransport& transport, std::span<const Vec2> sites, int nx,
                                         int ny, const Vec2& lower, const Vec2& upper) {
  std::vector<Vec2> means;
  for (const TransportMoments& m : transport_moments(transport, sites, nx, ny, lower, upper)) means.push_back(m.mean);
  return means;
}

std::vector<TransportMoments> transport_moments(const SemiDiscreteTransport& transport, std::span<const Vec2> sites,
                                                int nx, int ny, const Vec2& lower, const Vec2& upper) {
  const Vec2 size = upper - lower;
  const double dx = size.x() / nx, dy = size.y() / ny;
  std::vector<Vec2> weighted(static_cast<size_t>(nx) * static_cast<size_t>(ny), Vec2::Zero());
  std::vector<Eigen::Matrix2d> second(weighted.size(), Eigen::Matrix2d::Zero());
  std::vector<double> covered(weighted.size(), 0.0);
  LabelledPolygon cell, work, strip, piece;
  for (size_t i = 0; i < transport.cells.size(); ++i) {
    const std::vector<Vec2>& polygon = transport.cells[i];
    if (polygon.empty()) continue;
    Vec2 low = polygon[0], high = polygon[0];
    for (const Vec2& p : polygon) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
    const int c0 = std::clamp(static_cast<int>(std::floor((low.x() - lower.x()) / dx)), 0, nx - 1);
    const int c1 = std::clamp(static_cast<int>(std::floor((high.x() - lower.x()) / dx)), 0, nx - 1);
    const int r0 = std::clamp(static_cast<int>(std::floor((low.y() - lower.y()) / dy)), 0, ny - 1);
    const int r1 = std::clamp(static_cast<int>(std::floor((high.y() - lower.y()) / dy)), 0, ny - 1);
    cell.corners = polygon;
    cell.labels.assign(polygon.size(), -1);
    for (int c = c0; c <= c1; ++c) {
      const double x0 = lower.x() + c * dx;
      clip(cell, Vec2(-1, 0), c == 0 ? std::numeric_limits<double>::infinity() : -x0, -1, work);
      clip(work, Vec2(1, 0), c == nx - 1 ? std::numeric_limits<double>::infinity() : x0 + dx, -1, strip);
      if (strip.corners.empty()) continue;
      for (int r = r0; r <= r1; ++r) {
        const double y0 = lower.y() + r * dy;
        clip(strip, Vec2(0, -1), r == 0 ? std::numeric_limits<double>::infinity() : -y0, -1, work);
        clip(work, Vec2(0, 1), r == ny - 1 ? std::numeric_limits<double>::infinity() : y0 + dy, -1, piece);
        if (piece.corners.empty()) continue;
        const double area = polygon_area(piece.corners);
        const size_t square = static_cast<size_t>(r) * static_cast<size_t>(nx) + static_cast<size_t>(c);
        weighted[square] += area * sites[i];
        second[square] += area * sites[i] * sites[i].transpose();
        covered[square] += area;
      }
    }
  }
  std::vector<TransportMoments> moments(weighted.size());
  for (size_t k = 0; k < weighted.size(); ++k) {
    moments[k].mass = covered[k];
    if (covered[k] > 1e-12 * dx * dy) {
      moments[k].mean = weighted[k] / covered[k];
      // About the mean; never below zero where rounding would put it.
      const Eigen::Matrix2d about = second[k] / covered[k] - moments[k].mean * moments[k].mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(about);
      moments[k].covariance = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() *
                              eigen.eigenvectors().transpose();
    } else {
      moments[k].mean.setConstant(std::numeric_limits<double>::quiet_NaN());
      moments[k].covariance.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  return moments;
}

}  // namespace spec2fab

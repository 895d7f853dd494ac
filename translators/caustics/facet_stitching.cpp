#include "facet_stitching.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/SparseCholesky>

#include "core/parameter.h"
#include "reducer/height_surface.h"
#include "reducer/node.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

/// visit(k, m, c, d) for every shared corner: corner c of facet k meets
/// corner d of its east or north neighbour m (corners numbered as in
/// corner_heights).
template <class Visit>
void for_each_seam(const FacetGrid& grid, Visit&& visit) {
  const std::array<int, 2>& facets = grid.facets;
  for (int j = 0; j < facets[1]; ++j)
    for (int i = 0; i < facets[0]; ++i) {
      const size_t k = grid.index(i, j);
      if (i + 1 < facets[0]) visit(k, grid.index(i + 1, j), 1, 0), visit(k, grid.index(i + 1, j), 2, 3);
      if (j + 1 < facets[1]) visit(k, grid.index(i, j + 1), 3, 0), visit(k, grid.index(i, j + 1), 2, 1);
    }
}

}  // namespace

std::array<double, 4> FacetGrid::corner_heights(const HeightSurface& p) const {
  const double a = facet_mm[0], b = facet_mm[1];
  return {p.surface_height(0, 0), p.surface_height(a, 0), p.surface_height(a, b), p.surface_height(0, b)};
}

StitchReport stitch_facet_offsets(ReducerNode& columns, const FacetGrid& grid, double start_mm, double floor_mm,
                                  double top_mm) {
  const size_t n = columns.child_count();
  const auto corner_heights = [&](size_t k) { return grid.corner_heights(*columns.child(k).height_surface()); };
  std::vector<std::array<double, 4>> shape(n);  // corner heights above the plane's offset
  std::vector<Parameter*> offsets(n);
  for (size_t k = 0; k < n; ++k) {
    columns.child(k).visit_parameters([&](const std::string& name, Parameter& p) {
      if (name == "offset_mm") offsets[k] = &p;
    });
    const auto corners = corner_heights(k);
    for (int c = 0; c < 4; ++c) shape[k][static_cast<size_t>(c)] = corners[static_cast<size_t>(c)] - offsets[k]->value();
  }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  const double pull = 1e-6;
  const double start = start_mm;
  // Each seam's step (o_k + s_kc) − (o_m + s_md) in the least squares.
  for_each_seam(grid, [&](size_t k, size_t m, int c, int d) {
    const double gap = shape[k][static_cast<size_t>(c)] - shape[m][static_cast<size_t>(d)];
    const auto ik = static_cast<int>(k), im = static_cast<int>(m);
    entries.emplace_back(ik, ik, 1.0);
    entries.emplace_back(im, im, 1.0);
    entries.emplace_back(ik, im, -1.0);
    entries.emplace_back(im, ik, -1.0);
    rhs[ik] -= gap;
    rhs[im] += gap;
  });
  for (size_t k = 0; k < n; ++k) {
    entries.emplace_back(static_cast<int>(k), static_cast<int>(k), pull);
    rhs[static_cast<Eigen::Index>(k)] += pull * start;
  }
  Eigen::SparseMatrix<double> normal(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  normal.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  Eigen::VectorXd solved = solver.solve(rhs);
  if (solver.info() != Eigen::Success || !solved.allFinite()) throw std::runtime_error("facet caustics: offset stitching failed");
  double lowest = HUGE_VAL;
  for (size_t k = 0; k < n; ++k)
    for (double s : shape[k]) lowest = std::min(lowest, solved[static_cast<Eigen::Index>(k)] + s);
  StitchReport report;
  const double floor = floor_mm, top = top_mm;
  for (size_t k = 0; k < n; ++k) {
    double o = solved[static_cast<Eigen::Index>(k)] + floor - lowest;
    const double highest = o + *std::max_element(shape[k].begin(), shape[k].end());
    if (highest > top) {
      o -= highest - top;
      ++report.lowered;
    }
    offsets[k]->set(o);
  }
  evaluate_subtree(columns);
  std::vector<std::array<double, 4>> corners(n);
  for (size_t k = 0; k < n; ++k) corners[k] = corner_heights(k);
  double sum = 0;
  long long count = 0;
  for_each_seam(grid, [&](size_t k, size_t m, int c, int d) {
    const double step = std::abs(corners[k][static_cast<size_t>(c)] - corners[m][static_cast<size_t>(d)]);
    sum += step * step;
    ++count;
    report.max_step_mm = std::max(report.max_step_mm, step);
  });
  report.rms_step_mm = count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
  return report;
}

}  // namespace spec2fab

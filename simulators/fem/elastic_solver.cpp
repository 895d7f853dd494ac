#include "fem/elastic_solver.h"
#include "fem/elastic_solver_impl.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "fem/stiffness_pattern.h"

namespace spec2fab::fem {

ElasticSolver::ElasticSolver(const TetMesh& mesh, const std::vector<char>& fixed, LinearSolver linear_solver,
                             bool distributed)
    : mesh_(mesh), impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.kind = linear_solver;
  const std::vector<int> node_order = m.number_free_dofs(mesh, fixed);
  m.shape_rest(mesh);
  m.split_rows(mesh, node_order, distributed);
  StiffnessPattern pattern = stiffness_pattern(mesh, m.dof_index, m.free_count, m.share);
  m.stiffness = std::move(pattern.lower);
  m.diagonal = std::move(pattern.diagonal);
  m.scatter = std::move(pattern.scatter);
  m.make_linear_solver(mesh, node_order, distributed);
  m.size_buffers(mesh);
}

ElasticSolver::~ElasticSolver() = default;

size_t ElasticSolver::free_dofs() const { return static_cast<size_t>(impl_->free_count); }
double ElasticSolver::factor_nonzeros() const {
  return impl_->kind == LinearSolver::cholesky ? impl_->cholesky.factor_nonzeros() : 0.0;
}
double ElasticSolver::factor_flops() const {
  return impl_->kind == LinearSolver::cholesky ? impl_->cholesky.factor_flops() : 0.0;
}

double ElasticSolver::multigrid_complexity() const {
  if (impl_->gamg) return impl_->gamg->operator_complexity();
  if (impl_->block_amg) return impl_->block_amg->operator_complexity();
  return impl_->amg ? impl_->amg->operator_complexity() : 0.0;
}

int ElasticSolver::solve_ranks() const { return impl_->gamg ? impl_->gamg->ranks() : 1; }

size_t ElasticSolver::assembled_tets() const {
  const Impl& m = *impl_;
  if (m.share.whole()) return mesh_.tets.size();
  return static_cast<size_t>(std::count(m.share.tets.begin(), m.share.tets.end(), 1));
}

long long ElasticSolver::stiffness_entries() const { return impl_->stiffness.nonZeros(); }

void ElasticSolver::set_materials(std::span<const double> lambda, std::span<const double> mu,
                                  std::span<const char> active) {
  Impl& m = *impl_;
  if (lambda.size() != m.lambda.size() || mu.size() != m.mu.size() || active.size() != m.active.size()) {
    throw std::logic_error("ElasticSolver::set_materials: one value per tet");
  }
  std::copy(lambda.begin(), lambda.end(), m.lambda.begin());
  std::copy(mu.begin(), mu.end(), m.mu.begin());
  std::copy(active.begin(), active.end(), m.active.begin());
  std::fill(m.node_active.begin(), m.node_active.end(), 0);
  for (size_t t = 0; t < mesh_.tets.size(); ++t) {
    if (!m.active[t]) continue;
    for (int v : mesh_.tets[t]) m.node_active[static_cast<size_t>(v)] = 1;
  }
}

Eigen::MatrixXd ElasticSolver::free_rows(std::span<const std::vector<double>> vectors) const {
  const Impl& m = *impl_;
  const size_t dofs = 3 * mesh_.nodes.size();
  Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(m.free_count, static_cast<Eigen::Index>(vectors.size()));
  for (size_t k = 0; k < vectors.size(); ++k) {
    if (vectors[k].size() != dofs) throw std::logic_error("ElasticSolver::free_rows: 3 values per node");
    for (size_t d = 0; d < dofs; ++d)
      if (const int i = m.dof_index[d]; i >= 0) rows(i, static_cast<Eigen::Index>(k)) = vectors[k][d];
  }
  return rows;
}

std::optional<ElasticSolver::InverseProducts> ElasticSolver::inverse_products(const Eigen::MatrixXd& free_vectors) {
  Impl& m = *impl_;
  if (free_vectors.rows() != m.free_count || free_vectors.cols() == 0)
    throw std::logic_error("ElasticSolver::inverse_products: one row per free DOF, at least one column");
  m.form_linear_stiffness(mesh_);
  Eigen::MatrixXd& solution = m.block_solution;
  InverseProducts out;
  if (m.kind == LinearSolver::cholesky) {  // factorised once, every vector in one forward block solve
    if (!m.cholesky.factorize(m.stiffness)) return std::nullopt;
    m.cholesky.forward_solve(free_vectors, solution);
    if (!solution.allFinite()) return std::nullopt;
    out.with_first = solution.transpose() * solution.col(0);
    out.diagonal = solution.colwise().squaredNorm().transpose();
    return out;
  }
  // The iterative solvers: set up once, then X = K⁻¹V column by column.
  solution.resize(free_vectors.rows(), free_vectors.cols());
  SolveReport report;
  if (!m.prepare(report)) return std::nullopt;
  for (Eigen::Index k = 0; k < free_vectors.cols(); ++k) {
    m.residual = free_vectors.col(k);
    if (!m.solve_prepared(report)) return std::nullopt;
    solution.col(k) = m.step;
  }
  out.with_first = free_vectors.transpose() * solution.col(0);
  out.diagonal = (free_vectors.array() * solution.array()).colwise().sum().transpose();
  return out;
}

}  // namespace spec2fab::fem

#include "fem/elastic_solver.h"

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <stdexcept>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>

#include "core/error.h"
#include "fem/cholmod_factor.h"
#include "fem/hypre/amg_solver.h"
#include "fem/petsc/gamg_solver.h"

namespace spec2fab::fem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
constexpr size_t kPairs = 78;  // 12·13/2 entries of a symmetric 12×12
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

struct ElasticSolver::Impl {
  std::vector<TetRest> rest;
  std::vector<int> dof_index;   // full DOF -> free index, or -1
  int free_count = 0;
  // Per tet, for each of its 78 local pairs i <= j (column-major upper
  // triangle; element matrices are symmetric): the position of the global
  // lower-triangle entry in the matrix's value array, or -1 (a fixed DOF).
  std::vector<int> scatter;
  std::vector<int> diagonal;  // position of each free DOF's diagonal entry
  SparseMatrix stiffness;     // lower triangle of the free-free block
  CholmodFactor cholesky;
  std::unique_ptr<Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>> ldlt;  // made and analysed on first need
  bool use_ldlt = false;  // the last prepare() found K indefinite
  LinearSolver kind = LinearSolver::cholesky;
  using Preconditioner = Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>;
  std::unique_ptr<Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower, Preconditioner>> cg;
  std::unique_ptr<AmgSolver> amg;
  std::unique_ptr<GamgSolver> gamg;

  std::vector<double> lambda, mu;
  std::vector<char> active;
  std::vector<char> node_active;

  // Work buffers, sized once.
  Eigen::VectorXd residual, step;
  Eigen::MatrixXd block_solution;  // inverse_products', kept: the elastic bound calls it per subtree
  std::vector<double> forces, trial, last_converged, previous_converged;
  Eigen::VectorXd saved_residual;

  // Forms f_int (full) and, if `tangent`, the stiffness values.
  // Returns the elastic energy (N·mm).
  double form(const TetMesh& mesh, std::span<const double> u, bool corotated, bool tangent) {
    double energy = 0;
    std::fill(forces.begin(), forces.end(), 0.0);
    double* values = stiffness.valuePtr();
    if (tangent) std::fill(values, values + stiffness.nonZeros(), 0.0);
    Vec12 f;
    Mat12 k;
    double x[12];
    // Small strain: the tangent is the constant stiffness, in closed form.
    const bool linear_tangent = tangent && !corotated;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      if (!active[t]) continue;
      const Tet& tet = mesh.tets[t];
      for (int a = 0; a < 4; ++a) {
        const auto v = static_cast<size_t>(tet[static_cast<size_t>(a)]);
        for (int d = 0; d < 3; ++d) x[3 * a + d] = mesh.nodes[v][d] + u[3 * v + static_cast<size_t>(d)];
      }
      energy += tet_forces(rest[t], lambda[t], mu[t], x, corotated, f, tangent && !linear_tangent ? &k : nullptr);
      for (int a = 0; a < 4; ++a) {
        const auto v = static_cast<size_t>(tet[static_cast<size_t>(a)]);
        for (int d = 0; d < 3; ++d) forces[3 * v + static_cast<size_t>(d)] += f[3 * a + d];
      }
      if (!tangent) continue;
      if (linear_tangent) linear_tet_stiffness(rest[t], lambda[t], mu[t], k);
      add_element(t, k, values);
    }
    if (tangent) hold_untouched_nodes(values);
    return energy;
  }

  // The small-strain stiffness alone (a linear solve needs no forces).
  void form_linear_stiffness(const TetMesh& mesh) {
    double* values = stiffness.valuePtr();
    std::fill(values, values + stiffness.nonZeros(), 0.0);
    Mat12 k;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      if (!active[t]) continue;
      linear_tet_stiffness(rest[t], lambda[t], mu[t], k);
      add_element(t, k, values);
    }
    hold_untouched_nodes(values);
  }

  void add_element(size_t t, const Mat12& k, double* values) const {
    const int* map = &scatter[kPairs * t];
    for (int j = 0; j < 12; ++j) {
      for (int i = 0; i <= j; ++i, ++map) {
        if (*map >= 0) values[*map] += k(i, j);
      }
    }
  }

  // Nodes no active tet touches: keep them where they are.
  void hold_untouched_nodes(double* values) const {
    for (size_t v = 0; v < node_active.size(); ++v) {
      if (node_active[v]) continue;
      for (size_t d = 0; d < 3; ++d) {
        if (const int i = dof_index[3 * v + d]; i >= 0) values[diagonal[static_cast<size_t>(i)]] = 1.0;
      }
    }
  }

  // Sets the linear solver up for the current stiffness: CHOLMOD's
  // factor (LDLᵀ where K is not positive definite: a compressed, buckling
  // state), the incomplete factor, or a multigrid hierarchy. False when
  // that fails.
  bool prepare(SolveReport& report) {
    ++report.factorizations;
    const auto start = Clock::now();
    bool ok = true;
    switch (kind) {
      case LinearSolver::multigrid: amg->setup(stiffness); break;
      case LinearSolver::elastic_multigrid: gamg->setup(stiffness); break;
      case LinearSolver::conjugate_gradient:
        cg->compute(stiffness);
        ok = cg->info() == Eigen::Success;
        break;
      case LinearSolver::cholesky:
        use_ldlt = !cholesky.factorize(stiffness);
        if (use_ldlt) {
          if (!ldlt) {
            ldlt = std::make_unique<Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>>();
            ldlt->analyzePattern(stiffness);
          }
          ldlt->factorize(stiffness);
          ok = ldlt->info() == Eigen::Success;
        }
        break;
    }
    report.factorization_seconds += seconds_since(start);
    return ok;
  }

  // step = K⁻¹ residual with what prepare() set up; any number of times.
  bool solve_prepared(SolveReport& report) {
    const auto start = Clock::now();
    bool converged = true;
    switch (kind) {
      case LinearSolver::multigrid:
        converged = amg->solve(residual, step);
        report.cg_iterations += amg->last_iterations();
        break;
      case LinearSolver::elastic_multigrid:
        converged = gamg->solve(residual, step);
        report.cg_iterations += gamg->last_iterations();
        break;
      case LinearSolver::conjugate_gradient:
        step = cg->solve(residual);
        converged = cg->info() == Eigen::Success;
        report.cg_iterations += cg->iterations();
        break;
      case LinearSolver::cholesky:
        if (use_ldlt) {
          step = ldlt->solve(residual);
        } else {
          cholesky.solve(residual, step);
        }
        break;
    }
    report.solve_seconds += seconds_since(start);
    return converged && step.allFinite();
  }

  bool factorize_and_solve(SolveReport& report) { return prepare(report) && solve_prepared(report); }
};

ElasticSolver::ElasticSolver(const TetMesh& mesh, const std::vector<char>& fixed, LinearSolver linear_solver,
                             bool distributed)
    : mesh_(mesh), impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.kind = linear_solver;
  const size_t dofs = 3 * mesh.nodes.size();
  if (fixed.size() != dofs) throw std::logic_error("ElasticSolver: fixed flags must be 3 per node");
  // Free DOFs numbered node by node along the nodes' Morton curve: the
  // stiffness then has a small bandwidth and its products (the multigrids'
  // work) read memory in runs. The Cholesky solvers order it their own way.
  const std::vector<int> node_order = morton_order(mesh.nodes);
  m.dof_index.assign(dofs, -1);
  for (int v : node_order) {
    for (size_t d = 0; d < 3; ++d) {
      if (!fixed[3 * static_cast<size_t>(v) + d]) m.dof_index[3 * static_cast<size_t>(v) + d] = m.free_count++;
    }
  }
  if (m.free_count == static_cast<int>(dofs)) {
    throw InputError("FEM: no node is fixed or has a prescribed displacement, so the equilibrium "
                     "is singular (rigid motion is free); give a \"fixed\" region");
  }
  m.rest.reserve(mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    m.rest.push_back(tet_rest(mesh.nodes[static_cast<size_t>(tet[0])], mesh.nodes[static_cast<size_t>(tet[1])],
                              mesh.nodes[static_cast<size_t>(tet[2])], mesh.nodes[static_cast<size_t>(tet[3])]));
    if (!(m.rest.back().volume_mm3 > 0)) {
      throw std::logic_error("ElasticSolver: tet " + std::to_string(t) + " is not positively oriented");
    }
  }
  // The pattern straight from the node graph, in compressed form (no
  // triplet list: at 10⁵–10⁶ tets that would be the largest allocation of
  // the whole setup). Each node's neighbours, itself included, sorted:
  const size_t node_count = mesh.nodes.size();
  std::vector<int> adjacency_start(node_count + 1, 0), adjacency(16 * mesh.tets.size());
  for (const Tet& tet : mesh.tets)
    for (int a : tet) adjacency_start[static_cast<size_t>(a) + 1] += 4;
  for (size_t v = 0; v < node_count; ++v) adjacency_start[v + 1] += adjacency_start[v];
  {
    std::vector<int> cursor(adjacency_start.begin(), adjacency_start.end() - 1);
    for (const Tet& tet : mesh.tets)
      for (int a : tet)
        for (int b : tet) adjacency[static_cast<size_t>(cursor[static_cast<size_t>(a)]++)] = b;
    int kept = 0;
    for (size_t v = 0; v < node_count; ++v) {
      const auto begin = adjacency.begin() + adjacency_start[v], end = adjacency.begin() + adjacency_start[v + 1];
      std::sort(begin, end);
      const auto unique_end = std::unique(begin, end);
      adjacency_start[v] = kept;
      kept = static_cast<int>(std::copy(begin, unique_end, adjacency.begin() + kept) - adjacency.begin());
    }
    adjacency_start[node_count] = kept;
    adjacency.resize(static_cast<size_t>(kept));
    adjacency.shrink_to_fit();
  }
  // Column c of the lower triangle: the free DOFs of c's node's neighbours
  // numbered c or above, in order.
  std::vector<int> column_start(static_cast<size_t>(m.free_count) + 1, 0);
  auto for_each_row = [&](size_t v, int column, auto&& visit) {
    for (int k = adjacency_start[v]; k < adjacency_start[v + 1]; ++k) {
      const auto w = static_cast<size_t>(adjacency[static_cast<size_t>(k)]);
      for (size_t e = 0; e < 3; ++e) {
        if (const int row = m.dof_index[3 * w + e]; row >= column) visit(row);
      }
    }
  };
  for (size_t v = 0; v < node_count; ++v) {
    for (size_t d = 0; d < 3; ++d) {
      if (const int column = m.dof_index[3 * v + d]; column >= 0) {
        for_each_row(v, column, [&](int) { ++column_start[static_cast<size_t>(column) + 1]; });
      }
    }
  }
  for (size_t c = 0; c < static_cast<size_t>(m.free_count); ++c) column_start[c + 1] += column_start[c];
  m.stiffness.resize(m.free_count, m.free_count);
  m.stiffness.resizeNonZeros(column_start.back());
  std::copy(column_start.begin(), column_start.end(), m.stiffness.outerIndexPtr());
  int* rows = m.stiffness.innerIndexPtr();
  for (size_t v = 0; v < node_count; ++v) {
    for (size_t d = 0; d < 3; ++d) {
      if (const int column = m.dof_index[3 * v + d]; column >= 0) {
        int* at = rows + column_start[static_cast<size_t>(column)];
        for_each_row(v, column, [&](int row) { *at++ = row; });
        std::sort(rows + column_start[static_cast<size_t>(column)], at);
      }
    }
  }
  std::fill(m.stiffness.valuePtr(), m.stiffness.valuePtr() + m.stiffness.nonZeros(), 0.0);
  adjacency = {};

  const int* outer = m.stiffness.outerIndexPtr();
  const int* inner = m.stiffness.innerIndexPtr();
  auto position = [&](int row, int col) {
    const int* begin = inner + outer[col];
    const int* end = inner + outer[col + 1];
    return static_cast<int>(std::lower_bound(begin, end, row) - inner);
  };
  m.diagonal.resize(static_cast<size_t>(m.free_count));
  for (int i = 0; i < m.free_count; ++i) m.diagonal[static_cast<size_t>(i)] = position(i, i);
  m.scatter.assign(kPairs * mesh.tets.size(), -1);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    int* map = &m.scatter[kPairs * t];
    for (int j = 0; j < 12; ++j) {
      const int gj = m.dof_index[3 * static_cast<size_t>(tet[static_cast<size_t>(j / 3)]) + static_cast<size_t>(j % 3)];
      for (int i = 0; i <= j; ++i, ++map) {
        const int gi = m.dof_index[3 * static_cast<size_t>(tet[static_cast<size_t>(i / 3)]) + static_cast<size_t>(i % 3)];
        if (gi >= 0 && gj >= 0) *map = position(std::max(gi, gj), std::min(gi, gj));
      }
    }
  }
  if (m.kind == LinearSolver::conjugate_gradient) {
    m.cg = std::make_unique<Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower, Impl::Preconditioner>>();
    m.cg->setTolerance(1e-12);
    m.cg->setMaxIterations(std::max(1000, 10 * static_cast<int>(std::sqrt(static_cast<double>(m.free_count)))));
  } else if (m.kind == LinearSolver::multigrid || m.kind == LinearSolver::elastic_multigrid) {
    std::vector<int> dof_of_free(static_cast<size_t>(m.free_count));
    for (size_t d = 0; d < dofs; ++d) {
      if (const int i = m.dof_index[d]; i >= 0) dof_of_free[static_cast<size_t>(i)] = static_cast<int>(d);
    }
    // CG to 1e-10 relative: below Newton's default force tolerance (1e-9).
    if (m.kind == LinearSolver::multigrid)
      m.amg = std::make_unique<AmgSolver>(m.stiffness, std::move(dof_of_free), mesh.nodes.size(), 1e-10, 5000);
    else
      m.gamg = std::make_unique<GamgSolver>(m.stiffness, dof_of_free, mesh.nodes, node_order, 1e-10,
                                            5000, distributed);
  } else {
    m.cholesky.analyze(m.stiffness);
  }
  if (m.kind == LinearSolver::cholesky && std::getenv("SPEC2FAB_FEM_TRACE")) {
    std::fprintf(stderr, "cholmod: n %d, nnz(A) %ld, nnz(L) %.3g, flops %.3g\n", m.free_count,
                 static_cast<long>(m.stiffness.nonZeros()), m.cholesky.factor_nonzeros(), m.cholesky.factor_flops());
  }

  m.lambda.assign(mesh.tets.size(), 0.0);
  m.mu.assign(mesh.tets.size(), 0.0);
  m.active.assign(mesh.tets.size(), 0);
  m.node_active.assign(mesh.nodes.size(), 0);
  m.residual.resize(m.free_count);
  m.step.resize(m.free_count);
  m.forces.resize(dofs);
  m.trial.resize(dofs);
  m.last_converged.resize(dofs);
  m.previous_converged.resize(dofs);
  m.saved_residual.resize(m.free_count);
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
  return impl_->amg ? impl_->amg->operator_complexity() : 0.0;
}

int ElasticSolver::solve_ranks() const { return impl_->gamg ? impl_->gamg->ranks() : 1; }

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

SolveReport ElasticSolver::solve(const Constraints& c, const SolveOptions& options,
                                 std::vector<double>& u) {
  Impl& m = *impl_;
  const size_t dofs = 3 * mesh_.nodes.size();
  if (u.size() != dofs) u.assign(dofs, 0.0);
  SolveReport report;
  double external = 0;
  for (double f : c.force_n) external += f * f;
  external = std::sqrt(external);

  // ‖free residual‖ at the displacement in `at`, loads scaled by `scale`;
  // fills m.residual with −r (the Newton right-hand side) and `energy` with
  // the total potential energy (elastic minus the loads' work, N·mm).
  double energy = 0;
  auto residual_norm = [&](std::span<const double> at, double scale, bool corotated, bool tangent,
                           double& reference) {
    const auto start = Clock::now();
    energy = m.form(mesh_, at, corotated, tangent);
    report.assembly_seconds += seconds_since(start);
    double sum = 0, reactions = 0;
    for (size_t d = 0; d < dofs; ++d) {
      const int i = m.dof_index[d];
      if (i < 0) {
        reactions += m.forces[d] * m.forces[d];
        continue;
      }
      energy -= scale * c.force_n[d] * at[d];
      const double r = m.forces[d] - scale * c.force_n[d];
      m.residual[i] = -r;
      sum += r * r;
    }
    reference = std::max(scale * external, std::sqrt(reactions));
    return std::sqrt(sum);
  };

  if (!options.nonlinear) {
    for (size_t d = 0; d < dofs; ++d) u[d] = m.dof_index[d] < 0 ? c.prescribed_mm[d] : 0.0;
    double reference = 0;
    residual_norm(u, 1.0, false, true, reference);
    if (!m.factorize_and_solve(report)) {
      throw std::runtime_error(m.kind == LinearSolver::cholesky
                                   ? "FEM: the stiffness matrix is singular"
                                   : "FEM: conjugate gradients did not converge (try \"linear_solver\": \"cholesky\")");
    }
    for (size_t d = 0; d < dofs; ++d) {
      if (const int i = m.dof_index[d]; i >= 0) u[d] += m.step[i];
    }
    // The linear system's own residual b − K·Δ (a matrix product, not another
    // pass over the elements).
    m.saved_residual.noalias() = m.stiffness.selfadjointView<Eigen::Lower>() * m.step;
    const double r = (m.residual - m.saved_residual).norm();
    report.relative_residual = reference > 0 ? r / reference : r;
    report.newton_iterations = 1;
    report.load_steps = 1;
    report.converged = true;
    return report;
  }

  const bool trace = std::getenv("SPEC2FAB_FEM_TRACE") != nullptr;  // Newton's progress on stderr
  std::vector<double>& last_converged = m.last_converged;
  last_converged = u;
  double done = 0, previous_scale = -1;
  double increment = 1.0 / std::max(1, options.load_steps);
  int halvings = 0;
  while (done < 1.0 - 1e-12) {
    const double scale = std::min(1.0, done + increment);
    // Predictor: the last step's change, scaled to this one (a secant
    // extrapolation of the load path).
    if (report.load_steps > 0 && previous_scale < done) {
      const double ratio = (scale - done) / (done - previous_scale);
      for (size_t d = 0; d < dofs; ++d) {
        u[d] = m.dof_index[d] < 0 ? scale * c.prescribed_mm[d]
                                  : u[d] + ratio * (u[d] - m.previous_converged[d]);
      }
    } else {
      for (size_t d = 0; d < dofs; ++d) {
        if (m.dof_index[d] < 0) u[d] = scale * c.prescribed_mm[d];
      }
    }
    bool converged = false;
    double reference = 0;
    for (int iteration = 0; iteration < options.max_newton_iterations; ++iteration) {
      const double r = residual_norm(u, scale, true, true, reference);
      report.relative_residual = reference > 0 ? r / reference : r;
      if (trace) std::fprintf(stderr, "fem: load %.3f, iteration %d, relative residual %.3e\n", scale, iteration, report.relative_residual);
      if (r <= options.tolerance * std::max(reference, 1e-300)) {
        converged = true;
        break;
      }
      ++report.newton_iterations;
      if (!m.factorize_and_solve(report)) break;
      // Forces are differences of nearly equal stresses (F − R) at small
      // strains, so the residual has a round-off floor; a Newton correction
      // below 1e-10 of the displacement is converged whatever it says.
      double largest_u = 0, largest_step = 0;
      for (size_t d = 0; d < dofs; ++d) largest_u = std::max(largest_u, std::abs(u[d]));
      for (int i = 0; i < m.free_count; ++i) largest_step = std::max(largest_step, std::abs(m.step[i]));
      if (iteration > 0 && largest_step <= 1e-10 * largest_u) {
        for (size_t d = 0; d < dofs; ++d) {
          if (const int i = m.dof_index[d]; i >= 0) u[d] += m.step[i];
        }
        converged = true;
        break;
      }
      // Backtracking on the potential energy (the model is hyperelastic, so
      // equilibrium minimises it): a full Newton step on a slender body can
      // overshoot far past the minimum along the step.
      const double start_energy = energy;
      const double slope = -m.residual.dot(m.step);  // dE/dα at α = 0 (< 0 for a descent step)
      double alpha = 1.0;
      for (int tries = 0; tries < 8; ++tries) {
        for (size_t d = 0; d < dofs; ++d) {
          const int i = m.dof_index[d];
          m.trial[d] = i < 0 ? u[d] : u[d] + alpha * m.step[i];
        }
        double unused = 0;
        m.saved_residual = m.residual;
        residual_norm(m.trial, scale, true, false, unused);
        m.residual = m.saved_residual;
        // (Round-off in the energy sum is allowed for near convergence.)
        const double noise = 1e-11 * std::abs(start_energy);
        if (slope >= 0 || (std::isfinite(energy) && energy <= start_energy + 1e-4 * alpha * slope + noise)) break;
        alpha *= 0.5;
      }
      std::copy(m.trial.begin(), m.trial.end(), u.begin());
    }
    if (converged) {
      m.previous_converged.swap(last_converged);
      previous_scale = done;
      done = scale;
      ++report.load_steps;
      last_converged = u;
      continue;
    }
    if (++halvings > 6) {
      report.converged = false;
      return report;
    }
    u = last_converged;
    increment *= 0.5;
  }
  report.converged = true;
  return report;
}

}  // namespace spec2fab::fem

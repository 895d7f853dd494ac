#pragma once
// ElasticSolver's state, shared by its setup (elastic_solver.cpp) and its
// solves (elastic_equilibrium.cpp). Private: not installed.

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
#include "fem/block_amg.h"
#include "fem/cholmod_factor.h"
#include "fem/hypre/amg_solver.h"
#include "fem/petsc/gamg_solver.h"
#include "fem/stiffness_pattern.h"

namespace spec2fab::fem {

namespace elastic_detail {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace elastic_detail
using namespace elastic_detail;  // a private header, included by the solver's two sources only

struct ElasticSolver::Impl {
  struct Equilibrium;  // one solve (elastic_equilibrium.cpp)
  std::vector<TetRest> rest;
  std::vector<int> dof_index;   // full DOF -> free index, or -1
  int free_count = 0;
  // Where each tet's element matrix lands in the matrix's value array
  // (StiffnessPattern::scatter: 18 positions per tet).
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
  std::unique_ptr<BlockAmgSolver> block_amg;

  std::vector<double> lambda, mu;
  std::vector<char> active;
  std::vector<char> node_active;
  // A solve spread over the ranks (gamg under mpirun) assembles only the
  // rows this rank owns, from the tets touching one; one process, every row.
  // Forces and energy are still summed over every tet on every rank (one
  // pass over the elements, replicated, and the same numbers as one process).
  AssemblyShare share;

  bool assembles(size_t t) const { return share.assembles(t); }
  bool owns_dof(size_t dof) const { return share.owns_dof(dof); }

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
      const bool assemble = tangent && assembles(t);
      energy += tet_forces(rest[t], lambda[t], mu[t], x, corotated, f, assemble && !linear_tangent ? &k : nullptr);
      for (int a = 0; a < 4; ++a) {
        const auto v = static_cast<size_t>(tet[static_cast<size_t>(a)]);
        for (int d = 0; d < 3; ++d) forces[3 * v + static_cast<size_t>(d)] += f[3 * a + d];
      }
      if (!assemble) continue;
      if (linear_tangent) linear_tet_stiffness(rest[t], lambda[t], mu[t], k);
      add_element(mesh, t, k, values);
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
      if (!active[t] || !assembles(t)) continue;
      linear_tet_stiffness(rest[t], lambda[t], mu[t], k);
      add_element(mesh, t, k, values);
    }
    hold_untouched_nodes(values);
  }

  void add_element(const TetMesh& mesh, size_t t, const Mat12& k, double* values) const {
    add_element_matrix(scatter, diagonal, dof_index, mesh.tets[t], t, k, values);
  }

  // Nodes no active tet touches: keep them where they are.
  void hold_untouched_nodes(double* values) const {
    for (size_t v = 0; v < node_active.size(); ++v) {
      if (node_active[v]) continue;
      for (size_t d = 0; d < 3; ++d) {
        const int i = dof_index[3 * v + d];
        if (i >= 0 && diagonal[static_cast<size_t>(i)] >= 0) values[diagonal[static_cast<size_t>(i)]] = 1.0;
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
      case LinearSolver::block_multigrid: ok = block_amg->setup(stiffness); break;
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
      case LinearSolver::block_multigrid:
        converged = block_amg->solve(residual, step);
        report.cg_iterations += block_amg->last_iterations();
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

  /// Free DOFs numbered node by node along the nodes' Morton curve: the
  /// stiffness then has a small bandwidth and its products (the multigrids'
  /// work) read memory in runs. The Cholesky solvers order it their own way.
  /// Returns that node order.
  std::vector<int> number_free_dofs(const TetMesh& mesh, const std::vector<char>& fixed) {
    const size_t dofs = 3 * mesh.nodes.size();
    if (fixed.size() != dofs) throw std::logic_error("ElasticSolver: fixed flags must be 3 per node");
    std::vector<int> node_order = morton_order(mesh.nodes);
    dof_index.assign(dofs, -1);
    for (int v : node_order) {
      for (size_t d = 0; d < 3; ++d) {
        if (!fixed[3 * static_cast<size_t>(v) + d]) dof_index[3 * static_cast<size_t>(v) + d] = free_count++;
      }
    }
    if (free_count == static_cast<int>(dofs)) {
      throw InputError("FEM: no node is fixed or has a prescribed displacement, so the equilibrium "
                       "is singular (rigid motion is free); give a \"fixed\" region");
    }
    return node_order;
  }

  /// Under mpirun with gamg: which nodes' rows this rank owns (the run of
  /// the node order GamgSolver gives it), and the tets that touch them.
  void split_rows(const TetMesh& mesh, const std::vector<int>& node_order, bool distributed) {
    if (kind != LinearSolver::elastic_multigrid || !distributed) return;
    const GamgSolver::Partition part = GamgSolver::partition(node_order.size(), true);
    if (part.size < 2) return;
    std::vector<char> owned(mesh.nodes.size(), 0);
    for (size_t place = part.first_place; place < part.end_place; ++place)
      owned[static_cast<size_t>(node_order[place])] = 1;
    share = AssemblyShare(mesh, std::move(owned));
  }

  /// Each tet's rest shape (its inverse edge matrix and volume).
  void shape_rest(const TetMesh& mesh) {
    rest.reserve(mesh.tets.size());
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const Tet& tet = mesh.tets[t];
      rest.push_back(tet_rest(mesh.nodes[static_cast<size_t>(tet[0])], mesh.nodes[static_cast<size_t>(tet[1])],
                              mesh.nodes[static_cast<size_t>(tet[2])], mesh.nodes[static_cast<size_t>(tet[3])]));
      if (!(rest.back().volume_mm3 > 0)) {
        throw std::logic_error("ElasticSolver: tet " + std::to_string(t) + " is not positively oriented");
      }
    }
  }

  /// The linear solver `kind` names, set up on the pattern (the Cholesky
  /// factor analysed; a multigrid told each free DOF's node).
  void make_linear_solver(const TetMesh& mesh, const std::vector<int>& node_order, bool distributed) {
    if (kind == LinearSolver::conjugate_gradient) {
      cg = std::make_unique<Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower, Preconditioner>>();
      cg->setTolerance(1e-12);
      cg->setMaxIterations(std::max(1000, 10 * static_cast<int>(std::sqrt(static_cast<double>(free_count)))));
    } else if (kind == LinearSolver::multigrid || kind == LinearSolver::elastic_multigrid ||
               kind == LinearSolver::block_multigrid) {
      std::vector<int> dof_of_free(static_cast<size_t>(free_count));
      for (size_t d = 0; d < dof_index.size(); ++d) {
        if (const int i = dof_index[d]; i >= 0) dof_of_free[static_cast<size_t>(i)] = static_cast<int>(d);
      }
      // CG to 1e-10 relative: below Newton's default force tolerance (1e-9).
      if (kind == LinearSolver::multigrid)
        amg = std::make_unique<AmgSolver>(stiffness, std::move(dof_of_free), mesh.nodes.size(), 1e-10, 5000);
      else if (kind == LinearSolver::block_multigrid)
        block_amg = std::make_unique<BlockAmgSolver>(stiffness, dof_of_free, mesh.nodes, 1e-10, 5000);
      else
        gamg = std::make_unique<GamgSolver>(stiffness, dof_of_free, mesh.nodes, node_order, 1e-10, 5000, distributed);
    } else {
      cholesky.analyze(stiffness);
    }
    if (kind == LinearSolver::cholesky && std::getenv("SPEC2FAB_FEM_TRACE")) {
      std::fprintf(stderr, "cholmod: n %d, nnz(A) %ld, nnz(L) %.3g, flops %.3g\n", free_count,
                   static_cast<long>(stiffness.nonZeros()), cholesky.factor_nonzeros(), cholesky.factor_flops());
    }
  }

  void size_buffers(const TetMesh& mesh) {
    const size_t dofs = 3 * mesh.nodes.size();
    lambda.assign(mesh.tets.size(), 0.0);
    mu.assign(mesh.tets.size(), 0.0);
    active.assign(mesh.tets.size(), 0);
    node_active.assign(mesh.nodes.size(), 0);
    residual.resize(free_count);
    step.resize(free_count);
    forces.resize(dofs);
    trial.resize(dofs);
    last_converged.resize(dofs);
    previous_converged.resize(dofs);
    saved_residual.resize(free_count);
  }

  bool factorize_and_solve(SolveReport& report) { return prepare(report) && solve_prepared(report); }
};

}  // namespace spec2fab::fem

#pragma once
/// Conjugate gradients preconditioned by smoothed-aggregation multigrid
/// (Vaněk, Mandel & Brezina 1996) kept in node blocks: the stiffness as
/// 3 × 3 blocks of node pairs, the coarse levels as 6 × 6 blocks of
/// aggregates carrying the six rigid-body modes. It is the algorithm of
/// PETSc's GAMG (the `gamg` solver), written for this one operator: PETSc
/// keeps every level as scalar entries with a column index each, and its
/// Galerkin products work entry by entry, which on the 321k-tet cantilever
/// took 3 s of setup and 58 ms per CG iteration (benchmarks/RESULTS.md).
/// In blocks a product reads one column index per 9 or 36 values, and the
/// Galerkin product multiplies small dense blocks.
///
/// Per level: aggregates grown on the strong node graph (‖A_ij‖ ≥
/// θ √(‖A_ii‖ ‖A_jj‖); on the finest level two strong steps from a root, as
/// GAMG aggregates on A²'s graph), a tentative prolongator from each
/// aggregate's near-nullspace by Gram–Schmidt (the rigid-body modes on the
/// finest level, the factor R on the next), smoothed by one damped Jacobi
/// step (ω = 4 / (3 λ), λ the largest eigenvalue of D⁻¹A by Lanczos), the
/// coarse operator PᵀAP. Chebyshev smoothing of degree 2 on D⁻¹A over
/// [0.1 λ, 1.1 λ] before and after the coarse correction (the multigrid is
/// symmetric, so CG may use it), and a CHOLMOD factor on the coarsest level
/// (up to 20,000 rows: on the 321k-tet cantilever two levels, 181,371 and
/// 5,298 rows). Everything runs on one thread in a fixed order: the same
/// input gives the same bits.
///
/// On one core, side by side with CalculiX on the 321k-tet cantilever: 38
/// CG iterations, 11.8–12.2× ccx's time at 0.40× its memory, where GAMG
/// took 43 iterations at 3.8–4.1× (benchmarks/RESULTS.md). Not distributed: under
/// mpirun the `gamg` solver spreads its solves over the ranks.
///
/// Like the other multigrids, the system has every node's three rows (a
/// node with a free DOF; its prescribed DOFs are identity rows), so that the
/// rigid-body modes apply node by node.

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/SparseCore>

#include "geometry/mesh.h"

namespace spec2fab::fem {

class BlockAmgSolver {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  /// `lower`: the lower triangle (compressed) of the free-free stiffness,
  /// whose pattern every later matrix shares; `dof_of_free`: the node DOF
  /// (3·node + axis) of each free row, a node's free rows consecutive;
  /// `nodes`: rest positions (the rigid-body modes).
  BlockAmgSolver(const Matrix& lower, const std::vector<int>& dof_of_free,
                 std::span<const Vec3> nodes, double tolerance, int max_iterations);
  ~BlockAmgSolver();
  BlockAmgSolver(const BlockAmgSolver&) = delete;
  BlockAmgSolver& operator=(const BlockAmgSolver&) = delete;

  /// Takes the values of `lower` into node blocks and builds the hierarchy
  /// (the analogue of a numeric factorisation). False when the matrix is
  /// not positive definite (a diagonal entry ≤ 0, or the coarsest level's
  /// factor fails): a solve then fails too.
  bool setup(const Matrix& lower);
  /// x = A⁻¹ b to relative residual ‖b − Ax‖ / ‖b‖ ≤ `tolerance`, from
  /// x = 0; false when CG did not get there in `max_iterations` (or broke
  /// down: the preconditioner or the matrix not positive definite).
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  int last_iterations() const;
  double last_relative_residual() const;
  /// Σ scalar nonzeros over all levels / those of the finest.
  double operator_complexity() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab::fem

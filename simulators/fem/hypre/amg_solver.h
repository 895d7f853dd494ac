#pragma once
/// Conjugate gradients preconditioned by algebraic multigrid (BoomerAMG of
/// LLNL's hypre, Debian's libhypre-dev) for the FEM's symmetric positive
/// definite stiffness: memory close to the matrix itself and an iteration
/// count that barely grows with the mesh, where a Cholesky factor of a 3-D
/// mesh grows as n^(4/3) and incomplete Cholesky needs thousands of CG
/// iterations on a slender part.
///
/// The multigrid treats the system as 3 unknowns per node (x, y, z, each
/// coarsened on its own couplings: systems AMG's "unknown" approach), so the
/// preconditioned system has every node's three rows: free rows from the
/// stiffness, prescribed rows the identity (right-hand side 0).
///
/// hypre lives in its own target (spec2fab_hypre, CMake option
/// SPEC2FAB_WITH_HYPRE, on by default) and needs MPI: the first AmgSolver
/// initialises MPI as a singleton (no mpirun needed) and it is finalised at
/// exit. hypre keeps global state, so calls from several threads are
/// serialised.

#include <Eigen/SparseCore>

#include <cstddef>
#include <memory>
#include <vector>

namespace spec2fab::fem {

class AmgSolver {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  /// `lower`: the lower triangle (compressed) of the free-free stiffness,
  /// whose pattern every later matrix shares; `dof_of_free`: the node DOF
  /// (3·node + axis) of each free row. Throws std::runtime_error when this
  /// build has no hypre.
  AmgSolver(const Matrix& lower, std::vector<int> dof_of_free, size_t node_count, double tolerance,
            int max_iterations);
  ~AmgSolver();
  AmgSolver(const AmgSolver&) = delete;
  AmgSolver& operator=(const AmgSolver&) = delete;

  /// Copies the values of `lower` into hypre's matrix and builds the
  /// multigrid hierarchy (the analogue of a numeric factorisation).
  void setup(const Matrix& lower);
  /// x = A⁻¹ b to relative residual `tolerance`; false when CG did not get
  /// there in `max_iterations`.
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  int last_iterations() const;
  double last_relative_residual() const;
  /// Σ nnz over all levels / nnz of the matrix (BoomerAMG's operator complexity).
  double operator_complexity() const;

  static bool available();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab::fem

#pragma once
/// Conjugate gradients preconditioned by smoothed-aggregation algebraic
/// multigrid built for elasticity: PETSc's GAMG (Debian's petsc-dev) with the
/// six rigid-body modes of the nodes as its near-nullspace. Aggregation that
/// knows the rigid motions keeps the iteration count at a few dozen where a
/// scalar AMG needs 150-200 (docs/fem-solver-study.md: 39-42 against 142-203
/// on the 321k-tet cantilever).
///
/// Like AmgSolver (fem/hypre), the system has every node's three rows (free
/// rows from the stiffness, prescribed rows the identity with right-hand
/// side 0), so the matrix has a block size of 3 and the modes apply node by
/// node. The caller numbers the free DOFs node by node in `node_order` (a
/// Morton curve, tet_mesh.h), and the solver's rows follow the same order,
/// so that the full matrix's rows are the lower triangle's columns merged
/// with their transposes, sorted, without a permutation to store.
///
/// Distributed: with `distributed` under mpirun (`spec2fab simulate`, or a
/// run's FEM tuner told "spread_over_ranks") each rank takes the rows of a
/// contiguous run of the Morton order (a space-filling-curve partition of
/// the mesh, `partition()`) and passes a lower triangle whose entries in
/// those rows and columns are complete (ElasticSolver assembles only
/// them); PETSc's MPI matrices and GAMG solve across the ranks, and every
/// rank gets the whole solution back. Each call is then collective. PETSc's
/// world is fixed by the process's first solver: when that one is not
/// distributed (a run's tuners without "spread_over_ranks"), PETSc lives on
/// this process alone, and a later distributed solver solves alone too
/// (ranks() says 1; the fem simulator warns) rather than wait for ranks
/// that never come.
///
/// PETSc lives in its own target (spec2fab_petsc, CMake option
/// SPEC2FAB_WITH_PETSC, on by default). The first solver initialises PETSc
/// (and MPI as a singleton where nobody started it); it is finalised at
/// exit. PETSc is not thread-safe, so calls from several threads are
/// serialised. Options of the solver can be changed at run time through
/// PETSc's options database with the prefix `spec2fab_fem_`, e.g.
/// PETSC_OPTIONS="-spec2fab_fem_ksp_view" to print what it built.

#include <Eigen/SparseCore>

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "geometry/mesh.h"

namespace spec2fab::fem {

class GamgSolver {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  /// `lower`: the lower triangle (compressed) of the free-free stiffness,
  /// whose pattern every later matrix shares; `dof_of_free`: the node DOF
  /// (3·node + axis) of each free row, increasing along `node_order`;
  /// `nodes`: rest positions (the rigid modes). `distributed`: solve across
  /// the MPI ranks of this run (every rank calls alike, `lower` complete in
  /// the rows and columns of the nodes partition() gives it).
  /// Throws std::runtime_error when this build has no PETSc.
  GamgSolver(const Matrix& lower, const std::vector<int>& dof_of_free, std::span<const Vec3> nodes,
             std::span<const int> node_order, double tolerance, int max_iterations, bool distributed = false);
  ~GamgSolver();
  GamgSolver(const GamgSolver&) = delete;
  GamgSolver& operator=(const GamgSolver&) = delete;

  /// Copies the values of `lower` into PETSc's matrix and builds the
  /// multigrid hierarchy (the analogue of a numeric factorisation).
  void setup(const Matrix& lower);
  /// x = A⁻¹ b to relative residual ‖b − Ax‖ / ‖b‖ ≤ `tolerance`; false
  /// when CG did not get there in `max_iterations` (or broke down).
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  int last_iterations() const;
  double last_relative_residual() const;
  /// Σ nnz over all levels / nnz of the matrix (GAMG's operator complexity).
  double operator_complexity() const;
  /// Ranks the solve is spread over (1 unless distributed under mpirun).
  int ranks() const;

  /// This process's rank and the number of ranks a solver made with
  /// `distributed` will spread its solve over (starting PETSc if it was
  /// not), and the run of places in `node_order` whose rows it owns: what a
  /// caller needs to assemble only the rows this rank owns.
  struct Partition {
    int rank = 0, size = 1;
    size_t first_place = 0, end_place = 0;
  };
  static Partition partition(size_t node_count, bool distributed);

  static bool available();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab::fem

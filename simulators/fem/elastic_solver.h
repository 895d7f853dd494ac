#pragma once
/// Static equilibrium of a tet mesh of co-rotated linear elements
/// (corotated_tet.h) under prescribed displacements and dead loads:
/// Newton's method with load stepping for large deformation, or one linear
/// solve for small deformation.
///
/// Setup (constructor) does the geometry and pattern work once: rest-shape
/// data per tet, the free DOFs' sparsity pattern, the place of every element
/// entry in it, and CHOLMOD's symbolic analysis (supernodal Cholesky; an
/// LDLᵀ fallback for the rare indefinite tangent). A solve then re-forms
/// values in place and refactorises numerically — what an optimizer pays per
/// evaluation — and allocates nothing of its own.
///
/// Units: mm, N, MPa.

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "fem/corotated_tet.h"
#include "fem/tet_mesh.h"

namespace spec2fab::fem {

/// Boundary conditions, 3 entries per node.
struct Constraints {
  std::vector<char> fixed;            ///< 1: the DOF is prescribed
  std::vector<double> prescribed_mm;  ///< its value where fixed (0: clamped)
  std::vector<double> force_n;        ///< external dead load on the node
};

/// How each linear system is solved.
enum class LinearSolver {
  cholesky,            ///< CHOLMOD supernodal (LDLᵀ fallback): exact, fast to repeat, memory of the factor
  conjugate_gradient,  ///< CG with an incomplete-Cholesky preconditioner: a fraction of the memory
  multigrid,           ///< CG with an algebraic multigrid preconditioner (hypre BoomerAMG): small memory, fast on big meshes
  elastic_multigrid,   ///< CG with smoothed aggregation on the rigid-body modes (PETSc GAMG): fewest iterations; distributed under mpirun
  block_multigrid,     ///< the same smoothed aggregation in node blocks (fem/block_amg.h): fastest on one core
};

struct SolveOptions {
  bool nonlinear = true;           ///< co-rotated large deformation; false: small-strain linear
  int load_steps = 10;             ///< equal increments of load and prescribed displacement
  int max_newton_iterations = 30;  ///< per load step (a step that fails is halved, up to 6 times)
  double tolerance = 1e-9;         ///< on ‖residual‖ / ‖reference force‖
};

struct SolveReport {
  int newton_iterations = 0;  ///< in all load steps
  int load_steps = 0;         ///< taken, after any halving
  int factorizations = 0;
  bool converged = false;
  double relative_residual = 0;
  double assembly_seconds = 0;       ///< element forces and tangents, scattered
  double factorization_seconds = 0;  ///< numeric Cholesky (or LDLᵀ)
  double solve_seconds = 0;          ///< triangular solves (or CG iterations)
  long cg_iterations = 0;            ///< the iterative solvers: in all solves
};

class ElasticSolver {
 public:
  /// `fixed` holds 3 flags per node (1: prescribed). Throws InputError when
  /// nothing is fixed (the system would be singular).
  /// `distributed` (elastic_multigrid only): every MPI rank of the run
  /// constructs the same solver and makes the same calls, and the linear
  /// solves are spread over the ranks.
  ElasticSolver(const TetMesh& mesh, const std::vector<char>& fixed,
                LinearSolver linear_solver = LinearSolver::cholesky, bool distributed = false);
  ~ElasticSolver();
  ElasticSolver(const ElasticSolver&) = delete;
  ElasticSolver& operator=(const ElasticSolver&) = delete;

  /// Lamé parameters (MPa) per tet; inactive tets (void) carry nothing, and a
  /// node that only they touch stays where it is.
  void set_materials(std::span<const double> lambda, std::span<const double> mu,
                     std::span<const char> active);

  /// Solves for `displacement_mm` (3 per node; its free entries are the
  /// Newton start, e.g. the last solution). `constraints.fixed` must be the
  /// flags given at construction.
  SolveReport solve(const Constraints& constraints, const SolveOptions& options,
                    std::vector<double>& displacement_mm);

  /// What the elastic bound needs of K⁻¹ for vectors v₀ … v_m (3 per
  /// node; entries on fixed DOFs are ignored): vᵢᵀK⁻¹v₀ and vᵢᵀK⁻¹vᵢ.
  struct InverseProducts {
    Eigen::VectorXd with_first;  ///< vᵢᵀ K⁻¹ v₀
    Eigen::VectorXd diagonal;    ///< vᵢᵀ K⁻¹ vᵢ
  };
  /// Small strain only: assembles the stiffness K of the free DOFs at rest,
  /// factorises it once, and returns those products for the columns of
  /// `free_vectors` (free_rows' block). With the Cholesky factor
  /// K = PᵀLLᵀP they are dot products of Y = L⁻¹PV, so the vectors go
  /// through the forward half of a solve only, as one block; the iterative
  /// solvers solve each vector. Nothing of size n leaves the solver.
  /// Prescribed displacements play no part. Empty when K is not positive
  /// definite (or an iterative solve fails).
  std::optional<InverseProducts> inverse_products(const Eigen::MatrixXd& free_vectors);
  /// The free DOFs' entries of full vectors (3 per node), one column each:
  /// what inverse_products takes (made once by a caller that repeats).
  Eigen::MatrixXd free_rows(std::span<const std::vector<double>> vectors) const;

  size_t free_dofs() const;
  double factor_nonzeros() const;  ///< nnz of the Cholesky factor (CHOLMOD's analysis)
  double factor_flops() const;     ///< flops of one numeric factorisation
  double multigrid_complexity() const;  ///< multigrids: Σ nnz over their levels / nnz(K) (after a solve)
  int solve_ranks() const;              ///< MPI ranks a linear solve is spread over (1 unless distributed)
  /// Tets whose stiffness this process assembles: all of them, but those
  /// touching its own rows where the solve is spread over the ranks.
  size_t assembled_tets() const;
  long long stiffness_entries() const;  ///< entries of this process's lower triangle

 private:
  struct Impl;
  const TetMesh& mesh_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab::fem

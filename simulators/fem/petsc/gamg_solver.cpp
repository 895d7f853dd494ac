#include "fem/petsc/gamg_solver.h"

#include <stdexcept>
#include <string>

#include "core/build_options.h"
#include "core/ranks.h"
#include "core/third_party_leaks.h"

#if SPEC2FAB_WITH_PETSC

#include <algorithm>
#include <mutex>
#include <numeric>

#include <petscksp.h>

namespace spec2fab::fem {
namespace {

std::mutex& petsc_mutex() {
  static std::mutex mutex;
  return mutex;
}

void check(PetscErrorCode code, const char* what) {
  if (code == 0) return;
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  throw std::runtime_error(std::string("PETSc: ") + what + " failed" + (text ? std::string(": ") + text : ""));
}

// The solver's defaults in PETSc's options database, under its prefix, each
// only where the user (PETSC_OPTIONS) has not set it.
void set_default(const char* name, const char* value) {
  PetscBool set = PETSC_FALSE;
  check(PetscOptionsHasName(nullptr, nullptr, name, &set), "options");
  if (!set) check(PetscOptionsSetValue(nullptr, name, value), "options");
}

// PETSc for the process's lifetime, on the process's MPI
// (ranks::ensure_mpi: a single rank without mpirun), which it leaves to
// its owner to finalise.
// PetscInitialize and PetscFinalize are collective on PETSC_COMM_WORLD: it
// is MPI_COMM_WORLD only when the first solver solves across the ranks
// (simulate under mpirun, where every rank makes the same solvers), and
// this process alone otherwise (a run under mpirun gives each rank its own
// tuners, so only some ranks may ever start PETSc).
struct PetscSession {
  explicit PetscSession(bool across_ranks) {
    ranks::ensure_mpi();
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    PETSC_COMM_WORLD = across_ranks ? MPI_COMM_WORLD : MPI_COMM_SELF;
    // Spec2Fab handles signals itself (Ctrl-C stops a run cleanly; the
    // sanitizers report faults); PETSc's handlers would take them over.
    PetscOptionsSetValue(nullptr, "-no_signal_handler", nullptr);
    PetscOptionsSetValue(nullptr, "-options_left", "no");
    check(PetscInitializeNoArguments(), "initialise");
    // Errors come back as codes, which check() turns into exceptions with
    // PETSc's message, instead of PETSc printing its traceback.
    PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
    // Smoothed aggregation for elasticity (docs/fem-solver-study.md):
    // the eigenvalue estimate that smooths the prolongator by CG, as the
    // operator is SPD (with the default GMRES estimate GAMG diverged on a
    // 1e3-contrast checkerboard: the preconditioner became indefinite).
    set_default("-spec2fab_fem_pc_gamg_esteig_ksp_type", "cg");
    set_default("-spec2fab_fem_pc_gamg_esteig_ksp_max_it", "20");
    // The Chebyshev smoothers estimate their own largest eigenvalue instead
    // of reusing that estimate: on a beam half Vero, half DM9860 (E 2500 :
    // 3.6 MPa, nu 0.49) the reused one was too low, the smoother amplified
    // and CG stopped with DIVERGED_INDEFINITE_PC after 3 iterations (113
    // iterations to 1e-10 with the smoothers' own estimate).
    set_default("-spec2fab_fem_pc_gamg_use_sa_esteig", "0");
    // (The Galerkin products stay PETSc's default, "scalable": "-matptap_via
    // rap" set up 0.2-0.9 s faster on the 321k-tet cantilever but raised the
    // process's peak from 612 to 813 MB, benchmarks/RESULTS.md.)
  }
  ~PetscSession() {
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    int finalized = 0;
    MPI_Finalized(&finalized);  // mpirun's MPI may be finalised first (ranks::stop)
    if (!finalized) PetscFinalize();
  }
};

void start_petsc(bool across_ranks) {
  static PetscSession session(across_ranks);
}

}  // namespace

struct GamgSolver::Impl {
  MPI_Comm comm = MPI_COMM_SELF;
  int rank = 0, size = 1;
  PetscInt rows = 0;                    // every node's three rows
  PetscInt first_row = 0, end_row = 0;  // this rank's
  std::vector<PetscInt> row_of_free;  // free DOF -> row (increasing)
  // This rank's rows of the full matrix in CSR form. Seq: PETSc's matrix
  // uses these very arrays (no copy). MPI: PETSc copies them, and each
  // setup carries its numbers over in a `values` of its own, freed before
  // the multigrid is built (the prescribed rows' identity at
  // `identity_slots`).
  std::vector<PetscInt> row_start, columns, cursor, identity_slots;
  std::vector<PetscScalar> values;
  Mat matrix = nullptr;
  Vec rhs = nullptr, solution = nullptr, gathered = nullptr;
  VecScatter to_all = nullptr;
  KSP ksp = nullptr;
  int iterations = 0;
  double relative_residual = 0;
  PetscReal complexity = 0;  // of the last setup
  bool set_up = false;

  bool owned(PetscInt row) const { return row >= first_row && row < end_row; }
  // The constructor's steps.
  void number_rows(const std::vector<int>& dof_of_free, std::span<const int> node_order);
  void local_pattern(const Matrix& lower);
  void create_matrix();
  void set_rigid_body_modes(std::span<const Vec3> nodes, std::span<const int> node_order);
  void create_krylov(double tolerance, int max_iterations);

  // Visits the lower triangle's entries in column order as the full
  // matrix's (slot, column, index in `lower`) on this rank's rows: column
  // c's diagonal and the entries below it fill row c in order, and each
  // entry below the diagonal, mirrored, is the next of its row, whose
  // earlier columns came first. Rows increase with the free DOFs, so every
  // row comes out sorted, as PETSc keeps it.
  template <class Visit>
  void for_each_entry(const Matrix& lower, Visit&& visit) {
    const auto local_rows = static_cast<size_t>(end_row - first_row);
    cursor.assign(row_start.begin(), row_start.begin() + static_cast<long>(local_rows));
    const int* outer = lower.outerIndexPtr();
    const int* inner = lower.innerIndexPtr();
    for (int c = 0; c < static_cast<int>(lower.cols()); ++c) {
      const PetscInt column = row_of_free[static_cast<size_t>(c)];
      const bool column_owned = owned(column);
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const PetscInt row = row_of_free[static_cast<size_t>(inner[k])];
        if (column_owned) visit(cursor[static_cast<size_t>(column - first_row)]++, row, k);
        if (inner[k] != c && owned(row)) visit(cursor[static_cast<size_t>(row - first_row)]++, column, k);
      }
    }
  }

  ~Impl() {
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    if (ksp) KSPDestroy(&ksp);
    if (to_all) VecScatterDestroy(&to_all);
    if (gathered) VecDestroy(&gathered);
    if (rhs) VecDestroy(&rhs);
    if (solution) VecDestroy(&solution);
    if (matrix) MatDestroy(&matrix);
  }
};

bool GamgSolver::available() { return true; }

GamgSolver::GamgSolver(const Matrix& lower, const std::vector<int>& dof_of_free, std::span<const Vec3> nodes,
                       std::span<const int> node_order, double tolerance, int max_iterations, bool distributed)
    : impl_(std::make_unique<Impl>()) {
  if (!lower.isCompressed()) throw std::logic_error("GamgSolver: the matrix must be compressed");
  if (dof_of_free.size() != static_cast<size_t>(lower.cols())) throw std::logic_error("GamgSolver: one DOF per free row");
  if (node_order.size() != nodes.size()) throw std::logic_error("GamgSolver: one place per node");
  std::lock_guard lock(petsc_mutex());
  start_petsc(distributed);
  Impl& m = *impl_;
  if (distributed) m.comm = PETSC_COMM_WORLD;  // this process alone if PETSc was started so
  MPI_Comm_rank(m.comm, &m.rank);
  MPI_Comm_size(m.comm, &m.size);
  m.number_rows(dof_of_free, node_order);
  m.local_pattern(lower);
  [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
  m.create_matrix();
  m.set_rigid_body_modes(nodes, node_order);
  m.create_krylov(tolerance, max_iterations);
}

/// PETSc's rows: each node's three, in node_order (a space-filling curve);
/// this rank's, a contiguous run of the curve (a space-filling-curve
/// partition).
void GamgSolver::Impl::number_rows(const std::vector<int>& dof_of_free, std::span<const int> node_order) {
  const size_t node_count = node_order.size();
  rows = static_cast<PetscInt>(3 * node_count);
  std::vector<PetscInt> row_of_dof(3 * node_count);
  for (size_t place = 0; place < node_count; ++place)
    for (size_t axis = 0; axis < 3; ++axis)
      row_of_dof[3 * static_cast<size_t>(node_order[place]) + axis] = static_cast<PetscInt>(3 * place + axis);
  row_of_free.resize(dof_of_free.size());
  for (size_t i = 0; i < dof_of_free.size(); ++i) {
    row_of_free[i] = row_of_dof[static_cast<size_t>(dof_of_free[i])];
    if (i > 0 && row_of_free[i] <= row_of_free[i - 1])
      throw std::logic_error("GamgSolver: the free DOFs must be numbered along node_order");
  }
  const auto [first_node, end_node] = ranks::share(static_cast<long long>(node_count), rank, size);
  first_row = static_cast<PetscInt>(3 * first_node);
  end_row = static_cast<PetscInt>(3 * end_node);
}

GamgSolver::Partition GamgSolver::partition(size_t node_count, bool distributed) {
  std::lock_guard lock(petsc_mutex());
  start_petsc(distributed);
  Partition part;
  if (distributed) {
    MPI_Comm_rank(PETSC_COMM_WORLD, &part.rank);
    MPI_Comm_size(PETSC_COMM_WORLD, &part.size);
  }
  const auto [first, end] = ranks::share(static_cast<long long>(node_count), part.rank, part.size);
  part.first_place = static_cast<size_t>(first);
  part.end_place = static_cast<size_t>(end);
  return part;
}

void GamgSolver::Impl::local_pattern(const Matrix& lower) {
  const auto local_rows = static_cast<size_t>(end_row - first_row);
  // This rank's rows: a prescribed row is its diagonal (the identity);
  // a free row has its lower column's entries and their mirrors.
  std::vector<char> prescribed(local_rows, 1);
  for (PetscInt row : row_of_free)
    if (owned(row)) prescribed[static_cast<size_t>(row - first_row)] = 0;
  row_start.assign(local_rows + 1, 0);
  for (size_t r = 0; r < local_rows; ++r) row_start[r + 1] = prescribed[r];
  {
    const int* outer = lower.outerIndexPtr();
    const int* inner = lower.innerIndexPtr();
    for (int c = 0; c < static_cast<int>(lower.cols()); ++c) {
      const PetscInt column = row_of_free[static_cast<size_t>(c)];
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const PetscInt row = row_of_free[static_cast<size_t>(inner[k])];
        if (owned(column)) ++row_start[static_cast<size_t>(column - first_row) + 1];
        if (inner[k] != c && owned(row)) ++row_start[static_cast<size_t>(row - first_row) + 1];
      }
    }
  }
  std::partial_sum(row_start.begin(), row_start.end(), row_start.begin());
  const auto entries = static_cast<size_t>(row_start.back());
  columns.resize(entries);
  values.assign(entries, 0.0);
  for (size_t r = 0; r < local_rows; ++r) {
    if (!prescribed[r]) continue;
    columns[static_cast<size_t>(row_start[r])] = first_row + static_cast<PetscInt>(r);
    values[static_cast<size_t>(row_start[r])] = 1.0;
    identity_slots.push_back(row_start[r]);
  }
  for_each_entry(lower, [&](PetscInt slot, PetscInt column, int) { columns[static_cast<size_t>(slot)] = column; });
}

void GamgSolver::Impl::create_matrix() {
  const auto local = static_cast<PetscInt>(end_row - first_row);
  if (size > 1) {
    check(MatCreate(comm, &matrix), "matrix create");
    check(MatSetSizes(matrix, local, local, rows, rows), "matrix sizes");
    check(MatSetBlockSize(matrix, 3), "matrix block size");
    check(MatSetType(matrix, MATMPIAIJ), "matrix type");
    check(MatMPIAIJSetPreallocationCSR(matrix, row_start.data(), columns.data(), values.data()), "matrix pattern");
    columns = {};  // PETSc has its own copies
    values = {};
  } else {
    check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, local, local, row_start.data(), columns.data(),
                                    values.data(), &matrix),
          "matrix create");
    check(MatSetBlockSize(matrix, 3), "matrix block size");
  }
  check(MatSetOption(matrix, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE), "matrix option");
  check(MatSetOption(matrix, MAT_SPD, PETSC_TRUE), "matrix option");
  check(MatSetOption(matrix, MAT_SPD_ETERNAL, PETSC_TRUE), "matrix option");
}

/// The near-nullspace: the six rigid-body modes of this rank's nodes; the
/// vectors made like their coordinates.
void GamgSolver::Impl::set_rigid_body_modes(std::span<const Vec3> nodes, std::span<const int> node_order) {
  const auto local = static_cast<PetscInt>(end_row - first_row);
  const auto first_node = static_cast<size_t>(first_row / 3), end_node = static_cast<size_t>(end_row / 3);
  Vec coordinates = nullptr;
  check(VecCreate(comm, &coordinates), "vector create");
  check(VecSetSizes(coordinates, local, rows), "vector sizes");
  check(VecSetBlockSize(coordinates, 3), "vector block size");
  check(VecSetType(coordinates, size > 1 ? VECMPI : VECSEQ), "vector type");
  PetscScalar* xyz = nullptr;
  check(VecGetArray(coordinates, &xyz), "vector access");
  for (size_t place = first_node; place < end_node; ++place)
    for (size_t axis = 0; axis < 3; ++axis)
      xyz[3 * (place - first_node) + axis] =
          nodes[static_cast<size_t>(node_order[place])][static_cast<long>(axis)];
  check(VecRestoreArray(coordinates, &xyz), "vector access");
  MatNullSpace modes = nullptr;
  check(MatNullSpaceCreateRigidBody(coordinates, &modes), "rigid-body modes");
  check(MatSetNearNullSpace(matrix, modes), "near-nullspace");
  MatNullSpaceDestroy(&modes);
  check(VecDuplicate(coordinates, &rhs), "vector create");
  check(VecDuplicate(coordinates, &solution), "vector create");
  VecDestroy(&coordinates);
  if (size > 1) check(VecScatterCreateToAll(solution, &to_all, &gathered), "scatter create");
}

void GamgSolver::Impl::create_krylov(double tolerance, int max_iterations) {
  check(KSPCreate(comm, &ksp), "KSP create");
  check(KSPSetOptionsPrefix(ksp, "spec2fab_fem_"), "KSP prefix");
  check(KSPSetType(ksp, KSPCG), "KSP type");
  // ‖b − Ax‖ / ‖b‖, as the other solvers measure it, not the preconditioned norm.
  check(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED), "KSP norm");
  check(KSPSetTolerances(ksp, tolerance, 0.0, PETSC_DEFAULT, max_iterations), "KSP tolerances");
  PC pc = nullptr;
  check(KSPGetPC(ksp, &pc), "PC");
  check(PCSetType(pc, PCGAMG), "PC type");
  check(PCGAMGSetType(pc, PCGAMGAGG), "GAMG type");
  check(KSPSetFromOptions(ksp), "KSP options");
}

GamgSolver::~GamgSolver() {
  std::lock_guard lock(petsc_mutex());
  impl_.reset();
}

void GamgSolver::setup(const Matrix& lower) {
  std::lock_guard lock(petsc_mutex());
  [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
  Impl& m = *impl_;
  const double* from = lower.valuePtr();
  if (m.size > 1) {
    std::vector<PetscScalar> values(static_cast<size_t>(m.row_start.back()), 0.0);
    for (PetscInt slot : m.identity_slots) values[static_cast<size_t>(slot)] = 1.0;
    m.for_each_entry(lower, [&](PetscInt slot, PetscInt, int k) { values[static_cast<size_t>(slot)] = from[k]; });
    check(MatUpdateMPIAIJWithArray(m.matrix, values.data()), "matrix values");
  } else {
    PetscScalar* to = m.values.data();
    m.for_each_entry(lower, [&](PetscInt slot, PetscInt, int k) { to[slot] = from[k]; });
    // PETSc's matrix holds `values` itself: tell it that they changed.
    PetscScalar* same = nullptr;
    check(MatSeqAIJGetArray(m.matrix, &same), "matrix values");
    if (same != to) throw std::logic_error("GamgSolver: PETSc copied the matrix");
    check(MatSeqAIJRestoreArray(m.matrix, &same), "matrix values");
  }
  check(KSPSetOperators(m.ksp, m.matrix, m.matrix), "KSP operators");
  check(KSPSetUp(m.ksp), "multigrid setup");
  m.set_up = true;
  // Collective (a sum over the ranks): asked here, where every rank is,
  // not when rank 0 alone writes the report.
  PC pc = nullptr;
  PetscReal grid = 0;
  check(KSPGetPC(m.ksp, &pc), "PC");
  check(PCMGGetGridComplexity(pc, &grid, &m.complexity), "multigrid complexity");
}

bool GamgSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  std::lock_guard lock(petsc_mutex());
  Impl& m = *impl_;
  if (!m.set_up) throw std::logic_error("GamgSolver: solve before setup");
  PetscScalar* to = nullptr;
  check(VecSet(m.rhs, 0.0), "vector set");
  check(VecGetArray(m.rhs, &to), "vector access");
  for (size_t i = 0; i < m.row_of_free.size(); ++i) {
    if (const PetscInt row = m.row_of_free[i]; m.owned(row)) to[row - m.first_row] = b[static_cast<long>(i)];
  }
  check(VecRestoreArray(m.rhs, &to), "vector access");
  check(VecSet(m.solution, 0.0), "vector set");
  check(KSPSolve(m.ksp, m.rhs, m.solution), "CG solve");
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  PetscInt iterations = 0;
  PetscReal residual = 0, norm_b = 0;
  check(KSPGetConvergedReason(m.ksp, &reason), "CG result");
  check(KSPGetIterationNumber(m.ksp, &iterations), "CG result");
  check(KSPGetResidualNorm(m.ksp, &residual), "CG result");
  check(VecNorm(m.rhs, NORM_2, &norm_b), "vector norm");
  m.iterations = static_cast<int>(iterations);
  m.relative_residual = norm_b > 0 ? residual / norm_b : residual;

  Vec whole = m.solution;
  if (m.size > 1) {
    check(VecScatterBegin(m.to_all, m.solution, m.gathered, INSERT_VALUES, SCATTER_FORWARD), "gather");
    check(VecScatterEnd(m.to_all, m.solution, m.gathered, INSERT_VALUES, SCATTER_FORWARD), "gather");
    whole = m.gathered;
  }
  const PetscScalar* from = nullptr;
  check(VecGetArrayRead(whole, &from), "vector access");
  x.resize(static_cast<long>(m.row_of_free.size()));
  for (size_t i = 0; i < m.row_of_free.size(); ++i) x[static_cast<long>(i)] = from[m.row_of_free[i]];
  check(VecRestoreArrayRead(whole, &from), "vector access");
  return reason > 0;
}

int GamgSolver::last_iterations() const { return impl_->iterations; }
double GamgSolver::last_relative_residual() const { return impl_->relative_residual; }
int GamgSolver::ranks() const { return impl_->size; }

double GamgSolver::operator_complexity() const { return impl_->complexity; }

}  // namespace spec2fab::fem

#else  // a build without PETSc

namespace spec2fab::fem {

struct GamgSolver::Impl {};

bool GamgSolver::available() { return false; }

GamgSolver::GamgSolver(const Matrix&, const std::vector<int>&, std::span<const Vec3>, std::span<const int>, double, int,
                       bool) {
  throw std::runtime_error("this build has no PETSc (configure with -DSPEC2FAB_WITH_PETSC=ON)");
}
GamgSolver::~GamgSolver() = default;
void GamgSolver::setup(const Matrix&) {}
bool GamgSolver::solve(const Eigen::VectorXd&, Eigen::VectorXd&) { return false; }
int GamgSolver::last_iterations() const { return 0; }
double GamgSolver::last_relative_residual() const { return 0; }
double GamgSolver::operator_complexity() const { return 0; }
int GamgSolver::ranks() const { return 1; }
GamgSolver::Partition GamgSolver::partition(size_t node_count, bool) { return {0, 1, 0, node_count}; }

}  // namespace spec2fab::fem

#endif

#include "fem/petsc/gamg_solver.h"

#include <stdexcept>
#include <string>

#include "core/build_options.h"

#if SPEC2FAB_WITH_PETSC

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <numeric>

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

#include <Eigen/Geometry>
#include <petscksp.h>

namespace spec2fab::fem {
namespace {

std::mutex& petsc_mutex() {
  static std::mutex mutex;
  return mutex;
}

// Open MPI and PETSc keep, and at finalisation drop without freeing, state
// allocated in their own plugins and registries; the sanitizer build does
// not count those as leaks of ours (every allocation of Spec2Fab's still is).
struct IgnoreThirdPartyLeaks {
#if defined(__SANITIZE_ADDRESS__)
  IgnoreThirdPartyLeaks() { __lsan_disable(); }
  ~IgnoreThirdPartyLeaks() { __lsan_enable(); }
#endif
};

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

// PETSc for the process's lifetime. It initialises MPI as a singleton when
// nobody has (a plain run, no mpirun) and then finalises it too; under
// mpirun (ranks::start) or beside hypre it uses the MPI that is there.
struct PetscSession {
  PetscSession() {
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
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
  }
  ~PetscSession() {
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    int finalized = 0;
    MPI_Finalized(&finalized);  // mpirun's MPI may be finalised first (ranks::stop)
    if (!finalized) PetscFinalize();
  }
};

void start_petsc() {
  static PetscSession session;
}

// Nodes along a Morton (Z-order) curve of their positions: ties (equal
// codes) keep TetGen's order, so the numbering is deterministic.
std::vector<int> morton_order(std::span<const Vec3> nodes) {
  Eigen::AlignedBox3d box;
  for (const Vec3& x : nodes) box.extend(x);
  const Vec3 extent = box.sizes().cwiseMax(1e-12);
  constexpr double kCells = 2097151.0;  // 21 bits per axis
  auto spread = [](std::uint64_t v) {   // bits of v at every third place
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  std::vector<std::uint64_t> code(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Vec3 unit = (nodes[i] - box.min()).cwiseQuotient(extent);
    std::uint64_t c = 0;
    for (int axis = 0; axis < 3; ++axis)
      c |= spread(static_cast<std::uint64_t>(std::clamp(unit[axis], 0.0, 1.0) * kCells)) << axis;
    code[i] = c;
  }
  std::vector<int> order(nodes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return code[static_cast<size_t>(a)] < code[static_cast<size_t>(b)]; });
  return order;
}

}  // namespace

struct GamgSolver::Impl {
  MPI_Comm comm = MPI_COMM_SELF;
  int rank = 0, size = 1;
  double tolerance = 1e-10;
  PetscInt rows = 0;                  // every node's three rows
  PetscInt first_row = 0, end_row = 0;  // this rank's
  std::vector<int> dof_of_free;
  std::vector<PetscInt> row_of_dof;  // node DOF (3·node + axis) -> row in the Morton numbering
  // Where each entry of the lower triangle goes among this rank's values
  // (CSR order, as PETSc stores them): `slot` for (row, column) and
  // `mirror` for (column, row); -1 off this rank or on the diagonal.
  std::vector<int> slot, mirror;
  std::vector<int> identity_slots;  // prescribed rows' diagonals
  std::vector<PetscScalar> values;  // distributed only: this rank's CSR values
  Mat matrix = nullptr;
  Vec rhs = nullptr, solution = nullptr, gathered = nullptr;
  VecScatter to_all = nullptr;
  KSP ksp = nullptr;
  int iterations = 0;
  double relative_residual = 0;
  bool set_up = false;

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

GamgSolver::GamgSolver(const Matrix& lower, std::vector<int> dof_of_free, std::span<const Vec3> nodes,
                       double tolerance, int max_iterations, bool distributed)
    : impl_(std::make_unique<Impl>()) {
  if (!lower.isCompressed()) throw std::logic_error("GamgSolver: the matrix must be compressed");
  if (dof_of_free.size() != static_cast<size_t>(lower.cols())) throw std::logic_error("GamgSolver: one DOF per free row");
  std::lock_guard lock(petsc_mutex());
  start_petsc();
  Impl& m = *impl_;
  if (distributed) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (initialized) m.comm = PETSC_COMM_WORLD;
  }
  MPI_Comm_rank(m.comm, &m.rank);
  MPI_Comm_size(m.comm, &m.size);
  m.tolerance = tolerance;
  m.dof_of_free = std::move(dof_of_free);
  const size_t node_count = nodes.size();
  m.rows = static_cast<PetscInt>(3 * node_count);

  const std::vector<int> order = morton_order(nodes);
  m.row_of_dof.resize(3 * node_count);
  for (size_t place = 0; place < node_count; ++place)
    for (size_t axis = 0; axis < 3; ++axis)
      m.row_of_dof[3 * static_cast<size_t>(order[place]) + axis] = static_cast<PetscInt>(3 * place + axis);
  // A contiguous run of the curve per rank: a space-filling-curve partition.
  const auto count = static_cast<long long>(node_count);
  const long long first_node = count * m.rank / m.size, end_node = count * (m.rank + 1) / m.size;
  m.first_row = static_cast<PetscInt>(3 * first_node);
  m.end_row = static_cast<PetscInt>(3 * end_node);
  const auto local_rows = static_cast<size_t>(m.end_row - m.first_row);
  auto owned = [&](PetscInt row) { return row >= m.first_row && row < m.end_row; };

  // This rank's rows of the full symmetric matrix in the new numbering:
  // sizes, then (column, source) pairs, sorted per row. Source: 2k for
  // lower entry k as (row, column), 2k + 1 as its mirror, -1 the identity.
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const auto free_count = static_cast<int>(lower.cols());
  std::vector<char> prescribed(3 * node_count, 1);
  for (int dof : m.dof_of_free) prescribed[static_cast<size_t>(dof)] = 0;
  std::vector<PetscInt> row_start(local_rows + 1, 0);
  for (size_t dof = 0; dof < prescribed.size(); ++dof)
    if (prescribed[dof] && owned(m.row_of_dof[dof])) ++row_start[static_cast<size_t>(m.row_of_dof[dof] - m.first_row) + 1];
  auto row_of_free = [&](int i) { return m.row_of_dof[static_cast<size_t>(m.dof_of_free[static_cast<size_t>(i)])]; };
  for (int c = 0; c < free_count; ++c) {
    const PetscInt column = row_of_free(c);
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      const PetscInt row = row_of_free(inner[k]);
      if (owned(row)) ++row_start[static_cast<size_t>(row - m.first_row) + 1];
      if (inner[k] != c && owned(column)) ++row_start[static_cast<size_t>(column - m.first_row) + 1];
    }
  }
  std::partial_sum(row_start.begin(), row_start.end(), row_start.begin());
  const auto entries = static_cast<size_t>(row_start.back());
  std::vector<std::pair<PetscInt, long long>> cells(entries);
  {
    std::vector<PetscInt> cursor(row_start.begin(), row_start.end() - 1);
    auto put = [&](PetscInt row, PetscInt column, long long source) {
      cells[static_cast<size_t>(cursor[static_cast<size_t>(row - m.first_row)]++)] = {column, source};
    };
    for (size_t dof = 0; dof < prescribed.size(); ++dof)
      if (const PetscInt row = m.row_of_dof[dof]; prescribed[dof] && owned(row)) put(row, row, -1);
    for (int c = 0; c < free_count; ++c) {
      const PetscInt column = row_of_free(c);
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const PetscInt row = row_of_free(inner[k]);
        if (owned(row)) put(row, column, 2LL * k);
        if (inner[k] != c && owned(column)) put(column, row, 2LL * k + 1);
      }
    }
  }
  std::vector<PetscInt> columns(entries);
  m.slot.assign(static_cast<size_t>(lower.nonZeros()), -1);
  m.mirror.assign(static_cast<size_t>(lower.nonZeros()), -1);
  for (size_t r = 0; r < local_rows; ++r) {
    const auto begin = cells.begin() + row_start[r], end = cells.begin() + row_start[r + 1];
    std::sort(begin, end);
    for (auto it = begin; it != end; ++it) {
      const auto at = static_cast<size_t>(it - cells.begin());
      columns[at] = it->first;
      if (it->second < 0) m.identity_slots.push_back(static_cast<int>(at));
      else if (it->second % 2 == 0) m.slot[static_cast<size_t>(it->second / 2)] = static_cast<int>(at);
      else m.mirror[static_cast<size_t>(it->second / 2)] = static_cast<int>(at);
    }
  }
  cells = {};

  [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
  std::vector<PetscScalar> initial(entries, 0.0);
  for (int s : m.identity_slots) initial[static_cast<size_t>(s)] = 1.0;
  const auto local = static_cast<PetscInt>(local_rows);
  check(MatCreate(m.comm, &m.matrix), "matrix create");
  check(MatSetSizes(m.matrix, local, local, m.rows, m.rows), "matrix sizes");
  check(MatSetBlockSize(m.matrix, 3), "matrix block size");
  check(MatSetType(m.matrix, m.size > 1 ? MATMPIAIJ : MATSEQAIJ), "matrix type");
  if (m.size > 1) {
    check(MatMPIAIJSetPreallocationCSR(m.matrix, row_start.data(), columns.data(), initial.data()), "matrix pattern");
    m.values = std::move(initial);
  } else {
    check(MatSeqAIJSetPreallocationCSR(m.matrix, row_start.data(), columns.data(), initial.data()), "matrix pattern");
  }
  check(MatSetOption(m.matrix, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE), "matrix option");
  check(MatSetOption(m.matrix, MAT_SPD, PETSC_TRUE), "matrix option");
  check(MatSetOption(m.matrix, MAT_SPD_ETERNAL, PETSC_TRUE), "matrix option");

  // The near-nullspace: the six rigid-body modes of this rank's nodes.
  Vec coordinates = nullptr;
  check(VecCreate(m.comm, &coordinates), "vector create");
  check(VecSetSizes(coordinates, local, m.rows), "vector sizes");
  check(VecSetBlockSize(coordinates, 3), "vector block size");
  check(VecSetType(coordinates, m.size > 1 ? VECMPI : VECSEQ), "vector type");
  PetscScalar* xyz = nullptr;
  check(VecGetArray(coordinates, &xyz), "vector access");
  for (size_t place = static_cast<size_t>(first_node); place < static_cast<size_t>(end_node); ++place)
    for (size_t axis = 0; axis < 3; ++axis)
      xyz[3 * (place - static_cast<size_t>(first_node)) + axis] = nodes[static_cast<size_t>(order[place])][static_cast<long>(axis)];
  check(VecRestoreArray(coordinates, &xyz), "vector access");
  MatNullSpace modes = nullptr;
  check(MatNullSpaceCreateRigidBody(coordinates, &modes), "rigid-body modes");
  check(MatSetNearNullSpace(m.matrix, modes), "near-nullspace");
  MatNullSpaceDestroy(&modes);
  check(VecDuplicate(coordinates, &m.rhs), "vector create");
  check(VecDuplicate(coordinates, &m.solution), "vector create");
  VecDestroy(&coordinates);
  if (m.size > 1) check(VecScatterCreateToAll(m.solution, &m.to_all, &m.gathered), "scatter create");

  check(KSPCreate(m.comm, &m.ksp), "KSP create");
  check(KSPSetOptionsPrefix(m.ksp, "spec2fab_fem_"), "KSP prefix");
  check(KSPSetType(m.ksp, KSPCG), "KSP type");
  // ‖b − Ax‖ / ‖b‖, as the other solvers measure it, not the preconditioned norm.
  check(KSPSetNormType(m.ksp, KSP_NORM_UNPRECONDITIONED), "KSP norm");
  check(KSPSetTolerances(m.ksp, tolerance, 0.0, PETSC_DEFAULT, max_iterations), "KSP tolerances");
  PC pc = nullptr;
  check(KSPGetPC(m.ksp, &pc), "PC");
  check(PCSetType(pc, PCGAMG), "PC type");
  check(PCGAMGSetType(pc, PCGAMGAGG), "GAMG type");
  check(KSPSetFromOptions(m.ksp), "KSP options");
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
  auto fill = [&](PetscScalar* to) {
    for (size_t k = 0; k < m.slot.size(); ++k) {
      if (m.slot[k] >= 0) to[m.slot[k]] = from[k];
      if (m.mirror[k] >= 0) to[m.mirror[k]] = from[k];
    }
  };
  if (m.size > 1) {
    fill(m.values.data());
    check(MatUpdateMPIAIJWithArray(m.matrix, m.values.data()), "matrix values");
  } else {
    PetscScalar* to = nullptr;
    check(MatSeqAIJGetArray(m.matrix, &to), "matrix values");
    fill(to);
    check(MatSeqAIJRestoreArray(m.matrix, &to), "matrix values");
  }
  check(KSPSetOperators(m.ksp, m.matrix, m.matrix), "KSP operators");
  check(KSPSetUp(m.ksp), "multigrid setup");
  m.set_up = true;
}

bool GamgSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  std::lock_guard lock(petsc_mutex());
  Impl& m = *impl_;
  if (!m.set_up) throw std::logic_error("GamgSolver: solve before setup");
  PetscScalar* to = nullptr;
  check(VecSet(m.rhs, 0.0), "vector set");
  check(VecGetArray(m.rhs, &to), "vector access");
  for (size_t i = 0; i < m.dof_of_free.size(); ++i) {
    const PetscInt row = m.row_of_dof[static_cast<size_t>(m.dof_of_free[i])];
    if (row >= m.first_row && row < m.end_row) to[row - m.first_row] = b[static_cast<long>(i)];
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
  x.resize(static_cast<long>(m.dof_of_free.size()));
  for (size_t i = 0; i < m.dof_of_free.size(); ++i)
    x[static_cast<long>(i)] = from[m.row_of_dof[static_cast<size_t>(m.dof_of_free[i])]];
  check(VecRestoreArrayRead(whole, &from), "vector access");
  return reason > 0;
}

int GamgSolver::last_iterations() const { return impl_->iterations; }
double GamgSolver::last_relative_residual() const { return impl_->relative_residual; }
int GamgSolver::ranks() const { return impl_->size; }

double GamgSolver::operator_complexity() const {
  std::lock_guard lock(petsc_mutex());
  if (!impl_->set_up) return 0;
  PC pc = nullptr;
  PetscReal grid = 0, op = 0;
  if (KSPGetPC(impl_->ksp, &pc) || PCMGGetGridComplexity(pc, &grid, &op)) return 0;
  return op;
}

}  // namespace spec2fab::fem

#else  // a build without PETSc

namespace spec2fab::fem {

struct GamgSolver::Impl {};

bool GamgSolver::available() { return false; }

GamgSolver::GamgSolver(const Matrix&, std::vector<int>, std::span<const Vec3>, double, int, bool) {
  throw std::runtime_error("this build has no PETSc (configure with -DSPEC2FAB_WITH_PETSC=ON)");
}
GamgSolver::~GamgSolver() = default;
void GamgSolver::setup(const Matrix&) {}
bool GamgSolver::solve(const Eigen::VectorXd&, Eigen::VectorXd&) { return false; }
int GamgSolver::last_iterations() const { return 0; }
double GamgSolver::last_relative_residual() const { return 0; }
double GamgSolver::operator_complexity() const { return 0; }
int GamgSolver::ranks() const { return 1; }

}  // namespace spec2fab::fem

#endif

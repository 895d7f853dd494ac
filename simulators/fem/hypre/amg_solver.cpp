#include "fem/hypre/amg_solver.h"

#include <stdexcept>

#include "core/build_options.h"
#include "core/ranks.h"
#include "core/third_party_leaks.h"

#if SPEC2FAB_WITH_HYPRE

#include <algorithm>
#include <mutex>

#include <mpi.h>
#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_ls.h>

namespace spec2fab::fem {
namespace {

std::mutex& hypre_mutex() {
  static std::mutex mutex;
  return mutex;
}

// hypre for the process's lifetime, on the process's MPI (ranks::ensure_mpi:
// a single rank without mpirun).
struct HypreSession {
  HypreSession() {
    ranks::ensure_mpi();
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    HYPRE_Init();
  }
  ~HypreSession() {
    [[maybe_unused]] const IgnoreThirdPartyLeaks ignore;
    HYPRE_Finalize();
  }
};

void start_hypre() {
  static HypreSession session;
}

void check(HYPRE_Int code, const char* what) {
  if (code != 0 && !HYPRE_CheckError(code, HYPRE_ERROR_CONV)) {
    char message[256] = {};
    HYPRE_DescribeError(code, message);
    HYPRE_ClearAllErrors();
    throw std::runtime_error(std::string("hypre: ") + what + " failed: " + message);
  }
}

}  // namespace

struct AmgSolver::Impl {
  // The constructor's steps.
  void create_matrix(const Matrix& lower);
  void create_boomer_amg();
  void create_pcg();
  HYPRE_Int n = 0;  // rows of the preconditioned system: every node DOF
  double tolerance = 1e-10;
  int max_iterations = 1000;
  std::vector<int> dof_of_free;
  // hypre's matrix, built directly in its storage (one rank: all of it in
  // the diagonal block), each row's diagonal first as its smoothers expect.
  std::vector<HYPRE_Int> cursor;
  hypre_ParCSRMatrix* matrix = nullptr;
  hypre_ParVector* rhs = nullptr;
  hypre_ParVector* solution = nullptr;
  HYPRE_Solver pcg = nullptr, amg = nullptr;
  int iterations = 0;
  double relative_residual = 0;
  bool set_up = false;

  hypre_CSRMatrix* storage() const { return hypre_ParCSRMatrixDiag(matrix); }

  // Visits every entry of the full symmetric matrix's free rows as
  // (slot in hypre's storage, column, index in `lower`): row R holds its
  // diagonal first, then the transposed entries of earlier columns, then
  // the lower triangle's column below the diagonal.
  template <class Visit>
  void for_each_entry(const Matrix& lower, Visit&& visit) {
    const HYPRE_Int* row_start = hypre_CSRMatrixI(storage());
    for (HYPRE_Int r = 0; r < n; ++r) cursor[static_cast<size_t>(r)] = row_start[r] + 1;
    const int* outer = lower.outerIndexPtr();
    const int* inner = lower.innerIndexPtr();
    const auto free_count = static_cast<int>(lower.cols());
    for (int c = 0; c < free_count; ++c) {
      const int column = dof_of_free[static_cast<size_t>(c)];
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const int row = dof_of_free[static_cast<size_t>(inner[k])];
        if (row == column) {
          visit(row_start[column], column, k);
        } else {
          visit(cursor[static_cast<size_t>(column)]++, row, k);
          visit(cursor[static_cast<size_t>(row)]++, column, k);
        }
      }
    }
  }

  hypre_ParVector* make_vector() {
    HYPRE_BigInt partition[2] = {0, n};
    hypre_ParVector* v = hypre_ParVectorCreate(MPI_COMM_SELF, n, partition);
    check(hypre_ParVectorInitialize(v), "vector initialise");
    return v;
  }

  HYPRE_ParCSRMatrix hypre_matrix() const { return reinterpret_cast<HYPRE_ParCSRMatrix>(matrix); }
  static HYPRE_ParVector hypre_vector(hypre_ParVector* v) { return reinterpret_cast<HYPRE_ParVector>(v); }
  static double* data(hypre_ParVector* v) { return hypre_VectorData(hypre_ParVectorLocalVector(v)); }

  ~Impl() {
    if (pcg) HYPRE_ParCSRPCGDestroy(pcg);
    if (amg) HYPRE_BoomerAMGDestroy(amg);
    if (rhs) hypre_ParVectorDestroy(rhs);
    if (solution) hypre_ParVectorDestroy(solution);
    if (matrix) hypre_ParCSRMatrixDestroy(matrix);
  }
};

bool AmgSolver::available() { return true; }

AmgSolver::AmgSolver(const Matrix& lower, std::vector<int> dof_of_free, size_t node_count, double tolerance,
                     int max_iterations)
    : impl_(std::make_unique<Impl>()) {
  if (!lower.isCompressed()) throw std::logic_error("AmgSolver: the matrix must be compressed");
  if (dof_of_free.size() != static_cast<size_t>(lower.cols())) throw std::logic_error("AmgSolver: one DOF per free row");
  std::lock_guard lock(hypre_mutex());
  start_hypre();
  Impl& m = *impl_;
  m.n = static_cast<HYPRE_Int>(3 * node_count);
  m.tolerance = tolerance;
  m.max_iterations = max_iterations;
  m.dof_of_free = std::move(dof_of_free);
  m.create_matrix(lower);
  m.create_boomer_amg();
  m.create_pcg();
}

void AmgSolver::Impl::create_matrix(const Matrix& lower) {
  const auto rows = static_cast<size_t>(n);
  // Row sizes: a prescribed DOF's row is its diagonal (the identity).
  std::vector<HYPRE_Int> row_sizes(rows, 1);
  for (int dof : dof_of_free) row_sizes[static_cast<size_t>(dof)] = 0;
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  for (int c = 0; c < static_cast<int>(lower.cols()); ++c) {
    for (int k = outer[c]; k < outer[c + 1]; ++k) {
      ++row_sizes[static_cast<size_t>(dof_of_free[static_cast<size_t>(c)])];
      if (inner[k] != c) ++row_sizes[static_cast<size_t>(dof_of_free[static_cast<size_t>(inner[k])])];
    }
  }
  HYPRE_Int entries = 0;
  for (HYPRE_Int size : row_sizes) entries += size;
  HYPRE_BigInt partition[2] = {0, n};
  matrix = hypre_ParCSRMatrixCreate(MPI_COMM_SELF, n, n, partition, partition, 0, entries, 0);
  check(hypre_ParCSRMatrixInitialize(matrix), "matrix initialise");
  HYPRE_Int* row_start = hypre_CSRMatrixI(storage());
  HYPRE_Int* columns = hypre_CSRMatrixJ(storage());
  double* values = hypre_CSRMatrixData(storage());
  row_start[0] = 0;
  for (size_t r = 0; r < rows; ++r) {
    row_start[r + 1] = row_start[r] + row_sizes[r];
    columns[row_start[r]] = static_cast<HYPRE_Int>(r);  // the diagonal first
    values[row_start[r]] = 1.0;                           // stays 1 on prescribed rows
  }
  cursor.resize(rows);
  for_each_entry(lower, [&](HYPRE_Int slot, int column, int) { columns[slot] = column; });
  hypre_ParCSRMatrixSetNumNonzeros(matrix);
  check(hypre_MatvecCommPkgCreate(matrix), "matrix communication");
  rhs = make_vector();
  solution = make_vector();
}

// Systems AMG, "unknown" approach (each displacement component coarsened
// on its own couplings), with the settings hypre advises for 3-D problems
// (HMIS coarsening, extended+i interpolation truncated to 4 entries, one
// level of aggressive coarsening). Measured on the 321,191-tet cantilever
// of benchmarks/fem_vs_ccx.sh: operator complexity 1.29, ~150 CG
// iterations to 1e-10. Interpolating the rigid rotations as well (GM
// variant, nodal coarsening) cut the iterations to 43-106 but raised the
// complexity to 3.4-5.8: more memory and no faster.
void AmgSolver::Impl::create_boomer_amg() {
  const auto rows = static_cast<size_t>(n);
  check(HYPRE_BoomerAMGCreate(&amg), "BoomerAMG create");
  HYPRE_BoomerAMGSetPrintLevel(amg, 0);
  HYPRE_BoomerAMGSetMaxIter(amg, 1);  // one V-cycle per CG iteration
  HYPRE_BoomerAMGSetTol(amg, 0.0);
  HYPRE_BoomerAMGSetNumFunctions(amg, 3);  // x, y, z of each node, interleaved
  // BoomerAMG takes the array and frees it with hypre's allocator.
  auto* function_of_row = hypre_CTAlloc(HYPRE_Int, rows, HYPRE_MEMORY_HOST);
  for (size_t r = 0; r < rows; ++r) function_of_row[r] = static_cast<HYPRE_Int>(r % 3);
  HYPRE_BoomerAMGSetDofFunc(amg, function_of_row);
  HYPRE_BoomerAMGSetCoarsenType(amg, 10);  // HMIS
  HYPRE_BoomerAMGSetInterpType(amg, 6);    // extended+i
  HYPRE_BoomerAMGSetPMaxElmts(amg, 4);
  HYPRE_BoomerAMGSetStrongThreshold(amg, 0.5);
  HYPRE_BoomerAMGSetAggNumLevels(amg, 1);
  // Forward Gauss-Seidel going down and backward coming up: the V-cycle is
  // symmetric, as CG needs, at half the sweeps of symmetric Gauss-Seidel
  // on both legs. With nodal coarsening (a node's 3 unknowns coarsened
  // together, strength from the row-sum norm of its 3x3 blocks): 203 CG
  // iterations instead of 149, each cheaper; the 321k-tet cantilever's
  // solve 13.46 -> 10.69 s beside ccx's 27.1 s (benchmarks/RESULTS.md).
  HYPRE_BoomerAMGSetCycleRelaxType(amg, 3, 1);
  HYPRE_BoomerAMGSetCycleRelaxType(amg, 4, 2);
  HYPRE_BoomerAMGSetNodal(amg, 4);
  HYPRE_BoomerAMGSetCycleRelaxType(amg, 9, 3);  // Gaussian elimination on the coarsest grid
}

void AmgSolver::Impl::create_pcg() {
  check(HYPRE_ParCSRPCGCreate(MPI_COMM_SELF, &pcg), "PCG create");
  HYPRE_PCGSetTol(pcg, tolerance);
  HYPRE_PCGSetTwoNorm(pcg, 1);
  HYPRE_PCGSetMaxIter(pcg, max_iterations);
  HYPRE_PCGSetPrintLevel(pcg, 0);
  HYPRE_PCGSetPrecond(pcg, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
                      reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), amg);
}

AmgSolver::~AmgSolver() {
  std::lock_guard lock(hypre_mutex());
  impl_.reset();
}

void AmgSolver::setup(const Matrix& lower) {
  std::lock_guard lock(hypre_mutex());
  Impl& m = *impl_;
  const double* from = lower.valuePtr();
  double* to = hypre_CSRMatrixData(m.storage());
  m.for_each_entry(lower, [&](HYPRE_Int slot, int, int k) { to[slot] = from[k]; });
  check(HYPRE_ParCSRPCGSetup(m.pcg, m.hypre_matrix(), m.hypre_vector(m.rhs), m.hypre_vector(m.solution)),
        "multigrid setup");
  m.set_up = true;
}

bool AmgSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  std::lock_guard lock(hypre_mutex());
  Impl& m = *impl_;
  double* full_b = Impl::data(m.rhs);
  double* full_x = Impl::data(m.solution);
  std::fill(full_b, full_b + m.n, 0.0);
  std::fill(full_x, full_x + m.n, 0.0);
  for (size_t i = 0; i < m.dof_of_free.size(); ++i) full_b[m.dof_of_free[i]] = b[static_cast<long>(i)];
  if (!m.set_up) throw std::logic_error("AmgSolver: solve before setup");
  const HYPRE_Int code =
      HYPRE_ParCSRPCGSolve(m.pcg, m.hypre_matrix(), m.hypre_vector(m.rhs), m.hypre_vector(m.solution));
  HYPRE_Int iterations = 0;
  HYPRE_PCGGetNumIterations(m.pcg, &iterations);
  HYPRE_PCGGetFinalRelativeResidualNorm(m.pcg, &m.relative_residual);
  m.iterations = static_cast<int>(iterations);
  const bool converged = code == 0;
  HYPRE_ClearAllErrors();
  x.resize(static_cast<long>(m.dof_of_free.size()));
  for (size_t i = 0; i < m.dof_of_free.size(); ++i) x[static_cast<long>(i)] = full_x[m.dof_of_free[i]];
  return converged;
}

int AmgSolver::last_iterations() const { return impl_->iterations; }
double AmgSolver::last_relative_residual() const { return impl_->relative_residual; }

double AmgSolver::operator_complexity() const {
  std::lock_guard lock(hypre_mutex());
  auto* data = static_cast<hypre_ParAMGData*>(static_cast<void*>(impl_->amg));
  if (!data || !impl_->set_up) return 0;
  const int levels = hypre_ParAMGDataNumLevels(data);
  hypre_ParCSRMatrix** a = hypre_ParAMGDataAArray(data);
  if (levels < 1 || !a) return 0;
  double total = 0;
  auto nonzeros = [](hypre_ParCSRMatrix* level) {  // one rank: everything is in the diagonal block
    return static_cast<double>(hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixDiag(level)) +
                               hypre_CSRMatrixNumNonzeros(hypre_ParCSRMatrixOffd(level)));
  };
  for (int level = 0; level < levels; ++level) total += nonzeros(a[level]);
  const double finest = nonzeros(a[0]);
  return finest > 0 ? total / finest : 0;
}

}  // namespace spec2fab::fem

#else  // a build without hypre

namespace spec2fab::fem {

struct AmgSolver::Impl {};

bool AmgSolver::available() { return false; }

AmgSolver::AmgSolver(const Matrix&, std::vector<int>, size_t, double, int) {
  throw std::runtime_error("this build has no hypre (configure with -DSPEC2FAB_WITH_HYPRE=ON)");
}
AmgSolver::~AmgSolver() = default;
void AmgSolver::setup(const Matrix&) {}
bool AmgSolver::solve(const Eigen::VectorXd&, Eigen::VectorXd&) { return false; }
int AmgSolver::last_iterations() const { return 0; }
double AmgSolver::last_relative_residual() const { return 0; }
double AmgSolver::operator_complexity() const { return 0; }

}  // namespace spec2fab::fem

#endif

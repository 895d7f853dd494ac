#include "fem/cholmod_factor.h"

#include <mutex>
#include <stdexcept>

#include <cholmod.h>
#include <omp.h>

namespace spec2fab::fem {

struct CholmodFactor::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  cholmod_dense* x = nullptr;  // solve2's result and workspaces, kept between solves
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;
  Eigen::MatrixXd permuted;  // forward_solve's P·B, kept between solves

  Impl() {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.print = 0;
    common.error_handler = nullptr;
    common.quick_return_if_not_posdef = 1;
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &common);
    if (x) cholmod_free_dense(&x, &common);
    if (y) cholmod_free_dense(&y, &common);
    if (e) cholmod_free_dense(&e, &common);
    cholmod_finish(&common);
  }

  static cholmod_sparse view(const Matrix& m) {
    cholmod_sparse a{};
    a.nrow = static_cast<size_t>(m.rows());
    a.ncol = static_cast<size_t>(m.cols());
    a.nzmax = static_cast<size_t>(m.nonZeros());
    a.p = const_cast<int*>(m.outerIndexPtr());
    a.i = const_cast<int*>(m.innerIndexPtr());
    a.x = const_cast<double*>(m.valuePtr());
    a.stype = -1;  // the lower triangle holds the matrix
    a.itype = CHOLMOD_INT;
    a.xtype = CHOLMOD_REAL;
    a.dtype = CHOLMOD_DOUBLE;
    a.sorted = 1;
    a.packed = 1;
    return a;
  }
};

namespace {

// CHOLMOD 3 (SuiteSparse 5) asks OpenMP for a fixed 4 threads (num_threads
// clauses, whatever the machine or OMP_NUM_THREADS) in loops that only
// clear and scatter arrays; the factorisation's work is in the (serial)
// BLAS. Woken for every supernode, those threads cost more than they save:
// on the 2-core CI machine the elastic bound's 12-cell search took 8.1 s
// with them and 5.5 s with OMP_THREAD_LIMIT=1. OpenMP's active levels are
// set to 0 (every region runs on its calling thread) while any thread is in
// CHOLMOD, and set back when the last one leaves; hypre's OpenMP (the AMG
// solver) keeps its threads outside that window. The loops write disjoint
// entries, so the answer does not change.
class SerialOpenMp {
 public:
  SerialOpenMp() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (inside_++ == 0) {
      saved_ = omp_get_max_active_levels();
      omp_set_max_active_levels(0);
    }
  }
  ~SerialOpenMp() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (--inside_ == 0) omp_set_max_active_levels(saved_);
  }
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  static inline std::mutex mutex_;
  static inline int inside_ = 0, saved_ = 1;
};

/// Debian's serial OpenBLAS (libopenblas0-serial 0.3.21, built without
/// USE_LOCKING) shares its work buffers between calling threads: two
/// factorisations at once on two threads corrupt each other (found by
/// `spec2fab bench`, whose fem_book runs went different ways on every run
/// with 2 threads and agreed with reference BLAS or with this lock). So
/// CHOLMOD's numeric work, where its BLAS calls are, runs on one thread at a
/// time process-wide. Solvers on one thread (every translator's FEM tuner)
/// never wait; concurrent ones (bench runs) queue for their factorisations.
std::mutex& blas_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;

void CholmodFactor::analyze(const Matrix& lower) {
  if (!lower.isCompressed()) throw std::logic_error("CholmodFactor: the matrix must be compressed");
  const SerialOpenMp serial;
  cholmod_sparse a = Impl::view(lower);
  if (impl_->factor) cholmod_free_factor(&impl_->factor, &impl_->common);
  impl_->factor = cholmod_analyze(&a, &impl_->common);
  if (!impl_->factor) throw std::runtime_error("CHOLMOD: symbolic analysis failed (out of memory?)");
}

bool CholmodFactor::factorize(const Matrix& lower) {
  const std::lock_guard<std::mutex> one_at_a_time(blas_mutex());
  const SerialOpenMp serial;
  cholmod_sparse a = Impl::view(lower);
  cholmod_factorize(&a, impl_->factor, &impl_->common);
  if (impl_->common.status == CHOLMOD_OUT_OF_MEMORY) throw std::runtime_error("CHOLMOD: out of memory");
  return impl_->common.status == CHOLMOD_OK && impl_->factor->minor == impl_->factor->n;
}

bool CholmodFactor::analyze_and_factorize(const Eigen::SparseMatrix<double>& symmetric) {
  Matrix lower = symmetric.triangularView<Eigen::Lower>();
  lower.makeCompressed();
  analyze(lower);
  return factorize(lower);
}

const double* CholmodFactor::solve_columns(int system, const double* b, size_t rows, size_t columns) {
  cholmod_dense rhs{};
  rhs.nrow = rows;
  rhs.ncol = columns;
  rhs.nzmax = rows * columns;
  rhs.d = rows;
  rhs.x = const_cast<double*>(b);
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  const std::lock_guard<std::mutex> one_at_a_time(blas_mutex());
  const SerialOpenMp serial;
  if (!cholmod_solve2(system, impl_->factor, &rhs, nullptr, &impl_->x, nullptr, &impl_->y, &impl_->e,
                      &impl_->common)) {
    throw std::runtime_error("CHOLMOD: solve failed");
  }
  return static_cast<const double*>(impl_->x->x);
}

void CholmodFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  x = Eigen::Map<const Eigen::VectorXd>(solve_columns(CHOLMOD_A, b.data(), static_cast<size_t>(b.size()), 1),
                                        b.size());
}

void CholmodFactor::solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  const double* values =
      solve_columns(CHOLMOD_A, b.data(), static_cast<size_t>(b.rows()), static_cast<size_t>(b.cols()));
  x = Eigen::Map<const Eigen::MatrixXd>(values, b.rows(), b.cols());
}

void CholmodFactor::forward_solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& y) {
  // CHOLMOD_L does not permute: P B first (row k of P B is row Perm[k] of B).
  const cholmod_factor& factor = *impl_->factor;
  if (factor.is_ll == 0) throw std::logic_error("CholmodFactor::forward_solve: the factor must be LLᵀ");
  const auto* perm = static_cast<const int*>(factor.Perm);
  Eigen::MatrixXd& permuted = impl_->permuted;
  permuted.resize(b.rows(), b.cols());
  for (Eigen::Index c = 0; c < b.cols(); ++c)
    for (Eigen::Index k = 0; k < b.rows(); ++k) permuted(k, c) = b(perm ? perm[k] : k, c);
  const double* values =
      solve_columns(CHOLMOD_L, permuted.data(), static_cast<size_t>(b.rows()), static_cast<size_t>(b.cols()));
  y = Eigen::Map<const Eigen::MatrixXd>(values, b.rows(), b.cols());
}

double CholmodFactor::factor_nonzeros() const { return impl_->common.lnz; }
double CholmodFactor::factor_flops() const { return impl_->common.fl; }

}  // namespace spec2fab::fem

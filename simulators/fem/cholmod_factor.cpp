#include "fem/cholmod_factor.h"

#include <stdexcept>

#include <cholmod.h>

namespace spec2fab::fem {

struct CholmodFactor::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  cholmod_dense* x = nullptr;  // solve2's result and workspaces, kept between solves
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;

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

CholmodFactor::CholmodFactor() : impl_(std::make_unique<Impl>()) {}
CholmodFactor::~CholmodFactor() = default;

void CholmodFactor::analyze(const Matrix& lower) {
  if (!lower.isCompressed()) throw std::logic_error("CholmodFactor: the matrix must be compressed");
  cholmod_sparse a = Impl::view(lower);
  if (impl_->factor) cholmod_free_factor(&impl_->factor, &impl_->common);
  impl_->factor = cholmod_analyze(&a, &impl_->common);
  if (!impl_->factor) throw std::runtime_error("CHOLMOD: symbolic analysis failed (out of memory?)");
}

bool CholmodFactor::factorize(const Matrix& lower) {
  cholmod_sparse a = Impl::view(lower);
  cholmod_factorize(&a, impl_->factor, &impl_->common);
  if (impl_->common.status == CHOLMOD_OUT_OF_MEMORY) throw std::runtime_error("CHOLMOD: out of memory");
  return impl_->common.status == CHOLMOD_OK && impl_->factor->minor == impl_->factor->n;
}

void CholmodFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  cholmod_dense rhs{};
  rhs.nrow = static_cast<size_t>(b.size());
  rhs.ncol = 1;
  rhs.nzmax = rhs.nrow;
  rhs.d = rhs.nrow;
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, impl_->factor, &rhs, nullptr, &impl_->x, nullptr, &impl_->y, &impl_->e,
                      &impl_->common)) {
    throw std::runtime_error("CHOLMOD: solve failed");
  }
  const auto* values = static_cast<const double*>(impl_->x->x);
  x = Eigen::Map<const Eigen::VectorXd>(values, b.size());
}

double CholmodFactor::factor_nonzeros() const { return impl_->common.lnz; }
double CholmodFactor::factor_flops() const { return impl_->common.fl; }

}  // namespace spec2fab::fem

#pragma once
/// A thin owner of a CHOLMOD supernodal Cholesky factor for one sparsity
/// pattern: analyse once, refactorise numerically and solve many times,
/// reusing CHOLMOD's factor and solve workspaces (cholmod_solve2), so that a
/// repeated factorise-and-solve allocates nothing after the first.
/// Eigen's CholmodSupport wrapper allocates a result vector per solve.
/// The FEM's direct solver and elastic bound use it, and the optimal
/// transport's Newton steps (caustics), which analyse a new pattern each time.

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <cstddef>
#include <memory>

namespace spec2fab::fem {

class CholmodFactor {
 public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// Symbolic analysis (fill-reducing ordering, supernodes) of the lower
  /// triangle of `lower` (compressed); the matrix must keep its pattern.
  void analyze(const Matrix& lower);
  /// Numeric factorisation; false when the matrix is not positive definite.
  bool factorize(const Matrix& lower);
  /// Both of the above for a symmetric matrix given whole (both triangles,
  /// as products like AᵀA come out): its lower triangle is taken.
  bool analyze_and_factorize(const Eigen::SparseMatrix<double>& symmetric);
  /// x = A⁻¹ b (sizes n).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// X = A⁻¹ B for many right-hand sides at once (n × k, column-major):
  /// the supernodal solve then works on blocks (BLAS 3), several times
  /// faster per column than k single solves.
  void solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& x);

  /// Y = L⁻¹ P B, the forward half of a solve with A = PᵀLLᵀP: then
  /// bᵢᵀ A⁻¹ b_k = yᵢ · y_k. Half the work of X = A⁻¹ B for callers that
  /// need only such products (the elastic bound).
  void forward_solve(const Eigen::MatrixXd& b, Eigen::MatrixXd& y);

  double factor_nonzeros() const;  ///< nnz(L) from the analysis
  double factor_flops() const;     ///< flop count of one factorisation

 private:
  /// Solves the column-major n × k block at `b`; the result lives in the
  /// kept workspace until the next solve.
  const double* solve_columns(int system, const double* b, size_t rows, size_t columns);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spec2fab::fem

#pragma once
// Test problems with known optima, a finite-difference checker for analytic
// gradients and Jacobians, and building optimizers from JSON as users do.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/properties.h"
#include "tuning/optimizer.h"

namespace spec2fab::testing {

/// Builds an optimizer from a JSON snippet exactly as an experiment file
/// would, and insists that every key was read.
inline std::unique_ptr<Optimizer> optimizer_from(const std::string& json) {
  const Properties properties = Properties::parse(json, "t.json");
  std::unique_ptr<Optimizer> optimizer = build_optimizer(properties);
  properties.check_all_read();
  return optimizer;
}

/// Whether this build has the optimizer `json` names (the Ceres and NLopt
/// adapters are optional modules).
inline bool optimizer_built(const std::string& json) {
  return OptimizerRegistry::instance().contains(Properties::parse(json, "t.json").get<std::string>("type"));
}

/// The message of the InputError that `f` throws ("no error" otherwise).
inline std::string input_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

/// error = ½‖r(x)‖² with r and its Jacobian given by one function; offers
/// residuals and the gradient Jᵀr.
class LeastSquaresProblem : public Problem {
 public:
  /// residuals(x, r, J): fills r, and J (row-major m×n) when J is not empty.
  using Residuals =
      std::function<void(std::span<const double>, std::span<double>, std::span<double>)>;

  LeastSquaresProblem(std::vector<VariableDomain> domains, int residual_count, Residuals residuals)
      : domains_(std::move(domains)), m_(residual_count), residuals_(std::move(residuals)) {}

  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  bool has(Capability c) const override {
    return c == Capability::gradient || c == Capability::residuals || Problem::has(c);
  }
  int residual_count() const override { return m_; }
  void residuals(std::span<const double> x, std::span<double> r,
                 std::span<double> jacobian) override {
    residuals_(x, r, jacobian);
  }
  double error(std::span<const double> x) override {
    std::vector<double> r(static_cast<size_t>(m_));
    residuals_(x, r, {});
    double sum = 0;
    for (double v : r) sum += v * v;
    return 0.5 * sum;
  }
  double error_and_gradient(std::span<const double> x, std::span<double> gradient) override {
    const auto n = x.size(), m = static_cast<size_t>(m_);
    std::vector<double> r(m), jacobian(m * n);
    residuals_(x, r, jacobian);
    double sum = 0;
    std::fill(gradient.begin(), gradient.end(), 0.0);
    for (size_t k = 0; k < m; ++k) {
      sum += r[k] * r[k];
      for (size_t i = 0; i < n; ++i) gradient[i] += jacobian[k * n + i] * r[k];
    }
    return 0.5 * sum;
  }

 private:
  std::vector<VariableDomain> domains_;
  int m_;
  Residuals residuals_;
};

/// Chained Rosenbrock in residual form: for i = 0..n−2,
/// r_2i = 10(x_{i+1} − x_i²), r_2i+1 = 1 − x_i. For n = 2 this is the classic
/// Rosenbrock function; the minimum is 0 at x = (1, ..., 1).
inline LeastSquaresProblem rosenbrock(int n, double lower = -10, double upper = 10) {
  const auto residuals = [n](std::span<const double> x, std::span<double> r,
                             std::span<double> jacobian) {
    const auto un = static_cast<size_t>(n);
    if (!jacobian.empty()) std::fill(jacobian.begin(), jacobian.end(), 0.0);
    for (size_t i = 0; i + 1 < un; ++i) {
      r[2 * i] = 10 * (x[i + 1] - x[i] * x[i]);
      r[2 * i + 1] = 1 - x[i];
      if (!jacobian.empty()) {
        jacobian[2 * i * un + i] = -20 * x[i];
        jacobian[2 * i * un + i + 1] = 10;
        jacobian[(2 * i + 1) * un + i] = -1;
      }
    }
  };
  return LeastSquaresProblem(
      std::vector<VariableDomain>(static_cast<size_t>(n), VariableDomain::continuous(lower, upper)),
      2 * (n - 1), residuals);
}

/// Central-difference step for coordinate value v.
inline double difference_step(double v) { return 1e-6 * std::max(1.0, std::abs(v)); }

/// Compares error_and_gradient with central differences of error() at x:
/// |analytic − numeric| ≤ tolerance·max(1, max|analytic|) per component.
inline ::testing::AssertionResult gradient_matches(Problem& problem, std::vector<double> x,
                                                   double tolerance = 1e-6) {
  const size_t n = x.size();
  std::vector<double> analytic(n);
  const double error = problem.error_and_gradient(x, analytic);
  const double plain = problem.error(x);
  if (std::abs(error - plain) > tolerance * std::max(1.0, std::abs(plain))) {
    return ::testing::AssertionFailure()
           << "error_and_gradient returns " << error << " but error() " << plain;
  }
  double scale = 1;
  for (double g : analytic) scale = std::max(scale, std::abs(g));
  for (size_t i = 0; i < n; ++i) {
    const double h = difference_step(x[i]), saved = x[i];
    x[i] = saved + h;
    const double up = problem.error(x);
    x[i] = saved - h;
    const double down = problem.error(x);
    x[i] = saved;
    const double numeric = (up - down) / (2 * h);
    if (std::abs(numeric - analytic[i]) > tolerance * scale) {
      return ::testing::AssertionFailure() << "gradient component " << i << ": analytic "
                                           << analytic[i] << ", central difference " << numeric;
    }
  }
  return ::testing::AssertionSuccess();
}

/// Compares the analytic Jacobian of residuals() with central differences,
/// column by column, with the same tolerance rule as gradient_matches.
inline ::testing::AssertionResult jacobian_matches(Problem& problem, std::vector<double> x,
                                                   double tolerance = 1e-6) {
  const size_t n = x.size(), m = static_cast<size_t>(problem.residual_count());
  std::vector<double> r(m), analytic(m * n), up(m), down(m);
  problem.residuals(x, r, analytic);
  double scale = 1;
  for (double j : analytic) scale = std::max(scale, std::abs(j));
  for (size_t i = 0; i < n; ++i) {
    const double h = difference_step(x[i]), saved = x[i];
    x[i] = saved + h;
    problem.residuals(x, up, {});
    x[i] = saved - h;
    problem.residuals(x, down, {});
    x[i] = saved;
    for (size_t k = 0; k < m; ++k) {
      const double numeric = (up[k] - down[k]) / (2 * h);
      if (std::abs(numeric - analytic[k * n + i]) > tolerance * scale) {
        return ::testing::AssertionFailure()
               << "Jacobian entry (" << k << ", " << i << "): analytic " << analytic[k * n + i]
               << ", central difference " << numeric;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

/// A deterministic integer sequence for building test problems (a 64-bit
/// LCG), independent of the standard library.
class Sequence {
 public:
  explicit Sequence(unsigned long long seed) : state_(seed) {}
  int next(int modulus) {
    state_ = state_ * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<int>((state_ >> 33) % static_cast<unsigned long long>(modulus));
  }

 private:
  unsigned long long state_;
};

}  // namespace spec2fab::testing

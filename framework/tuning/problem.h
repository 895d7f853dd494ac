#pragma once
/// The only thing an optimizer sees (paper §6.2): a dimension, the domain of
/// each variable, error(x) — the paper's getError — and optional capabilities
/// that particular algorithms need. An optimizer asked to run on a problem
/// lacking a capability it needs refuses with a message naming both.

#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/parameter.h"

namespace spec2fab {

/// The domain of one variable: continuous in [lower, upper], discrete
/// (lower + k·step), or one of listed choices.
struct VariableDomain {
  ParameterKind kind = ParameterKind::continuous;
  double lower = 0, upper = 0, step = 0;
  std::vector<double> choices;  ///< for ParameterKind::choice

  static VariableDomain of(const Parameter& parameter);
  static VariableDomain continuous(double lower, double upper);
  static VariableDomain discrete(double lower, double upper, double step);
  static VariableDomain choice(std::vector<double> choices);

  /// Number of admissible values (0 for continuous variables).
  long long cardinality() const;
  double admissible(long long index) const;  ///< discrete/choice
  double nearest_admissible(double x) const;
  /// Index of the admissible value nearest x (discrete/choice).
  long long index_of(double x) const;
  /// Smallest and largest admissible values (for choices, over the list).
  double smallest() const;
  double largest() const;
};

enum class Capability {
  gradient,         ///< error_and_gradient
  residuals,        ///< residuals (+ Jacobian) for least squares
  lower_bound,      ///< lower_bound on partial discrete assignments
  neighbour_moves,  ///< swap_delta / commit_swap with neighbouring tuners
  discrete_only,    ///< every variable discrete or choice (not a method, a property)
};
std::string to_string(Capability capability);

class Problem {
 public:
  virtual ~Problem() = default;

  virtual int dimension() const = 0;
  virtual const VariableDomain& domain(int i) const = 0;
  /// The error at x (x.size() == dimension()); smaller is better.
  virtual double error(std::span<const double> x) = 0;

  virtual bool has(Capability capability) const;

  /// Error and its gradient at x (Capability::gradient).
  virtual double error_and_gradient(std::span<const double> x, std::span<double> gradient);

  /// Least squares (Capability::residuals): error(x) = ½‖r(x)‖².
  virtual int residual_count() const { return 0; }
  /// r(x) into `residuals`; when `jacobian` is not empty, ∂r/∂x row-major
  /// (residual_count × dimension).
  virtual void residuals(std::span<const double> x, std::span<double> residuals,
                         std::span<double> jacobian);

  /// A lower bound on error over every completion of a partial assignment in
  /// which variables 0..assigned-1 take x[0..assigned) (Capability::lower_bound).
  virtual double lower_bound(std::span<const double> x, int assigned);

  /// Neighbour moves (Capability::neighbour_moves): neighbouring tuners whose
  /// states this problem may exchange with its own.
  virtual int neighbour_count() const { return 0; }
  /// Change of the summed error of this problem (at x) and neighbour k if
  /// they exchanged states.
  virtual double swap_delta(std::span<const double> x, int neighbour);
  /// Performs that exchange: the neighbour takes x; returns this problem's new x.
  virtual std::vector<double> commit_swap(std::span<const double> x, int neighbour);
};

/// A Problem defined by a function, with optional gradient — for tests,
/// benchmarks and quick experiments.
class FunctionProblem : public Problem {
 public:
  using Error = std::function<double(std::span<const double>)>;
  using ErrorAndGradient = std::function<double(std::span<const double>, std::span<double>)>;

  FunctionProblem(std::vector<VariableDomain> domains, Error error,
                  ErrorAndGradient error_and_gradient = {});

  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  double error(std::span<const double> x) override { return error_(x); }
  bool has(Capability capability) const override;
  double error_and_gradient(std::span<const double> x, std::span<double> gradient) override;

 private:
  std::vector<VariableDomain> domains_;
  Error error_;
  ErrorAndGradient error_and_gradient_;
};

}  // namespace spec2fab

#include "tuning/problem.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace spec2fab {

VariableDomain VariableDomain::of(const Parameter& parameter) {
  VariableDomain d;
  d.kind = parameter.kind();
  d.lower = parameter.lower();
  d.upper = parameter.upper();
  d.step = parameter.step();
  d.choices = parameter.choices();
  return d;
}

VariableDomain VariableDomain::continuous(double lower, double upper) {
  VariableDomain d;
  d.lower = lower;
  d.upper = upper;
  return d;
}

VariableDomain VariableDomain::discrete(double lower, double upper, double step) {
  VariableDomain d;
  d.kind = ParameterKind::discrete;
  d.lower = lower;
  d.upper = upper;
  d.step = step;
  return d;
}

VariableDomain VariableDomain::choice(std::vector<double> choices) {
  VariableDomain d;
  d.kind = ParameterKind::choice;
  d.choices = std::move(choices);
  if (!d.choices.empty()) {
    d.lower = *std::min_element(d.choices.begin(), d.choices.end());
    d.upper = *std::max_element(d.choices.begin(), d.choices.end());
  }
  return d;
}

long long VariableDomain::cardinality() const {
  switch (kind) {
    case ParameterKind::continuous:
      return 0;
    case ParameterKind::discrete:
      // A zero step (or an empty range) admits the lower bound alone.
      if (!(step > 0) || !(upper > lower)) return 1;
      return static_cast<long long>(std::floor((upper - lower) / step + 1e-9)) + 1;
    case ParameterKind::choice:
      return static_cast<long long>(choices.size());
  }
  return 0;
}

double VariableDomain::admissible(long long index) const {
  if (kind == ParameterKind::choice) return choices.at(static_cast<size_t>(index));
  return lower + static_cast<double>(index) * step;
}

double VariableDomain::nearest_admissible(double x) const {
  switch (kind) {
    case ParameterKind::continuous:
      return std::clamp(x, lower, upper);
    case ParameterKind::discrete:
      return admissible(index_of(x));
    case ParameterKind::choice:
      return choices.empty() ? x : admissible(index_of(x));
  }
  return x;
}

long long VariableDomain::index_of(double x) const {
  if (std::isnan(x)) return 0;
  if (kind == ParameterKind::discrete) {
    if (!(step > 0)) return 0;
    const double k = std::clamp((x - lower) / step, 0.0, static_cast<double>(cardinality() - 1));
    return std::llround(k);
  }
  long long best = 0;
  for (size_t i = 1; i < choices.size(); ++i) {
    if (std::abs(choices[i] - x) < std::abs(choices[static_cast<size_t>(best)] - x)) {
      best = static_cast<long long>(i);
    }
  }
  return best;
}

double VariableDomain::smallest() const {
  if (kind == ParameterKind::choice && !choices.empty()) {
    return *std::min_element(choices.begin(), choices.end());
  }
  return lower;
}

double VariableDomain::largest() const {
  if (kind == ParameterKind::choice && !choices.empty()) {
    return *std::max_element(choices.begin(), choices.end());
  }
  if (kind == ParameterKind::discrete) return admissible(cardinality() - 1);
  return upper;
}

std::string to_string(Capability capability) {
  switch (capability) {
    case Capability::gradient:
      return "a gradient";
    case Capability::residuals:
      return "residuals";
    case Capability::lower_bound:
      return "a lower bound on partial assignments";
    case Capability::neighbour_moves:
      return "neighbour moves";
    case Capability::discrete_only:
      return "only discrete or choice variables";
  }
  return "?";
}

bool Problem::has(Capability capability) const {
  if (capability != Capability::discrete_only) return false;
  for (int i = 0; i < dimension(); ++i) {
    if (domain(i).kind == ParameterKind::continuous) return false;
  }
  return true;
}

namespace {
[[noreturn]] void missing(Capability capability) {
  throw std::logic_error("Problem: called without " + to_string(capability));
}
}  // namespace

double Problem::error_and_gradient(std::span<const double>, std::span<double>) {
  missing(Capability::gradient);
}
void Problem::residuals(std::span<const double>, std::span<double>, std::span<double>) {
  missing(Capability::residuals);
}
double Problem::lower_bound(std::span<const double>, int) { missing(Capability::lower_bound); }
double Problem::swap_delta(std::span<const double>, int) { missing(Capability::neighbour_moves); }
std::vector<double> Problem::commit_swap(std::span<const double>, int) {
  missing(Capability::neighbour_moves);
}

FunctionProblem::FunctionProblem(std::vector<VariableDomain> domains, Error error,
                                 ErrorAndGradient error_and_gradient)
    : domains_(std::move(domains)),
      error_(std::move(error)),
      error_and_gradient_(std::move(error_and_gradient)) {}

bool FunctionProblem::has(Capability capability) const {
  if (capability == Capability::gradient) return static_cast<bool>(error_and_gradient_);
  return Problem::has(capability);
}

double FunctionProblem::error_and_gradient(std::span<const double> x, std::span<double> gradient) {
  if (!error_and_gradient_) return Problem::error_and_gradient(x, gradient);
  return error_and_gradient_(x, gradient);
}

}  // namespace spec2fab

#pragma once
/// A tunable value of a reducer node (the paper's Parameter class).
///
/// A parameter is continuous (any value in [lower, upper]), discrete (values
/// lower + k·step), or a choice (one of a list of values, e.g. material ids,
/// with labels for people). It is free (a tuner may change it) or fixed.

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace spec2fab {

class Properties;

enum class ParameterKind { continuous, discrete, choice };

class Parameter {
 public:
  static Parameter continuous(double value, double lower, double upper, bool free = false);
  static Parameter discrete(double value, double lower, double upper, double step,
                            bool free = false);
  static Parameter choice(double value, std::vector<double> choices,
                          std::vector<std::string> labels, bool free = false);

  ParameterKind kind() const { return kind_; }
  double value() const { return value_; }
  double lower() const { return lower_; }
  double upper() const { return upper_; }
  double step() const { return step_; }  ///< 0 for continuous parameters
  const std::vector<double>& choices() const;
  const std::vector<std::string>& labels() const;
  bool is_free() const { return free_; }
  void set_free(bool free) { free_ = free; }

  /// Number of admissible values for discrete and choice parameters; 0 for continuous ones.
  long long cardinality() const;
  /// The admissible value closest to `x` (clamped to bounds, snapped to the step/choices).
  double nearest_admissible(double x) const;
  /// Sets the value, snapped to the nearest admissible one.
  void set(double x) { value_ = nearest_admissible(x); }
  /// The i-th admissible value of a discrete/choice parameter.
  double admissible(long long index) const;
  /// Index of the current value among the admissible ones (discrete/choice).
  long long index() const;
  /// Label of the current value ("" for numeric parameters).
  std::string label() const;

 private:
  ParameterKind kind_ = ParameterKind::continuous;
  double value_ = 0, lower_ = 0, upper_ = 0, step_ = 0;
  // Shared, because a tree may hold tens of thousands of copies of one choice
  // list (a material choice per column).
  struct ChoiceSet {
    std::vector<double> values;
    std::vector<std::string> labels;
  };
  std::shared_ptr<const ChoiceSet> choice_set_;
  bool free_ = false;
};

/// Reads a numeric parameter from JSON. Accepted forms:
///   3.0                                            fixed value
///   {"value": 3.0, "min": 1, "max": 5}             free, continuous
///   {"value": 3.0, "min": 1, "max": 5, "step": 0.5, "free": false}
///   {"value": 0.27, "choices": [0.135, 0.27, 0.54]}  free, one of a list
/// `default_lower`/`default_upper` bound values given in the plain form and
/// are the limits no bound may exceed.
Parameter read_numeric_parameter(const Properties& properties, const std::string& key,
                                 double fallback, double default_lower, double default_upper);

/// Writes a parameter in the form read_numeric_parameter reads.
nlohmann::json numeric_parameter_to_json(const Parameter& parameter);

}  // namespace spec2fab

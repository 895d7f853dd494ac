#include "core/parameter.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "core/properties.h"

namespace spec2fab {

Parameter Parameter::continuous(double value, double lower, double upper, bool free) {
  Parameter p;
  p.kind_ = ParameterKind::continuous;
  p.lower_ = lower;
  p.upper_ = upper;
  p.free_ = free;
  p.value_ = p.nearest_admissible(value);
  return p;
}

Parameter Parameter::discrete(double value, double lower, double upper, double step, bool free) {
  Parameter p;
  p.kind_ = ParameterKind::discrete;
  p.lower_ = lower;
  p.upper_ = upper;
  p.step_ = step;
  p.free_ = free;
  p.value_ = p.nearest_admissible(value);
  return p;
}

Parameter Parameter::choice(double value, std::vector<double> choices,
                            std::vector<std::string> labels, bool free) {
  Parameter p;
  p.kind_ = ParameterKind::choice;
  labels.resize(choices.size());
  p.lower_ = choices.empty() ? 0 : *std::min_element(choices.begin(), choices.end());
  p.upper_ = choices.empty() ? 0 : *std::max_element(choices.begin(), choices.end());
  p.choice_set_ = std::make_shared<const ChoiceSet>(ChoiceSet{std::move(choices), std::move(labels)});
  p.free_ = free;
  p.value_ = p.nearest_admissible(value);
  return p;
}

const std::vector<double>& Parameter::choices() const {
  static const std::vector<double> none;
  return choice_set_ ? choice_set_->values : none;
}

const std::vector<std::string>& Parameter::labels() const {
  static const std::vector<std::string> none;
  return choice_set_ ? choice_set_->labels : none;
}

long long Parameter::cardinality() const {
  switch (kind_) {
    case ParameterKind::continuous:
      return 0;
    case ParameterKind::discrete:
      return static_cast<long long>(std::floor((upper_ - lower_) / step_ + 1e-9)) + 1;
    case ParameterKind::choice:
      return static_cast<long long>(choices().size());
  }
  return 0;
}

double Parameter::admissible(long long index) const {
  if (kind_ == ParameterKind::choice) return choices().at(static_cast<size_t>(index));
  return lower_ + static_cast<double>(index) * step_;
}

long long Parameter::index() const {
  if (kind_ == ParameterKind::choice) {
    const auto& values = choices();
    return std::find(values.begin(), values.end(), value_) - values.begin();
  }
  if (kind_ == ParameterKind::discrete) return std::llround((value_ - lower_) / step_);
  return 0;
}

double Parameter::nearest_admissible(double x) const {
  switch (kind_) {
    case ParameterKind::continuous:
      return std::clamp(x, lower_, upper_);
    case ParameterKind::discrete: {
      const long long last = cardinality() - 1;
      const long long k = std::clamp<long long>(std::llround((x - lower_) / step_), 0, last);
      return admissible(k);
    }
    case ParameterKind::choice: {
      const auto& values = choices();
      if (values.empty()) return x;
      double best = values.front();
      for (double c : values) {
        if (std::abs(c - x) < std::abs(best - x)) best = c;
      }
      return best;
    }
  }
  return x;
}

std::string Parameter::label() const {
  if (kind_ != ParameterKind::choice) return {};
  const long long i = index();
  const auto& names = labels();
  return i < static_cast<long long>(names.size()) ? names[static_cast<size_t>(i)] : "";
}

Parameter read_numeric_parameter(const Properties& properties, const std::string& key,
                                 double fallback, double default_lower, double default_upper) {
  auto check_range = [&](double x, const char* what) {
    if (x < default_lower || x > default_upper) {
      std::ostringstream message;
      message << what << " " << x << " is outside [" << default_lower << ", " << default_upper
              << "]";
      properties.fail(key, message.str());
    }
  };
  if (!properties.has(key)) return Parameter::continuous(fallback, default_lower, default_upper);
  if (!properties.peek(key).is_object()) {
    const double value = properties.get<double>(key);
    check_range(value, "value");
    return Parameter::continuous(value, default_lower, default_upper);
  }
  const Properties spec = properties.object(key);
  const double value = spec.get<double>("value");
  if (spec.has("choices")) {
    if (spec.has("min") || spec.has("max") || spec.has("step")) {
      spec.fail("choices", "give \"choices\" or a range (min, max, step), not both");
    }
    const auto choices = spec.get<std::vector<double>>("choices");
    if (choices.empty()) spec.fail("choices", "no values to choose from");
    std::vector<std::string> labels;
    for (double c : choices) {
      check_range(c, "choice");
      labels.push_back(fmt::format("{:g}", c));
    }
    if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
      spec.fail("value", "is not among the choices");
    }
    return Parameter::choice(value, choices, std::move(labels), spec.get<bool>("free", true));
  }
  const double lower = spec.get<double>("min", default_lower);
  const double upper = spec.get<double>("max", default_upper);
  const bool free = spec.get<bool>("free", true);
  check_range(lower, "min");
  check_range(upper, "max");
  if (lower > upper) properties.fail(key, "min is greater than max");
  if (value < lower || value > upper) properties.fail(key, "value lies outside [min, max]");
  if (spec.has("step")) {
    const double step = spec.get<double>("step");
    if (!(step > 0)) spec.fail("step", "step must be positive");
    return Parameter::discrete(value, lower, upper, step, free);
  }
  return Parameter::continuous(value, lower, upper, free);
}

nlohmann::json numeric_parameter_to_json(const Parameter& parameter) {
  if (!parameter.is_free()) return parameter.value();
  if (parameter.kind() == ParameterKind::choice) {
    return {{"value", parameter.value()}, {"choices", parameter.choices()}};
  }
  nlohmann::json out = {{"value", parameter.value()},
                        {"min", parameter.lower()},
                        {"max", parameter.upper()}};
  if (parameter.kind() == ParameterKind::discrete) out["step"] = parameter.step();
  return out;
}

}  // namespace spec2fab

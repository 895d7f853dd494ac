#pragma once
/// Options declared once. A part's options struct lists every option in one
/// place — name, type, default (the member's initial value), range or
/// choices, one line of meaning — and reading them from JSON, checking a
/// struct built in C++, and documenting them all come from that list:
///
///   struct Options {
///     int iterations = 1000;
///     double cooling = 0.999;
///     std::string schedule = "exponential";
///     template <class Declare, class Self> static void declare(Declare& d, Self& o) {
///       d.number(o.iterations, "iterations", Range::at_least(1), "moves proposed");
///       d.number(o.cooling, "cooling", Range::open_closed(0, 1), "alpha of the exponential schedule");
///       d.choice(o.schedule, "schedule", {"exponential", "linear"}, "how the temperature falls");
///     }
///     bool IsValid(std::string* why) const { return options_valid(*this, why); }
///   };
///
///   Options o = read_options<Options>(properties);  // errors name the file and JSON path
///   TypeDoc doc{summary, option_docs<Options>(), example};  // `spec2fab list --verbose`, docs/parts.md
///
/// A constraint between options (one at least another) goes in an optional
/// `bool check(std::string* why) const`, which reading and IsValid also run.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "core/properties.h"
#include "core/registry.h"
#include "core/strings.h"

namespace spec2fab {

/// Where a number may lie; either end open or closed, or absent.
struct Range {
  double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
  bool open_min = false, open_max = false;

  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }
  static Range open_closed(double lo, double hi) { return {lo, hi, true, false}; }
  static Range at_least(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, false}; }
  static Range above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true, false}; }
  static Range any() { return {}; }

  bool contains(double v) const {
    return std::isfinite(v) && (open_min ? v > min : v >= min) && (open_max ? v < max : v <= max);
  }
  /// "in (0, 1]", "at least 1", "above 0", "" (any finite number).
  std::string text() const {
    const bool low = std::isfinite(min), high = std::isfinite(max);
    if (low && high)
      return fmt::format("in {}{:g}, {:g}{}", open_min ? '(' : '[', min, max, open_max ? ')' : ']');
    if (low) return fmt::format("{} {:g}", open_min ? "above" : "at least", min);
    if (high) return fmt::format("{} {:g}", open_max ? "below" : "at most", max);
    return "";
  }
};

namespace options_detail {

template <class T>
std::string default_text(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_arithmetic_v<T>) {
    return fmt::format("{:g}", static_cast<double>(value));
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "\"" + value + "\"";
  } else {
    std::vector<std::string> items;
    for (const auto& item : value) items.push_back(default_text(item));
    return "[" + join(items) + "]";
  }
}

template <class T>
std::string type_text() {
  if constexpr (std::is_same_v<T, bool>) return "bool";
  else if constexpr (std::is_integral_v<T>) return "integer";
  else if constexpr (std::is_arithmetic_v<T>) return "number";
  else if constexpr (std::is_same_v<T, std::string>) return "string";
  else return "array";
}

template <class O>
concept HasCheck = requires(const O& o, std::string* why) {
  { o.check(why) } -> std::convertible_to<bool>;
};

/// Reads each option from JSON (absent: the default stays).
class Reader {
 public:
  explicit Reader(const Properties& properties) : p_(properties) {}
  template <class T>
  void number(T& value, const char* name, Range range, const char*) {
    value = p_.get<T>(name, value);
    if (!range.contains(static_cast<double>(value)))
      p_.fail(name, fmt::format("{:g} is not {}", static_cast<double>(value), range.text()));
  }
  void choice(std::string& value, const char* name, const std::vector<std::string>& choices, const char*) {
    value = p_.get<std::string>(name, value);
    if (std::find(choices.begin(), choices.end(), value) == choices.end())
      p_.fail(name, "unknown value '" + value + "'" + did_you_mean(value, choices) + " (known: " + join(choices) + ")");
  }
  template <class T>
  void value(T& value, const char* name, const char*) {
    value = p_.get<T>(name, value);
  }

 private:
  const Properties& p_;
};

/// Finds the first option out of its range or choices (a struct built in C++).
class Checker {
 public:
  std::string problem;
  template <class T>
  void number(const T& value, const char* name, Range range, const char*) {
    if (problem.empty() && !range.contains(static_cast<double>(value)))
      problem = fmt::format("{}: {:g} is not {}", name, static_cast<double>(value), range.text());
  }
  void choice(const std::string& value, const char* name, const std::vector<std::string>& choices, const char*) {
    if (problem.empty() && std::find(choices.begin(), choices.end(), value) == choices.end())
      problem = std::string(name) + ": unknown value '" + value + "'" + did_you_mean(value, choices) +
                " (known: " + join(choices) + ")";
  }
  template <class T>
  void value(const T&, const char*, const char*) {}
};

/// The options as documentation rows: name, type, default, meaning.
class Documenter {
 public:
  std::vector<PropertyDoc> rows;
  template <class T>
  void number(const T& value, const char* name, Range range, const char* meaning) {
    const std::string bound = range.text();
    rows.push_back({name, type_text<T>() + (bound.empty() ? "" : " " + bound), default_text(value), meaning});
  }
  void choice(const std::string& value, const char* name, const std::vector<std::string>& choices,
              const char* meaning) {
    rows.push_back({name, join(choices, " | "), default_text(value), meaning});
  }
  template <class T>
  void value(const T& value, const char* name, const char* meaning) {
    rows.push_back({name, type_text<T>(), default_text(value), meaning});
  }
};

}  // namespace options_detail

/// Whether a struct of options holds (every range and choice, then check()).
template <class O>
bool options_valid(const O& options, std::string* why) {
  options_detail::Checker checker;
  O::declare(checker, options);
  if (checker.problem.empty() && [&] {
        if constexpr (options_detail::HasCheck<O>) return !options.check(&checker.problem);
        return false;
      }()) {
    if (checker.problem.empty()) checker.problem = "options are inconsistent";
  }
  if (checker.problem.empty()) return true;
  if (why) *why = checker.problem;
  return false;
}

/// The defaults, overridden by what `properties` holds; throws InputError at
/// the offending key (or at the object, for a constraint between options).
template <class O>
O read_options(const Properties& properties) {
  O options;
  options_detail::Reader reader(properties);
  O::declare(reader, options);
  if constexpr (options_detail::HasCheck<O>) {
    std::string why;
    if (!options.check(&why)) properties.fail(why);
  }
  return options;
}

/// The options' rows for a part's TypeDoc.
template <class O>
std::vector<PropertyDoc> option_docs() {
  const O defaults;
  options_detail::Documenter documenter;
  O::declare(documenter, defaults);
  return documenter.rows;
}

}  // namespace spec2fab

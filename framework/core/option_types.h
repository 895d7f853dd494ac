#pragma once
/// The small types options are declared with (core/options.h): where a
/// number may lie, a documented default another option sets, the sentinel
/// of a number not given, and numbers written as a person writes them.

#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>

namespace spec2fab {

/// A number as a person writes it: 1000000, 0.999, 1e-5, 1e12 (not 1e+06,
/// 1e-05, 1000000000000), and exactly (4294967295).
inline std::string number_text(double v) {
  std::string text = fmt::format("{:.15g}", v);
  if (const std::string shorter = fmt::format("{:g}", v); text.size() > 8 && std::stod(shorter) == v) text = shorter;
  const size_t e = text.find('e');
  if (e == std::string::npos) return text;
  std::string exponent = text.substr(e + 1);
  const bool negative = exponent[0] == '-';
  exponent.erase(0, exponent.find_first_not_of("+-0"));
  return text.substr(0, e + 1) + (negative ? "-" : "") + exponent;
}

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
      return fmt::format("in {}{}, {}{}", open_min ? '(' : '[', number_text(min), number_text(max), open_max ? ')' : ']');
    if (low) return fmt::format("{} {}", open_min ? "above" : "at least", number_text(min));
    if (high) return fmt::format("{} {}", open_max ? "below" : "at most", number_text(max));
    return "";
  }
};

/// For a check(): `name` = `value` may not exceed `bound_name` = `bound`
/// (a sampling step and the depth it samples).
inline bool at_most(double value, const char* name, double bound, const char* bound_name, std::string* why) {
  if (value <= bound) return true;
  *why = std::string(name) + ": " + number_text(value) + " is more than " + bound_name + " (" + number_text(bound) + ")";
  return false;
}

/// The documented default of an option whose default another option sets.
struct Default {
  const char* text;
};

/// The sentinel of a number with a Default: not given.
inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

}  // namespace spec2fab

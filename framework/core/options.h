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
/// `bool check(std::string* why) const`, which reading and IsValid also run;
/// a reason that starts "key: " is reported at that key.
///
/// number() also takes arrays (each element in the range); required() has no
/// default; an option whose default depends on others (rays: twice the image)
/// keeps a sentinel and says so in the docs with Default{"2 × image"}. A name
/// ending in _mm is documented as millimetres. file() is a required path to
/// an existing file, relative to the document's folder (optional when the
/// member is a std::optional). parameter() is a
/// node's tunable Parameter: its default value and limits are the member's.
///
/// custom() is for a value whose type reads and documents itself (a child
/// node, a material): it has read(properties, name, context),
/// type_text() and default_text(). read_options(properties, context)
/// hands the context to it, and to nested structs.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "core/properties.h"
#include "core/parameter.h"
#include "core/registry.h"
#include "core/strings.h"
#include "core/option_types.h"
#include "core/options_detail.h"  // the machinery: Reader, Checker, Documenter

namespace spec2fab {

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

/// Options a translator composes in C++ (typed parts, not JSON) must hold
/// what their declaration says; when they do not, the translator has a bug —
/// std::logic_error naming `part` and the option — never an error in the
/// user's input. Returns the options, for use in a constructor's initialiser.
template <class O>
const O& require_valid(const O& options, std::string_view part) {
  std::string why;
  if (!options_valid(options, &why))
    throw std::logic_error(std::string(part) + ": options built in C++ do not hold: " + why);
  return options;
}

/// The defaults, overridden by what `properties` holds; throws InputError at
/// the offending key (or at the object, for a constraint between options).
template <class O, class Context = options_detail::NoContext>
void read_options_into(O& options, const Properties& properties, const Context& context = {}) {
  options_detail::Reader<Context> reader(properties, context);
  O::declare(reader, options);
  if constexpr (options_detail::HasCheck<O>) {
    std::string why;
    if (!options.check(&why)) options_detail::fail_at_key(properties, why);
  }
}

template <class O, class Context = options_detail::NoContext>
O read_options(const Properties& properties, const Context& context = {}) {
  O options;
  read_options_into(options, properties, context);
  return options;
}

/// The options' rows for a part's TypeDoc; `defaults` for a struct whose
/// members name its keys (a piece whose keys a translator renames).
template <class O>
std::vector<PropertyDoc> option_docs(const O& defaults = O{}) {
  options_detail::Documenter documenter;
  O::declare(documenter, defaults);
  return documenter.rows;
}

/// A piece's rows where a translator finds them ("goal." + key).
inline std::vector<PropertyDoc> prefixed(std::vector<PropertyDoc> rows, const std::string& prefix) {
  for (PropertyDoc& row : rows) row.name = prefix + row.name;
  return rows;
}

/// Appends rows to a TypeDoc's.
inline void append(std::vector<PropertyDoc>& to, std::vector<PropertyDoc> rows) {
  for (PropertyDoc& row : rows) to.push_back(std::move(row));
}

/// For a range that other options or the experiment set (heights within the
/// solid): fails at `name` as a declared range would.
inline void require_in(const Properties& properties, const char* name, double value, Range range) {
  if (!range.contains(value)) properties.fail(name, number_text(value) + " is not " + range.text());
}

namespace options_detail {

template <class O>
std::string keys_text() {
  std::vector<std::string> keys;
  for (const PropertyDoc& row : option_docs<O>()) keys.push_back(row.name);
  std::string text = "{";  // appended: GCC 12 warns (-Wrestrict) wrongly on "{" + …
  text += join(keys);
  text += "}";
  return text;
}

/// A nested options struct; one with a `where` member learns its JSON place.
template <class O, class Context>
O read_nested(const Properties& properties, const Context& context) {
  O options = read_options<O>(properties, context);
  if constexpr (HasWhere<O>) options.where = properties.where();
  return options;
}

}  // namespace options_detail

}  // namespace spec2fab

#pragma once
/// How core/options.h reads, checks and documents a declared options
/// struct: the Reader, Checker and Documenter its declare() is called with.
/// Include core/options.h, not this.

#include <algorithm>
#include <array>
#include <concepts>
#include <filesystem>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "core/option_types.h"
#include "core/parameter.h"
#include "core/properties.h"
#include "core/registry.h"
#include "core/strings.h"

namespace spec2fab {
namespace options_detail {

template <class T>
struct is_std_array : std::false_type {};
template <class T, size_t N>
struct is_std_array<std::array<T, N>> : std::true_type {};
template <class T>
struct is_std_vector : std::false_type {};
template <class T>
struct is_std_vector<std::vector<T>> : std::true_type {};
template <class T>
inline constexpr bool is_sequence_v = is_std_array<T>::value || is_std_vector<T>::value;

/// Each number of a value (itself, or an array's elements).
template <class T, class F>
void for_each_number(const T& value, F&& f) {
  if constexpr (is_sequence_v<T>) {
    for (const auto& item : value) for_each_number(item, f);
  } else {
    f(static_cast<double>(value));
  }
}

template <class T>
std::string default_text(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_arithmetic_v<T>) {
    return number_text(static_cast<double>(value));
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "\"" + value + "\"";
  } else {
    std::vector<std::string> items;
    for (const auto& item : value) items.push_back(default_text(item));
    std::string text = "[";  // appended: GCC 12 warns (-Wrestrict) wrongly on "[" + …
    text += join(items);
    text += "]";
    return text;
  }
}

template <class T>
std::string type_text() {
  if constexpr (std::is_same_v<T, bool>) {
    return "bool";
  } else if constexpr (std::is_integral_v<T>) {
    return "integer";
  } else if constexpr (std::is_arithmetic_v<T>) {
    return "number";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "string";
  } else if constexpr (std::is_same_v<T, Parameter>) {
    return "parameter";
  } else if constexpr (is_std_array<T>::value) {
    const std::vector<std::string> items(std::tuple_size_v<T>, type_text<typename T::value_type>());
    // Appended, not "[" + …: GCC 12 warns (-Wrestrict) wrongly on that form.
    std::string text = "[";
    text += join(items);
    text += "]";
    return text;
  } else if constexpr (is_std_vector<T>::value) {
    std::string text = "array of ";
    text += type_text<typename T::value_type>();
    if constexpr (!is_sequence_v<typename T::value_type>) text += "s";
    return text;
  } else {
    return "array";
  }
}

/// The type as documented: a name ending in _mm is in millimetres.
template <class T>
std::string full_type_text(const char* name) {
  const std::string_view n(name);
  return type_text<T>() + (n.size() > 3 && n.substr(n.size() - 3) == "_mm" ? " (mm)" : "");
}

template <class T>
std::string range_problem(const T& value, Range range) {
  std::string problem;
  for_each_number(value, [&](double v) {
    if (problem.empty() && !range.contains(v)) problem = number_text(v) + " is not " + range.text();
  });
  return problem;
}

template <class O>
concept HasCheck = requires(const O& o, std::string* why) {
  { o.check(why) } -> std::convertible_to<bool>;
};

template <class O>
concept HasWhere = requires(O& o) { o.where = std::string(); };

/// "{min, max, force_n}": the keys of a nested options struct.
template <class O>
std::string keys_text();

/// What reading hands to custom() values: nothing, unless the reader of a
/// part gives a context (a node's palette).
struct NoContext {};

template <class O, class Context>
O read_nested(const Properties& properties, const Context& context);

/// The type of a parameter() as documented: "parameter (mm) in [0, 1000]".
inline std::string parameter_type_text(const char* name, Range limits) {
  const std::string bound = limits.text();
  return full_type_text<Parameter>(name) + (bound.empty() ? "" : " " + bound);
}

/// A check()'s "key: problem" fails at that key's JSON path when the object
/// holds the key; any other message, at the object.
[[noreturn]] inline void fail_at_key(const Properties& properties, const std::string& why) {
  const size_t colon = why.find(": ");
  if (colon != std::string::npos && colon > 0) {
    const std::string key = why.substr(0, colon);
    const bool plain = std::all_of(key.begin(), key.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    });
    if (plain && properties.has(key)) properties.fail(key, why.substr(colon + 2));
  }
  properties.fail(why);
}

/// Reads each option from JSON (absent: the default stays).
template <class Context = NoContext>
class Reader {
 public:
  Reader(const Properties& properties, const Context& context) : p_(properties), context_(context) {}
  template <class T>
  void number(T& value, const char* name, Range range, const char*) {
    value = p_.get<T>(name, value);
    if (const std::string problem = range_problem(value, range); !problem.empty()) p_.fail(name, problem);
  }
  template <class T>
  void number(T& value, const char* name, Range range, const char* meaning, Default) {
    if (p_.has(name)) number(value, name, range, meaning);
  }
  template <class T>
  void required(T& value, const char* name, Range range, const char*) {
    value = p_.get<T>(name);
    if (const std::string problem = range_problem(value, range); !problem.empty()) p_.fail(name, problem);
  }
  template <class T>
  void required(T& value, const char* name, const char*) {
    value = p_.get<T>(name);
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
  /// A value whose default another option or the experiment sets.
  template <class T>
  void value(T& value, const char* name, const char*, Default) {
    value = p_.get<T>(name, value);
  }
  template <class T>
  void value(std::optional<T>& value, const char* name, const char*, Default) {
    if (p_.has(name)) value = p_.get<T>(name);
  }
  void file(std::filesystem::path& value, const char* name, const char*) { value = p_.existing_file(name); }
  void file(std::optional<std::filesystem::path>& value, const char* name, const char*) {
    if (p_.has(name)) value = p_.existing_file(name);
  }
  /// An array of objects, each an options struct of its own.
  template <class E>
  void objects(std::vector<E>& value, const char* name, const char*) {
    if (!p_.has(name)) return;
    value.clear();
    for (const Properties& item : p_.objects(name)) value.push_back(read_nested<E>(item, context_));
  }
  /// An optional object.
  template <class E>
  void object(std::optional<E>& value, const char* name, const char*) {
    if (const auto item = p_.optional_object(name)) value = read_nested<E>(*item, context_);
  }
  /// A tunable parameter; a plain number is fixed, limits as the default's.
  void parameter(Parameter& value, const char* name, const char*) {
    value = read_numeric_parameter(p_, name, value.value(), value.lower(), value.upper());
  }
  /// The same, absent unless given.
  void parameter(std::optional<Parameter>& value, const char* name, Range limits, const char*, Default) {
    if (p_.has(name)) value = read_numeric_parameter(p_, name, 0, limits.min, limits.max);
  }
  template <class T>
  void custom(T& value, const char* name, const char*) {
    value.read(p_, name, context_);
  }

 private:
  const Properties& p_;
  const Context& context_;
};

/// Finds the first option out of its range or choices (a struct built in C++).
class Checker {
 public:
  std::string problem;
  template <class T>
  void number(const T& value, const char* name, Range range, const char*) {
    if (const std::string p = range_problem(value, range); problem.empty() && !p.empty())
      problem = std::string(name) + ": " + p;
  }
  template <class T>
  void number(const T&, const char*, Range, const char*, Default) {}  // the sentinel is not checked
  template <class T>
  void required(const T& value, const char* name, Range range, const char* meaning) {
    number(value, name, range, meaning);
  }
  template <class T>
  void required(const T&, const char*, const char*) {}
  void choice(const std::string& value, const char* name, const std::vector<std::string>& choices, const char*) {
    if (problem.empty() && std::find(choices.begin(), choices.end(), value) == choices.end())
      problem = std::string(name) + ": unknown value '" + value + "'" + did_you_mean(value, choices) +
                " (known: " + join(choices) + ")";
  }
  template <class T>
  void value(const T&, const char*, const char*) {}
  template <class T>
  void value(const T&, const char*, const char*, Default) {}
  void file(const std::filesystem::path&, const char*, const char*) {}
  void file(const std::optional<std::filesystem::path>&, const char*, const char*) {}
  template <class E>
  void objects(const std::vector<E>&, const char*, const char*) {}
  template <class E>
  void object(const std::optional<E>&, const char*, const char*) {}
  template <class P>
  void parameter(const P&, const char*, const char*) {}
  template <class P>
  void parameter(const P&, const char*, Range, const char*, Default) {}
  template <class T>
  void custom(const T&, const char*, const char*) {}
};

/// The options as documentation rows: name, type, default, meaning.
class Documenter {
 public:
  std::vector<PropertyDoc> rows;
  template <class T>
  void number(const T& value, const char* name, Range range, const char* meaning) {
    rows.push_back({name, typed(value, name, range), default_text(value), meaning});
  }
  template <class T>
  void number(const T& value, const char* name, Range range, const char* meaning, Default fallback) {
    rows.push_back({name, typed(value, name, range), fallback.text, meaning});
  }
  template <class T>
  void required(const T& value, const char* name, Range range, const char* meaning) {
    rows.push_back({name, typed(value, name, range), "required", meaning});
  }
  template <class T>
  void required(const T&, const char* name, const char* meaning) {
    rows.push_back({name, full_type_text<T>(name), "required", meaning});
  }
  void choice(const std::string& value, const char* name, const std::vector<std::string>& choices,
              const char* meaning) {
    rows.push_back({name, join(choices, " | "), default_text(value), meaning});
  }
  template <class T>
  void value(const T& value, const char* name, const char* meaning) {
    rows.push_back({name, full_type_text<T>(name), default_text(value), meaning});
  }
  template <class T>
  void value(const T&, const char* name, const char* meaning, Default fallback) {
    rows.push_back({name, full_type_text<T>(name), fallback.text, meaning});
  }
  template <class T>
  void value(const std::optional<T>&, const char* name, const char* meaning, Default fallback) {
    rows.push_back({name, full_type_text<T>(name), fallback.text, meaning});
  }
  void file(const std::filesystem::path&, const char* name, const char* meaning) {
    rows.push_back({name, "file", "required", meaning});
  }
  void file(const std::optional<std::filesystem::path>&, const char* name, const char* meaning) {
    rows.push_back({name, "file", "-", meaning});
  }
  template <class E>
  void objects(const std::vector<E>&, const char* name, const char* meaning) {
    rows.push_back({name, "array of " + keys_text<E>(), "[]", meaning});
  }
  template <class E>
  void object(const std::optional<E>&, const char* name, const char* meaning) {
    rows.push_back({name, keys_text<E>(), "none", meaning});
  }
  void parameter(const Parameter& value, const char* name, const char* meaning) {
    rows.push_back({name, parameter_type_text(name, Range::closed(value.lower(), value.upper())),
                    number_text(value.value()), meaning});
  }
  void parameter(const std::optional<Parameter>&, const char* name, Range limits, const char* meaning,
                 Default absent) {
    rows.push_back({name, parameter_type_text(name, limits), absent.text, meaning});
  }
  template <class T>
  void custom(const T& value, const char* name, const char* meaning) {
    rows.push_back({name, value.type_text(), value.default_text(), meaning});
  }

 private:
  template <class T>
  static std::string typed(const T&, const char* name, Range range) {
    const std::string bound = range.text();
    return full_type_text<T>(name) + (bound.empty() ? "" : " " + bound);
  }
};

}  // namespace options_detail
}  // namespace spec2fab

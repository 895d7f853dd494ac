#pragma once
/// Report sections declared once, as options are (core/options.h). A part's
/// section of result.json is a struct that lists its fields — name and one
/// line of meaning — and writing it, reading it back and documenting it all
/// come from that list:
///
///   struct TreeSummary {
///     std::size_t nodes = 0, parameters = 0;
///     template <class Fields, class Self> static void fields(Fields& f, Self& s) {
///       f(s.nodes, "nodes", "nodes of the reducer tree");
///       f(s.parameters, "parameters", "its parameters, fixed and free");
///     }
///   };
///
///   nlohmann::json j = write_section(summary);             // result.json
///   TreeSummary back = read_section<TreeSummary>(properties);  // errors name file and JSON path
///   std::vector<ReportFieldDoc> rows = section_docs<TreeSummary>();
///
/// A field is a number, bool, string, an array or map of them, another
/// section, a std::vector or std::map<std::string, …> of sections, or a
/// std::optional of any of these (left out when empty). A section field
/// named "" is inline: its fields sit beside the others (a piece's figures
/// that a translator extends with its own). A field of type
/// nlohmann::json is a figure whose shape a helper decides (an image's error
/// statistics); it is written as it is and documented as "object".

#include <map>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/options_detail.h"
#include "core/properties.h"

namespace spec2fab {

/// One documented field: dotted name ("geometry.mesh"), type, meaning.
struct ReportFieldDoc {
  std::string name, type, meaning;
};

namespace report_detail {

template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
struct is_name_map : std::false_type {};
template <class T>
struct is_name_map<std::map<std::string, T>> : std::true_type {};

/// What a section's fields() is probed with.
struct Probe {
  template <class T>
  void operator()(const T&, const char*, const char*) {}
};

}  // namespace report_detail

/// A struct that declares its fields (above).
template <class S>
concept ReportSection = requires(report_detail::Probe& probe, const S& section) { S::fields(probe, section); };

namespace report_detail {

/// A std::vector of sections; a std::map from names to sections.
template <class T>
inline constexpr bool is_section_vector = false;
template <class E>
inline constexpr bool is_section_vector<std::vector<E>> = ReportSection<E>;
template <class T>
inline constexpr bool is_section_map = false;
template <class E>
inline constexpr bool is_section_map<std::map<std::string, E>> = ReportSection<E>;

template <class T>
nlohmann::json to_value(const T& value);

class Writer {
 public:
  nlohmann::json out = nlohmann::json::object();
  template <class T>
  void operator()(const T& value, const char* name, const char*) {
    if constexpr (is_optional<T>::value) {
      if (value) out[name] = to_value(*value);
    } else if constexpr (ReportSection<T>) {
      if (*name == '\0') {
        T::fields(*this, value);
      } else {
        out[name] = to_value(value);
      }
    } else {
      out[name] = to_value(value);
    }
  }
};

template <class T>
nlohmann::json to_value(const T& value) {
  if constexpr (ReportSection<T>) {
    Writer writer;
    T::fields(writer, value);
    return std::move(writer.out);
  } else if constexpr (is_section_vector<T>) {
    nlohmann::json array = nlohmann::json::array();
    for (const auto& item : value) array.push_back(to_value(item));
    return array;
  } else if constexpr (is_section_map<T>) {
    nlohmann::json object = nlohmann::json::object();
    for (const auto& [name, item] : value) object[name] = to_value(item);
    return object;
  } else {
    return nlohmann::json(value);
  }
}

template <class S>
S read(const Properties& properties);

class Reader {
 public:
  explicit Reader(const Properties& properties) : p_(properties) {}
  template <class T>
  void operator()(T& value, const char* name, const char*) {
    if constexpr (is_optional<T>::value) {
      if (!p_.has(name)) return;
      typename T::value_type item{};
      read_value(item, name);
      value = std::move(item);
    } else {
      read_value(value, name);
    }
  }

 private:
  template <class T>
  void read_value(T& value, const char* name) {
    if constexpr (ReportSection<T>) {
      value = *name == '\0' ? read<T>(p_) : read<T>(p_.object(name));
    } else if constexpr (is_section_vector<T>) {
      value.clear();
      for (const Properties& item : p_.objects(name)) value.push_back(read<typename T::value_type>(item));
    } else if constexpr (is_section_map<T>) {
      const Properties object = p_.object(name);
      value.clear();
      for (const std::string& key : object.keys()) value[key] = read<typename T::mapped_type>(object.object(key));
    } else {
      value = p_.get<T>(name);
    }
  }
  const Properties& p_;
};

template <class S>
S read(const Properties& properties) {
  S section{};
  Reader reader(properties);
  S::fields(reader, section);
  return section;
}

template <class T>
std::string type_text();

template <class S>
void document(std::vector<ReportFieldDoc>& rows, const std::string& prefix);

class Documenter {
 public:
  Documenter(std::vector<ReportFieldDoc>& rows, std::string prefix) : rows_(rows), prefix_(std::move(prefix)) {}
  template <class T>
  void operator()(const T&, const char* name, const char* meaning) {
    if constexpr (is_optional<T>::value) {
      add<typename T::value_type>(name, meaning, ", optional");
    } else {
      add<T>(name, meaning, "");
    }
  }

 private:
  template <class T>
  void add(const char* name, const char* meaning, const char* optional) {
    if constexpr (ReportSection<T>) {
      if (*name == '\0') return document<T>(rows_, prefix_);
    }
    const std::string full = prefix_ + name;
    rows_.push_back({full, type_text<T>() + optional, meaning});
    if constexpr (ReportSection<T>) {
      document<T>(rows_, full + ".");
    } else if constexpr (is_section_vector<T>) {
      document<typename T::value_type>(rows_, full + "[].");
    } else if constexpr (is_section_map<T>) {
      document<typename T::mapped_type>(rows_, full + ".<name>.");
    }
  }
  std::vector<ReportFieldDoc>& rows_;
  std::string prefix_;
};

template <class S>
void document(std::vector<ReportFieldDoc>& rows, const std::string& prefix) {
  const S section{};
  Documenter documenter(rows, prefix);
  S::fields(documenter, section);
}

/// A field's type as documented: sections and maps of them here, values as
/// options document theirs (core/options_detail.h).
template <class T>
std::string type_text() {
  if constexpr (ReportSection<T> || std::is_same_v<T, nlohmann::json>) {
    return "object";  // nlohmann::json: a helper's figures
  } else if constexpr (is_section_vector<T>) {
    return "array of objects";
  } else if constexpr (is_name_map<T>::value) {
    return "object: name → " + type_text<typename T::mapped_type>();
  } else {
    return options_detail::type_text<T>();
  }
}

}  // namespace report_detail

/// The mean, smallest and largest of some figures (one per column, …).
struct Spread {
  double mean = 0, max = 0, min = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.mean, "mean", "their mean");
    f(s.max, "max", "the largest");
    f(s.min, "min", "the smallest");
  }
  /// Of `values`, not empty.
  static Spread of(std::vector<double> values);
};

/// The section as result.json holds it.
template <ReportSection S>
nlohmann::json write_section(const S& section) {
  return report_detail::to_value(section);
}

/// A section read back from a report; throws InputError naming the file and
/// JSON path of a missing or mistyped field.
template <ReportSection S>
S read_section(const Properties& properties) {
  return report_detail::read<S>(properties);
}

/// The keys write_section writes for `section`: what a report's header
/// takes for itself (ReportSections' reserved names).
template <ReportSection S>
std::set<std::string> section_keys(const S& section) {
  std::set<std::string> keys;
  const nlohmann::json written = write_section(section);  // alive while items() walks it
  for (const auto& item : written.items()) keys.insert(item.key());
  return keys;
}

/// The section's fields, nested ones by dotted names, for docs/run-report.md.
template <ReportSection S>
std::vector<ReportFieldDoc> section_docs(const std::string& prefix = {}) {
  std::vector<ReportFieldDoc> rows;
  report_detail::document<S>(rows, prefix);
  return rows;
}

/// Sections a report holds by name (result.json, simulation.json), each
/// added once: a second section of one name, or one of the names the
/// report keeps for itself (`reserved`), is a bug (std::logic_error) — a
/// section has one writer.
class ReportSections {
 public:
  explicit ReportSections(std::set<std::string> reserved = {}) : reserved_(std::move(reserved)) {}
  /// A section, or a list of them.
  template <class S>
    requires ReportSection<S> || report_detail::is_section_vector<S>
  void add(const std::string& name, const S& section) {
    add_written(name, report_detail::to_value(section));
  }
  bool has(const std::string& name) const { return sections_.count(name) > 0; }
  /// Each section into `report` under its name.
  void write_into(nlohmann::json& report) const;

 private:
  void add_written(const std::string& name, nlohmann::json section);
  std::set<std::string> reserved_;
  std::map<std::string, nlohmann::json> sections_;
};

}  // namespace spec2fab

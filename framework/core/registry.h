#pragma once
/// Registries of named types, filled by one line at the end of each type's
/// file:
///
///     SPEC2FAB_REGISTER(NodeRegistry, StratumNode, "stratum");
///
/// A registered type provides a constructor taking (const Properties&, Args...)
/// and a `static TypeDoc doc()` that `spec2fab list --verbose` prints. There is
/// no central list of types to edit.

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/build_options.h"
#include "core/properties.h"
#include "core/strings.h"

namespace spec2fab {

/// One property of a registered type, as documented to users.
struct PropertyDoc {
  std::string name;
  std::string type;           ///< e.g. "number (mm)", "parameter", "node"
  std::string default_value;  ///< "required" when there is none
  std::string meaning;
};

/// What a registered type does, its properties and a JSON example.
struct TypeDoc {
  std::string summary;
  std::vector<PropertyDoc> properties;
  std::string example;  ///< a JSON snippet that builds this type
};

template <class Base, class... Args>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Base>(const Properties&, Args...)>;
  /// Made when first asked for, not at registration: a doc may list another
  /// registry's parts (a translator's output switches are the print
  /// writers), which static initialisation may not have filled yet.
  using DocMaker = std::function<TypeDoc()>;
  struct Entry {
    Factory factory;
    DocMaker make_doc;
    mutable std::optional<TypeDoc> doc;
  };

  static Registry& instance() {
    static Registry registry;
    return registry;
  }

  bool add(std::string name, Factory factory, DocMaker make_doc) {
    entries_.emplace(std::move(name), Entry{std::move(factory), std::move(make_doc), std::nullopt});
    return true;
  }

  /// What the type named `name` does, its properties and an example.
  const TypeDoc& doc(std::string_view name) const {
    const Entry& e = entry(name);
    const std::lock_guard<std::mutex> lock(doc_mutex_);
    if (!e.doc) e.doc = e.make_doc();
    return *e.doc;
  }

  bool contains(std::string_view name) const { return entries_.count(std::string(name)) > 0; }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& [name, entry] : entries_) out.push_back(name);
    return out;
  }

  const Entry& entry(std::string_view name) const { return entries_.at(std::string(name)); }

  /// Builds the type named by `properties[type_key]`; an unknown name is an
  /// InputError that lists the known ones (or says which build option left
  /// it out).
  std::unique_ptr<Base> create(const Properties& properties, std::string_view kind,
                               Args... args, std::string_view type_key = "type") const {
    const std::string name = properties.get<std::string>(type_key);
    return create_named(name, properties, kind, std::forward<Args>(args)..., type_key);
  }

  std::unique_ptr<Base> create_named(const std::string& name, const Properties& properties,
                                     std::string_view kind, Args... args,
                                     std::string_view type_key = "type") const {
    const auto found = entries_.find(name);
    if (found == entries_.end()) {
      if (const std::string left_out = left_out_of_build(kind, name); !left_out.empty())
        properties.fail(type_key, left_out);
      properties.fail(type_key, "unknown " + std::string(kind) + " '" + name + "'" +
                                    did_you_mean(name, names()) + " (known: " + join(names()) +
                                    ")");
    }
    return found->second.factory(properties, std::forward<Args>(args)...);
  }

 private:
  std::map<std::string, Entry, std::less<>> entries_;
  mutable std::mutex doc_mutex_;
};

/// A registry as `spec2fab list` shows it. Each registry puts itself in the
/// listing with SPEC2FAB_LIST_REGISTRY next to its parts' base, so a new
/// kind of part needs no edit of the command.
struct ListedRegistry {
  int rank = 0;         ///< place in the listing (lower first)
  std::string kind;     ///< as typed: "spec2fab list node"
  std::string heading;  ///< "nodes"
  std::function<std::vector<std::pair<std::string, TypeDoc>>()> entries;  ///< name and doc, sorted by name
};

inline std::vector<ListedRegistry>& listed_registries() {
  static std::vector<ListedRegistry> all;
  return all;
}

}  // namespace spec2fab

#define SPEC2FAB_CONCAT_INNER(a, b) a##b
#define SPEC2FAB_CONCAT(a, b) SPEC2FAB_CONCAT_INNER(a, b)
// Names made with __COUNTER__, not __LINE__: a unity build (CMakeLists.txt)
// compiles several .cpp files as one, where two lines may have one number.

/// Registers `Type` in `RegistryType` under `name`. Use once, at namespace scope
/// in the type's .cpp file.
#define SPEC2FAB_REGISTER(RegistryType, Type, name)                                       \
  namespace {                                                                             \
  [[maybe_unused]] const bool SPEC2FAB_CONCAT(registered_, __COUNTER__) =                  \
      RegistryType::instance().add(                                                       \
          name,                                                                           \
          [](const ::spec2fab::Properties& properties, auto&&... args) {                  \
            return std::make_unique<Type>(properties, std::forward<decltype(args)>(args)...); \
          },                                                                              \
          [] { return Type::doc(); });                                                    \
  }

/// Lists `RegistryType` in `spec2fab list` under `heading`, at `rank`. Use
/// once, at namespace scope, in the file that owns the registry's base.
#define SPEC2FAB_LIST_REGISTRY(RegistryType, rank, kind, heading)                          \
  namespace {                                                                             \
  [[maybe_unused]] const bool SPEC2FAB_CONCAT(listed_, __COUNTER__) = [] {                 \
    ::spec2fab::listed_registries().push_back({rank, kind, heading, [] {                  \
      std::vector<std::pair<std::string, ::spec2fab::TypeDoc>> out;                       \
      const auto& registry = RegistryType::instance();                                    \
      for (const std::string& name : registry.names()) out.emplace_back(name, registry.doc(name)); \
      return out;                                                                         \
    }});                                                                                  \
    return true;                                                                          \
  }();                                                                                    \
  }

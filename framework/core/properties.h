#pragma once
/// A property bag that complains: typed access to one JSON object of a
/// document, with the document's file name and the JSON pointer of every value
/// so that every error names where it is.
///
/// All Properties of one document share a ledger of the keys readers asked
/// for. After everything is built, `check_all_read()` walks the whole document
/// and reports the first key nobody asked for, with a did-you-mean suggestion
/// taken from the keys that were asked for in the same object:
///
///     exp.json: /goal/tree/layers/0/thicknes_mm: unknown key; did you mean 'thickness_mm'?
///
/// Keys that start with '_' are comments and are never reported.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace spec2fab {

class Properties {
 public:
  /// Parses a JSON file. Throws InputError for a missing/unreadable file or
  /// malformed JSON (with line and column).
  static Properties load(const std::filesystem::path& file);
  /// Parses text; `origin` names it in messages, relative paths resolve
  /// against `base_directory`.
  static Properties parse(std::string_view text, std::string origin,
                          std::filesystem::path base_directory = ".");
  /// Wraps an in-memory JSON object.
  static Properties wrap(nlohmann::json document, std::string origin,
                         std::filesystem::path base_directory = ".");

  const std::string& origin() const;
  const std::filesystem::path& base_directory() const;
  /// JSON pointer of this object within its document ("" for the root).
  const std::string& pointer() const { return pointer_; }
  /// "origin: /pointer/key" — the prefix of every message about `key`.
  std::string where(std::string_view key = {}) const;
  /// The JSON object this bag reads (for serialising it back unchanged).
  const nlohmann::json& value() const { return *object_; }
  std::vector<std::string> keys() const;

  bool has(std::string_view key) const;

  /// Required value; throws naming the key when missing or of the wrong type.
  /// T: bool, int, std::uint64_t (seeds: exact to 2^64 - 1), double,
  /// std::string, std::vector<double|int|std::string>,
  /// std::array<double|int, N>.
  template <class T>
  T get(std::string_view key) const;
  /// Optional value with a default.
  template <class T>
  T get(std::string_view key, const T& fallback) const {
    return has(key) ? get<T>(key) : fallback;
  }
  /// A number that must lie in [lower, upper].
  double get_in_range(std::string_view key, double fallback, double lower, double upper) const;

  /// A nested object (required / optional).
  Properties object(std::string_view key) const;
  std::optional<Properties> optional_object(std::string_view key) const;
  /// An array of objects.
  std::vector<Properties> objects(std::string_view key) const;
  /// Element `index` of the array at `key`, which must be an object: for an
  /// array whose elements take several forms (a name or an object), after
  /// peek() showed this one is an object.
  Properties element_object(std::string_view key, size_t index) const;
  /// The raw JSON value of a key without marking its contents read (to look
  /// at its type before reading it with get/object).
  const nlohmann::json& peek(std::string_view key) const;
  /// The raw JSON value of a key; the whole value counts as read.
  const nlohmann::json& raw(std::string_view key) const;
  /// A path to an existing file, resolved against the document's folder.
  std::filesystem::path existing_file(std::string_view key) const;

  [[noreturn]] void fail(std::string_view key, const std::string& problem) const;
  [[noreturn]] void fail(const std::string& problem) const { fail({}, problem); }

  /// Throws InputError for the first key of the whole document that no reader
  /// asked for.
  void check_all_read() const;

 private:
  struct Document;
  Properties(std::shared_ptr<Document> document, const nlohmann::json* object, std::string pointer);
  const nlohmann::json& lookup(std::string_view key) const;  // marks asked; throws when missing
  std::string child_pointer(std::string_view key) const;
  void consume(std::string_view key) const;

  std::shared_ptr<Document> document_;
  const nlohmann::json* object_;
  std::string pointer_;
};

}  // namespace spec2fab

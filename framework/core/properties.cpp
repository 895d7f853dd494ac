#include "core/properties.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/file_read.h"
#include "core/strings.h"

namespace spec2fab {

using nlohmann::json;

struct Properties::Document {
  json root;
  std::string origin;
  std::filesystem::path base_directory;
  std::map<std::string, std::set<std::string>> asked;  // object pointer -> keys asked for
  std::set<std::string> consumed;                      // values read whole
};

namespace {

std::string escape_pointer_token(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~') out += "~0";
    else if (c == '/') out += "~1";
    else out += c;
  }
  return out;
}

std::string type_name(const json& value) {
  if (value.is_number_integer()) return "an integer";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_boolean()) return "a boolean";
  if (value.is_array()) return "an array";
  if (value.is_object()) return "an object";
  return "null";
}

template <class T>
struct Converter;

template <>
struct Converter<double> {
  static constexpr const char* expected = "a number";
  static std::optional<double> convert(const json& v) {
    if (!v.is_number()) return std::nullopt;
    const double x = v.get<double>();
    if (!std::isfinite(x)) return std::nullopt;
    return x;
  }
};
template <>
struct Converter<int> {
  static constexpr const char* expected = "an integer";
  static std::optional<int> convert(const json& v) {
    // Read wide and checked: get<int>() would wrap 4294967297 to 1.
    if (v.is_number_unsigned()) {
      const auto x = v.get<std::uint64_t>();
      if (x > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) return std::nullopt;
      return static_cast<int>(x);
    }
    if (v.is_number_integer()) {
      const auto x = v.get<std::int64_t>();
      if (x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) return std::nullopt;
      return static_cast<int>(x);
    }
    if (v.is_number_float()) {
      const double x = v.get<double>();
      if (std::isfinite(x) && x == std::floor(x) && std::abs(x) < 2e9) return static_cast<int>(x);
    }
    return std::nullopt;
  }
};
// Seeds: any integer from 0 to 2^64 - 1, exactly. A number written with a
// fraction or exponent is taken only while a double holds it exactly (below
// 2^53): 18446744073709551615 read as a double would round silently.
template <>
struct Converter<std::uint64_t> {
  static constexpr const char* expected = "a whole number from 0 to 18446744073709551615";
  static std::optional<std::uint64_t> convert(const json& v) {
    if (v.is_number_unsigned()) return v.get<std::uint64_t>();
    if (v.is_number_integer()) {
      const auto x = v.get<std::int64_t>();
      if (x < 0) return std::nullopt;
      return static_cast<std::uint64_t>(x);
    }
    if (v.is_number_float()) {
      const double x = v.get<double>();
      if (std::isfinite(x) && x >= 0 && x == std::floor(x) && x <= 0x1p53) return static_cast<std::uint64_t>(x);
    }
    return std::nullopt;
  }
};
template <>
struct Converter<bool> {
  static constexpr const char* expected = "true or false";
  static std::optional<bool> convert(const json& v) {
    if (!v.is_boolean()) return std::nullopt;
    return v.get<bool>();
  }
};
template <>
struct Converter<std::string> {
  static constexpr const char* expected = "a string";
  static std::optional<std::string> convert(const json& v) {
    if (!v.is_string()) return std::nullopt;
    return v.get<std::string>();
  }
};
template <class E>
struct Converter<std::vector<E>> {
  static constexpr const char* expected = "an array";
  static std::optional<std::vector<E>> convert(const json& v) {
    if (!v.is_array()) return std::nullopt;
    std::vector<E> out;
    for (const json& e : v) {
      auto x = Converter<E>::convert(e);
      if (!x) return std::nullopt;
      out.push_back(*x);
    }
    return out;
  }
};
template <class E, size_t N>
struct Converter<std::array<E, N>> {
  static constexpr const char* expected = "an array of fixed length";
  static std::optional<std::array<E, N>> convert(const json& v) {
    if (!v.is_array() || v.size() != N) return std::nullopt;
    std::array<E, N> out{};
    for (size_t i = 0; i < N; ++i) {
      auto x = Converter<E>::convert(v[i]);
      if (!x) return std::nullopt;
      out[i] = *x;
    }
    return out;
  }
};

template <class T>
struct ArrayLength {
  static constexpr size_t value = 0;
};
template <class E, size_t N>
struct ArrayLength<std::array<E, N>> {
  static constexpr size_t value = N;
};

template <class T>
std::string expectation() {
  if constexpr (std::is_same_v<T, std::vector<double>>) return "an array of numbers";
  else if constexpr (std::is_same_v<T, std::vector<int>>) return "an array of integers";
  else if constexpr (std::is_same_v<T, std::vector<std::string>>) return "an array of strings";
  else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>>) return "an array of arrays of numbers";
  else if constexpr (ArrayLength<T>::value > 0) {
    const bool integers = std::is_same_v<typename T::value_type, int>;
    return "an array of " + std::to_string(ArrayLength<T>::value) +
           (integers ? " integers" : " numbers");
  }
  else return Converter<T>::expected;
}

}  // namespace

Properties::Properties(std::shared_ptr<Document> document, const json* object, std::string pointer)
    : document_(std::move(document)), object_(object), pointer_(std::move(pointer)) {}

Properties Properties::load(const std::filesystem::path& file) {
  if (const std::string why = unreadable_file_reason(file); !why.empty())
    throw InputError(file.string() + ": cannot open: " + why);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open: not readable");
  std::stringstream text;
  text << in.rdbuf();
  return parse(text.str(), file.string(), file.parent_path().empty() ? "." : file.parent_path());
}

Properties Properties::parse(std::string_view text, std::string origin,
                             std::filesystem::path base_directory) {
  json document;
  try {
    document = json::parse(text);
  } catch (const json::exception& e) {  // parse errors, and numbers beyond a double (1e999)
    std::string what = e.what();
    // nlohmann prefixes "[json.exception.parse_error.101] "; keep the human part.
    if (const auto bracket = what.find("] "); bracket != std::string::npos) what.erase(0, bracket + 2);
    throw InputError(origin + ": malformed JSON: " + what);
  }
  return wrap(std::move(document), std::move(origin), std::move(base_directory));
}

Properties Properties::wrap(json document, std::string origin, std::filesystem::path base_directory) {
  auto doc = std::make_shared<Document>();
  doc->root = std::move(document);
  doc->origin = std::move(origin);
  doc->base_directory = std::move(base_directory);
  if (!doc->root.is_object()) {
    throw InputError(doc->origin + ": expected a JSON object at the top level, got " +
                     type_name(doc->root));
  }
  const json* root = &doc->root;
  return Properties(std::move(doc), root, "");
}

const std::string& Properties::origin() const { return document_->origin; }
const std::filesystem::path& Properties::base_directory() const { return document_->base_directory; }

std::string Properties::child_pointer(std::string_view key) const {
  return pointer_ + "/" + escape_pointer_token(key);
}

std::string Properties::where(std::string_view key) const {
  const std::string pointer = key.empty() ? pointer_ : child_pointer(key);
  return document_->origin + ": " + (pointer.empty() ? "/" : pointer);
}

std::vector<std::string> Properties::keys() const {
  std::vector<std::string> out;
  for (const auto& item : object_->items()) out.push_back(item.key());
  return out;
}

bool Properties::has(std::string_view key) const {
  document_->asked[pointer_].insert(std::string(key));
  return object_->contains(key);
}

void Properties::fail(std::string_view key, const std::string& problem) const {
  throw InputError(where(key) + ": " + problem);
}

const json& Properties::lookup(std::string_view key) const {
  if (!has(key)) {
    // A misspelling of the key here says so, rather than only that it is missing.
    std::vector<std::string> present;
    for (const auto& item : object_->items())
      if (!item.key().empty() && item.key()[0] != '_') present.push_back(item.key());
    if (const std::string near = closest_match(key, present); !near.empty())
      fail(key, "missing required key (is '" + near + "' a misspelling of it?)");
    fail(key, "missing required key");
  }
  return object_->at(std::string(key));
}

void Properties::consume(std::string_view key) const { document_->consumed.insert(child_pointer(key)); }

template <class T>
struct HoldsInts : std::is_same<T, int> {};
template <class E>
struct HoldsInts<std::vector<E>> : HoldsInts<E> {};
template <class E, size_t N>
struct HoldsInts<std::array<E, N>> : HoldsInts<E> {};

/// Whether `value` holds an integer that T, made of ints, refused for its size.
template <class T>
bool integer_beyond_int(const json& value) {
  if constexpr (HoldsInts<T>::value) {
    auto beyond = [](const json& v) { return v.is_number_integer() && !Converter<int>::convert(v); };
    if (value.is_array()) return std::any_of(value.begin(), value.end(), beyond);
    return beyond(value);
  }
  return false;
}

template <class T>
T Properties::get(std::string_view key) const {
  const json& value = lookup(key);
  consume(key);
  auto converted = Converter<T>::convert(value);
  if (!converted) {
    const bool beyond = integer_beyond_int<T>(value);
    const std::string shown = value.dump();
    fail(key, "expected " + expectation<T>() + ", got " +
                  ((value.is_number() || beyond) && shown.size() <= 80 ? shown : type_name(value)) +
                  (beyond ? " (beyond ±2147483647)" : ""));
  }
  return *converted;
}

template bool Properties::get<bool>(std::string_view) const;
template int Properties::get<int>(std::string_view) const;
template std::uint64_t Properties::get<std::uint64_t>(std::string_view) const;
template double Properties::get<double>(std::string_view) const;
template std::string Properties::get<std::string>(std::string_view) const;
template std::vector<double> Properties::get<std::vector<double>>(std::string_view) const;
template std::vector<int> Properties::get<std::vector<int>>(std::string_view) const;
template std::vector<std::string> Properties::get<std::vector<std::string>>(std::string_view) const;
template std::vector<std::vector<double>> Properties::get<std::vector<std::vector<double>>>(std::string_view) const;
template std::array<double, 2> Properties::get<std::array<double, 2>>(std::string_view) const;
template std::array<double, 3> Properties::get<std::array<double, 3>>(std::string_view) const;
template std::array<double, 4> Properties::get<std::array<double, 4>>(std::string_view) const;
template std::array<int, 2> Properties::get<std::array<int, 2>>(std::string_view) const;
template std::array<int, 3> Properties::get<std::array<int, 3>>(std::string_view) const;
template std::vector<std::array<double, 3>> Properties::get<std::vector<std::array<double, 3>>>(std::string_view) const;

double Properties::get_in_range(std::string_view key, double fallback, double lower,
                                double upper) const {
  const double value = get<double>(key, fallback);
  if (value < lower || value > upper) {
    std::ostringstream message;
    message << "value " << value << " is outside [" << lower << ", " << upper << "]";
    fail(key, message.str());
  }
  return value;
}

Properties Properties::object(std::string_view key) const {
  const json& value = lookup(key);
  if (!value.is_object()) fail(key, "expected an object, got " + type_name(value));
  return Properties(document_, &value, child_pointer(key));
}

std::optional<Properties> Properties::optional_object(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return object(key);
}

std::vector<Properties> Properties::objects(std::string_view key) const {
  const json& value = lookup(key);
  if (!value.is_array()) fail(key, "expected an array of objects, got " + type_name(value));
  std::vector<Properties> out;
  const std::string base = child_pointer(key);
  for (size_t i = 0; i < value.size(); ++i) {
    const std::string pointer = base + "/" + std::to_string(i);
    if (!value[i].is_object()) {
      throw InputError(document_->origin + ": " + pointer + ": expected an object, got " +
                       type_name(value[i]));
    }
    out.push_back(Properties(document_, &value[i], pointer));
  }
  return out;
}

Properties Properties::element_object(std::string_view key, size_t index) const {
  const json& value = lookup(key);
  const std::string pointer = child_pointer(key) + "/" + std::to_string(index);
  if (!value.is_array() || index >= value.size())
    throw InputError(document_->origin + ": " + pointer + ": expected an array element");
  if (!value[index].is_object())
    throw InputError(document_->origin + ": " + pointer + ": expected an object, got " + type_name(value[index]));
  return Properties(document_, &value[index], pointer);
}

const json& Properties::peek(std::string_view key) const { return lookup(key); }

const json& Properties::raw(std::string_view key) const {
  const json& value = lookup(key);
  consume(key);
  return value;
}

std::filesystem::path Properties::existing_file(std::string_view key) const {
  const std::filesystem::path given = get<std::string>(key);
  const std::filesystem::path resolved =
      given.is_absolute() ? given : document_->base_directory / given;
  if (const std::string why = unreadable_file_reason(resolved); !why.empty())
    fail(key, why + ": " + resolved.lexically_normal().string());
  return resolved.lexically_normal();
}

void Properties::check_all_read() const {
  // Walk from this object down; comments (keys starting with '_') are skipped.
  struct Walker {
    const Document& doc;
    void walk(const json& value, const std::string& pointer) const {
      if (doc.consumed.count(pointer)) return;
      if (value.is_object()) {
        const auto asked = doc.asked.find(pointer);
        for (const auto& item : value.items()) {
          const std::string& key = item.key();
          if (!key.empty() && key[0] == '_') continue;
          const std::string child = pointer + "/" + escape_pointer_token(key);
          if (asked == doc.asked.end() || !asked->second.count(key)) {
            std::vector<std::string> known;
            if (asked != doc.asked.end()) known.assign(asked->second.begin(), asked->second.end());
            throw InputError(doc.origin + ": " + child + ": unknown key" + did_you_mean(key, known));
          }
          walk(item.value(), child);
        }
      } else if (value.is_array()) {
        for (size_t i = 0; i < value.size(); ++i) walk(value[i], pointer + "/" + std::to_string(i));
      }
    }
  };
  Walker{*document_}.walk(*object_, pointer_);
}

}  // namespace spec2fab

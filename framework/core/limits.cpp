#include "core/limits.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <map>
#include <mutex>

#include <fmt/format.h>

#include "core/error.h"
#include "core/properties.h"
#include "core/strings.h"

namespace spec2fab {
namespace limits {

namespace {

std::mutex& guard() {
  static std::mutex m;
  return m;
}

std::vector<LimitDoc>& declared() {
  static std::vector<LimitDoc> all;
  return all;
}

// Declarations end before main starts; after that the list only is read.
const LimitDoc* find(std::string_view name) {
  for (const LimitDoc& doc : declared())
    if (doc.name == name) return &doc;
  return nullptr;
}

std::vector<std::string> names() {
  std::vector<std::string> out;
  for (const LimitDoc& doc : docs()) out.push_back(doc.name);
  return out;
}

// A value above the limit's ceiling: why it cannot be set, else "".
std::string beyond_ceiling(std::string_view name, double value) {
  const LimitDoc* doc = find(name);
  if (doc == nullptr || doc->ceiling <= 0 || value <= doc->ceiling) return {};
  return fmt::format("at most {:g}: {}", doc->ceiling, doc->ceiling_reason);
}

}  // namespace

bool declare(std::string name, double default_value, std::string meaning, double ceiling, std::string ceiling_reason) {
  LimitDoc doc{std::move(name), default_value, std::move(meaning), ceiling, std::move(ceiling_reason)};
  const std::lock_guard lock(guard());
  std::vector<LimitDoc>& all = declared();
  for (const LimitDoc& other : all)
    if (other.name == doc.name) throw std::logic_error("limits: '" + doc.name + "' is declared twice");
  all.push_back(std::move(doc));
  return true;
}

std::vector<LimitDoc> docs() {
  std::vector<LimitDoc> all;
  {
    const std::lock_guard lock(guard());
    all = declared();
  }
  // Static initialisation declares them in no fixed order.
  std::sort(all.begin(), all.end(), [](const LimitDoc& a, const LimitDoc& b) { return a.name < b.name; });
  return all;
}

}  // namespace limits

const Limits& default_limits() {
  static const Limits defaults;
  return defaults;
}

double Limits::get(std::string_view name) const {
  if (const auto found = command_line_.find(name); found != command_line_.end()) return found->second;
  if (const auto found = experiment_.find(name); found != experiment_.end()) return found->second;
  const LimitDoc* doc = limits::find(name);
  if (doc == nullptr) throw std::logic_error("limits: no limit '" + std::string(name) + "'");
  return doc->default_value;
}

void Limits::set_from_command_line(const std::string& assignment) {
  const size_t equals = assignment.find('=');
  const std::string name = assignment.substr(0, equals);
  if (limits::find(name) == nullptr)
    throw InputError("--limit " + assignment + ": no limit '" + name + "'" + did_you_mean(name, limits::names()) +
                     " (limits: " + join(limits::names()) + ")");
  double value = NAN;
  try {
    size_t used = 0;
    const std::string text = equals == std::string::npos ? "" : assignment.substr(equals + 1);
    value = std::stod(text, &used);
    if (used != text.size()) value = NAN;
  } catch (const std::exception&) {
  }
  if (!(value > 0) || !std::isfinite(value))
    throw InputError("--limit " + assignment + ": give NAME=VALUE with a positive number, e.g. --limit " + name + "=" +
                     fmt::format("{:g}", limits::find(name)->default_value * 2));
  if (const std::string why = limits::beyond_ceiling(name, value); !why.empty())
    throw InputError("--limit " + assignment + ": " + why);
  command_line_[name] = value;
}

void Limits::set_from_experiment(const Properties& limits) {
  std::map<std::string, double, std::less<>> read;
  for (const LimitDoc& doc : limits::docs()) {
    if (!limits.has(doc.name)) continue;
    const double value = limits.get<double>(doc.name);
    if (!(value > 0)) limits.fail(doc.name, "must be a positive number");
    if (const std::string why = limits::beyond_ceiling(doc.name, value); !why.empty()) limits.fail(doc.name, why);
    read[doc.name] = value;
  }
  experiment_ = std::move(read);
}

std::string Limits::how_to_change(std::string_view name) const {
  return fmt::format("(limit {} = {:.3g}; set it with --limit {}=… or the experiment's \"limits\")", name, get(name),
                     name);
}

}  // namespace spec2fab

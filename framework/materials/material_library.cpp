#include "materials/material_library.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/error.h"
#include "core/strings.h"

namespace spec2fab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<std::string>& known_kinds() {
  // "void" is not here: the palette adds the one void material itself.
  static const std::vector<std::string> kinds = {"rigid", "flexible", "transparent", "support"};
  return kinds;
}

// The physically possible values of one quantity; plausibility (e.g. a
// density near that of plastics) is the data tests' business, not the loader's.
struct QuantityRange {
  double lower;
  double upper;
  bool lower_open = false;
  bool upper_open = false;

  bool contains(double v) const {
    return (lower_open ? v > lower : v >= lower) && (upper_open ? v < upper : v <= upper);
  }
  std::string text() const {
    std::ostringstream out;
    out << (lower_open ? "(" : "[") << lower << ", ";
    if (std::isinf(upper))
      out << "inf)";
    else
      out << upper << (upper_open ? ")" : "]");
    return out.str();
  }
};

const QuantityRange kNonNegative{0, kInf, false, true};
const QuantityRange kPositive{0, kInf, true, true};
const QuantityRange kUnit{0, 1};

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

void check_value(const Properties& entry, std::string_view key, double v, const QuantityRange& range,
                 std::string_view component = {}) {
  if (range.contains(v)) return;
  std::string problem = std::string(component.empty() ? "value " : component) + number(v) +
                        " is outside " + range.text();
  entry.fail(key, problem);
}

Rgb read_rgb(const Properties& entry, std::string_view key, const QuantityRange& range) {
  // A single number is a grey value, the same in R, G and B.
  Rgb rgb{};
  if (entry.peek(key).is_number()) {
    rgb.fill(entry.get<double>(key));
  } else {
    rgb = entry.get<std::array<double, 3>>(key);
  }
  static const char* const kChannel[] = {"R value ", "G value ", "B value "};
  for (size_t c = 0; c < 3; ++c) check_value(entry, key, rgb[c], range, kChannel[c]);
  return rgb;
}

std::string read_source(const Properties& entry) {
  std::string source = entry.get<std::string>("source");
  if (std::all_of(source.begin(), source.end(), [](unsigned char c) { return std::isspace(c); })) {
    entry.fail("source",
               "must say where the value comes from (citation, data sheet, or how it was "
               "estimated)");
  }
  return source;
}

Sourced<double> read_scalar(const Properties& section, std::string_view key, const QuantityRange& range) {
  const Properties entry = section.object(key);
  Sourced<double> out;
  out.value = entry.get<double>("value");
  check_value(entry, "value", out.value, range);
  out.source = read_source(entry);
  out.estimate = entry.get<bool>("estimate", false);
  return out;
}

Sourced<Rgb> read_color(const Properties& section, std::string_view key, const QuantityRange& range) {
  const Properties entry = section.object(key);
  Sourced<Rgb> out;
  out.value = read_rgb(entry, "value", range);
  out.source = read_source(entry);
  out.estimate = entry.get<bool>("estimate", false);
  return out;
}

Material read_material(const Properties& entry) {
  Material m;
  m.name = entry.get<std::string>("name");
  if (m.name.empty()) entry.fail("name", "must not be empty");
  if (m.name == "void") {
    entry.fail("name", "'void' is reserved: every palette adds it as material 0");
  }
  m.description = entry.get<std::string>("description", "");
  m.kind = entry.get<std::string>("kind");
  const auto& kinds = known_kinds();
  if (std::find(kinds.begin(), kinds.end(), m.kind) == kinds.end()) {
    entry.fail("kind", "unknown kind '" + m.kind + "' (expected one of: " + join(kinds) + ")" +
                           did_you_mean(m.kind, kinds));
  }
  if (entry.has("display_srgb")) m.display_srgb = read_rgb(entry, "display_srgb", kUnit);

  const Properties optical = entry.object("optical");
  m.absorption_per_mm = read_color(optical, "absorption_per_mm", kNonNegative);
  m.reduced_scattering_per_mm = read_color(optical, "reduced_scattering_per_mm", kNonNegative);
  // Every solid and liquid index lies well inside [1, 3] at visible wavelengths.
  m.refractive_index = read_scalar(optical, "refractive_index", QuantityRange{1, 3});
  m.albedo = read_color(optical, "albedo", kUnit);

  const Properties mechanical = entry.object("mechanical");
  m.youngs_modulus_pa = read_scalar(mechanical, "youngs_modulus_pa", kPositive);
  // Isotropic stability bounds of linear elasticity.
  m.poisson_ratio = read_scalar(mechanical, "poisson_ratio", QuantityRange{-1, 0.5, true, true});
  m.density_kg_m3 = read_scalar(mechanical, "density_kg_m3", kPositive);
  if (mechanical.has("tensile_strength_pa"))
    m.tensile_strength_pa = read_scalar(mechanical, "tensile_strength_pa", kPositive);

  if (entry.has("cost")) {
    const Properties cost = entry.object("cost");
    m.price_usd_per_kg = read_scalar(cost, "price_usd_per_kg", kNonNegative);
  }
  return m;
}

}  // namespace

MaterialLibrary MaterialLibrary::load(const std::filesystem::path& file) {
  const Properties properties = Properties::load(file);
  MaterialLibrary library = from_properties(properties);
  properties.check_all_read();  // a misspelt key is an error, not a silent default
  return library;
}

MaterialLibrary MaterialLibrary::from_properties(const Properties& properties) {
  MaterialLibrary library;
  library.origin_ = properties.origin();
  properties.get<std::string>("library", "");  // a title for readers of the file; type-checked only
  const std::vector<Properties> entries = properties.objects("materials");
  if (entries.empty()) properties.fail("materials", "the library lists no materials");
  std::map<std::string, std::string> first_seen;  // name -> pointer of its entry
  for (const Properties& entry : entries) {
    Material material = read_material(entry);
    const auto [it, inserted] = first_seen.emplace(material.name, entry.pointer());
    if (!inserted) {
      entry.fail("name",
                 "duplicate material '" + material.name + "' (first at " + it->second + ")");
    }
    library.materials_.emplace(material.name, std::move(material));
  }
  return library;
}

bool MaterialLibrary::contains(const std::string& name) const { return materials_.count(name) > 0; }

const Material& MaterialLibrary::get(const std::string& name) const {
  const auto it = materials_.find(name);
  if (it == materials_.end()) {
    const std::vector<std::string> known = names();
    throw InputError(origin_ + ": material '" + name + "' is not in this library (known: " +
                     join(known) + ")" + did_you_mean(name, known));
  }
  return it->second;
}

std::vector<std::string> MaterialLibrary::names() const {
  std::vector<std::string> out;
  out.reserve(materials_.size());
  for (const auto& [name, material] : materials_) out.push_back(name);
  return out;
}

}  // namespace spec2fab

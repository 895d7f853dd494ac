#include "materials/palette.h"

#include <algorithm>
#include <limits>

#include "core/error.h"
#include "core/strings.h"

namespace spec2fab {
namespace {

// Empty space: what a voxel holds when the printer deposits nothing there.
Material make_void() {
  Material m;
  m.name = "void";
  m.description = "empty space: the printer deposits nothing";
  m.kind = "void";
  m.display_srgb = {1, 1, 1};
  const std::string none = "no material";
  m.absorption_per_mm = {{0, 0, 0}, none, false};
  m.reduced_scattering_per_mm = {{0, 0, 0}, none, false};
  m.refractive_index = {1.0, none, false};  // vacuum/air: refraction at a void boundary is neutral
  m.albedo = {{0, 0, 0}, none, false};
  m.youngs_modulus_pa = {0, none, false};
  m.poisson_ratio = {0, none, false};
  m.density_kg_m3 = {0, none, false};
  return m;
}

// "file" for a loaded printer, a readable stand-in for one built in code.
std::string printer_where(const PrinterProfile& printer) {
  return printer.origin.empty() ? "printer '" + printer.name + "'" : printer.origin;
}

}  // namespace

MaterialPalette::MaterialPalette(const MaterialLibrary& library, const PrinterProfile& printer)
    : printer_name_(printer.name) {
  const std::string where = printer_where(printer);
  const std::vector<std::string> known = library.names();
  auto not_in_library = [&](const std::string& pointer, const std::string& name) {
    return InputError(where + ": " + pointer + ": material '" + name + "' is not in library " +
                      library.origin() + " (known: " + join(known) + ")" +
                      did_you_mean(name, known));
  };

  materials_.push_back(make_void());
  for (size_t i = 0; i < printer.model_materials.size(); ++i) {
    const std::string& name = printer.model_materials[i];
    const std::string pointer = "/model_materials/" + std::to_string(i);
    if (!library.contains(name)) throw not_in_library(pointer, name);
    // Profiles built in code skip the loader's checks; repeat the one that
    // would make ids ambiguous.
    if (contains(name)) {
      throw InputError(where + ": " + pointer + ": material '" + name + "' is listed twice");
    }
    materials_.push_back(library.get(name));
  }
  if (!printer.support_material.empty()) {
    if (!library.contains(printer.support_material)) throw not_in_library("/support_material", printer.support_material);
    cavity_fill_ = library.get(printer.support_material);
  }
}

MaterialPalette::MaterialPalette(std::vector<Material> model_materials) {
  materials_.push_back(make_void());
  for (Material& material : model_materials) {
    if (contains(material.name)) {
      throw InputError("material palette: material '" + material.name +
                       "' appears twice (or is named 'void', which is id 0)");
    }
    materials_.push_back(std::move(material));
  }
  if (materials_.size() > size_t{std::numeric_limits<MaterialId>::max()} + 1) {
    throw InputError("material palette: too many materials for a MaterialId");
  }
}

MaterialId MaterialPalette::id(const std::string& name, const std::string& where) const {
  for (size_t i = 0; i < materials_.size(); ++i) {
    if (materials_[i].name == name) return static_cast<MaterialId>(i);
  }
  const std::vector<std::string> loaded = names();
  const std::string holder =
      printer_name_.empty() ? "in this palette" : "loaded in printer '" + printer_name_ + "'";
  throw InputError(where + ": material '" + name + "' is not " + holder +
                   " (loaded: " + join(loaded) + ")" + did_you_mean(name, loaded));
}

bool MaterialPalette::contains(const std::string& name) const {
  return std::any_of(materials_.begin(), materials_.end(),
                     [&](const Material& m) { return m.name == name; });
}

std::vector<std::string> MaterialPalette::names() const {
  std::vector<std::string> out;
  out.reserve(materials_.size());
  for (const Material& material : materials_) out.push_back(material.name);
  return out;
}

}  // namespace spec2fab

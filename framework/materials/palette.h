#pragma once
/// The materials one run may assign: void (id 0) and the model materials the
/// chosen printer holds (ids 1..n, in the printer's order), each resolved in
/// the material library.

#include <optional>
#include <string>
#include <vector>

#include "materials/material.h"
#include "materials/material_library.h"
#include "materials/printer_profile.h"

namespace spec2fab {

class MaterialPalette {
 public:
  /// Throws InputError when the printer names a material the library lacks.
  MaterialPalette(const MaterialLibrary& library, const PrinterProfile& printer);
  /// A palette of the given materials (tests, tools).
  explicit MaterialPalette(std::vector<Material> model_materials);

  size_t size() const { return materials_.size(); }  ///< including void
  const Material& material(MaterialId id) const { return materials_.at(id); }
  const std::string& name(MaterialId id) const { return materials_.at(id).name; }
  /// Id of a material by name ("void" is 0); throws InputError via `where`
  /// ("file: /ptr") when the printer does not hold it.
  MaterialId id(const std::string& name, const std::string& where) const;
  bool contains(const std::string& name) const;
  std::vector<std::string> names() const;  ///< including "void"
  const std::string& printer_name() const { return printer_name_; }
  /// What fills a cavity the print encloses: the printer's support material
  /// (PolyJet jets its gel under every overhang, and none can leave a closed
  /// cavity), or null where cavities stay empty (FDM bridges over them).
  const Material* cavity_fill() const { return cavity_fill_ ? &*cavity_fill_ : nullptr; }
  /// A palette whose cavities fill with `fill` (tests, tools).
  void set_cavity_fill(Material fill) { cavity_fill_ = std::move(fill); }

 private:
  std::vector<Material> materials_;
  std::string printer_name_;
  std::optional<Material> cavity_fill_;
};

}  // namespace spec2fab

#pragma once
/// The material set of a run: every material described in one library file
/// (e.g. datasets/materials/polyjet.json).

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/properties.h"
#include "materials/material.h"

namespace spec2fab {

class MaterialLibrary {
 public:
  /// Reads a library file; every value is validated (ranges, sources present)
  /// and errors name the file and JSON path.
  static MaterialLibrary load(const std::filesystem::path& file);
  static MaterialLibrary from_properties(const Properties& properties);

  bool contains(const std::string& name) const;
  /// Throws InputError listing the known names when `name` is unknown.
  const Material& get(const std::string& name) const;
  std::vector<std::string> names() const;
  const std::string& origin() const { return origin_; }

 private:
  std::map<std::string, Material> materials_;
  std::string origin_;
};

}  // namespace spec2fab

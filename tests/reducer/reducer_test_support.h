#pragma once
// Shared by the reducer tests: a palette of named test materials and tree
// building from JSON text.

#include <memory>
#include <string>
#include <vector>

#include "core/properties.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"

namespace spec2fab::testing {

inline std::shared_ptr<MaterialPalette> make_palette(const std::vector<std::string>& names) {
  std::vector<Material> materials;
  for (const std::string& name : names) {
    Material m;
    m.name = name;
    m.kind = "rigid";
    materials.push_back(m);
  }
  return std::make_shared<MaterialPalette>(materials);
}

inline std::unique_ptr<ReducerTree> make_tree(const std::string& json, const MaterialPalette& palette) {
  const Properties properties = Properties::parse(json, "tree.json");
  auto tree = std::make_unique<ReducerTree>(properties, palette);
  properties.check_all_read();
  return tree;
}

}  // namespace spec2fab::testing

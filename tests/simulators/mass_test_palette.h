#pragma once
// The palette the mass tests weigh with: round densities whose sums are
// textbook arithmetic.

#include "materials/palette.h"

namespace spec2fab {

/// Light (1000 kg/m³) and heavy (3000 kg/m³).
inline MaterialPalette light_and_heavy() {
  std::vector<Material> materials(2);
  materials[0].name = "light";
  materials[0].density_kg_m3.value = 1000;
  materials[1].name = "heavy";
  materials[1].density_kg_m3.value = 3000;
  return MaterialPalette(materials);
}

}  // namespace spec2fab

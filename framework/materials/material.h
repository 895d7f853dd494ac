#pragma once
/// A printable material with the optical and mechanical data simulators use.
/// Every value in the dataset files carries its source (or is marked an
/// estimate); see datasets/materials/README.md for the file format.

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace spec2fab {

/// Index of a material in a run's MaterialPalette. 0 is always void.
using MaterialId = std::uint16_t;
inline constexpr MaterialId kVoid = 0;

using Rgb = std::array<double, 3>;

/// A number with where it comes from.
template <class T>
struct Sourced {
  T value{};
  std::string source;     ///< citation, datasheet, or how it was estimated
  bool estimate = false;  ///< true when not taken from a measurement or datasheet
};

struct Material {
  std::string name;
  std::string description;
  std::string kind;  ///< "rigid", "flexible", "transparent", "support" or "void"
  Rgb display_srgb{0.5, 0.5, 0.5};  ///< colour for previews and 3MF, sRGB in [0,1]

  // Optics (per colour channel R, G, B where three values are given).
  Sourced<Rgb> absorption_per_mm;          ///< σa (1/mm)
  Sourced<Rgb> reduced_scattering_per_mm;  ///< σs' (1/mm)
  Sourced<double> refractive_index;        ///< η
  Sourced<Rgb> albedo;                     ///< diffuse reflectance of a thick slab, linear RGB

  // Mechanics (SI).
  Sourced<double> youngs_modulus_pa;
  Sourced<double> poisson_ratio;
  Sourced<double> density_kg_m3;
  /// Ultimate tensile strength (Pa), where the data sheet gives one; for
  /// goals that bound stress.
  std::optional<Sourced<double>> tensile_strength_pa;

  /// Price (US dollars per kg of material used); absent where the library
  /// gives none (the print's cost then says which materials it left out).
  std::optional<Sourced<double>> price_usd_per_kg;
};

}  // namespace spec2fab

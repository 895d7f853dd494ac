#pragma once
/// What a printer can do: resolution, build volume, the materials loaded in
/// it. A translator may only use the loaded model materials (device
/// independence: the same translator, another printer, another palette).

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/properties.h"

namespace spec2fab {

struct PrinterProfile {
  std::string name;
  std::string technology;       ///< "polyjet", "fdm", ...
  std::array<double, 2> dpi{};  ///< x, y resolution (dots per inch)
  double layer_mm = 0;          ///< z resolution (layer thickness)
  std::array<double, 3> build_volume_mm{};
  std::vector<std::string> model_materials;  ///< loaded model materials, by library name
  std::string support_material;              ///< "" when the process needs none
  double nozzle_mm = 0;                      ///< FDM nozzle diameter; 0 when not applicable
  std::string source;                        ///< where the figures come from
  std::string origin;                        ///< file it was read from

  /// Voxel size (mm) in x, y, z.
  std::array<double, 3> voxel_mm() const;

  static PrinterProfile load(const std::filesystem::path& file);
  static PrinterProfile from_properties(const Properties& properties);
};

}  // namespace spec2fab

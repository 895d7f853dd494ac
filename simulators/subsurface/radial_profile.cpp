#include "subsurface/radial_profile.h"

#include <fmt/format.h>

#include "core/file_write.h"

namespace spec2fab {

namespace fs = std::filesystem;

std::vector<std::string> RadialProfileObservation::write_files(const fs::path& folder) const {
  // R(r) in 1/mm² (reflected flux per unit area per unit incident flux).
  std::string csv = "radius_mm,r,g,b\n";
  const std::vector<double> rgb = samples();
  const std::span<const double> radii = basis->radii();
  for (size_t i = 0; i < radii.size(); ++i) {
    csv += fmt::format("{:.6g},{:.9g},{:.9g},{:.9g}\n", radii[i], rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
  }
  write_file(folder / "profile.csv", csv);
  return {"profile.csv"};
}

}  // namespace spec2fab

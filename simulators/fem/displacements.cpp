#include "fem/displacements.h"

#include <fmt/format.h>

#include "core/file_write.h"

namespace spec2fab {

namespace fs = std::filesystem;

std::vector<std::string> DisplacementsObservation::write_files(const fs::path& folder) const {
  // Probes first (their rest point), then the mesh's nodes.
  std::string csv = "point,kind,ux_mm,uy_mm,uz_mm\n";
  for (size_t i = 0; 3 * i + 2 < xyz_mm.size(); ++i) {
    const bool probe = i < static_cast<size_t>(probe_count);
    csv += fmt::format("{},{},{:.9g},{:.9g},{:.9g}\n", probe ? i : i - static_cast<size_t>(probe_count),
                       probe ? "probe" : "node", xyz_mm[3 * i], xyz_mm[3 * i + 1], xyz_mm[3 * i + 2]);
  }
  write_file(folder / "observation.csv", csv);
  return {"observation.csv"};
}

}  // namespace spec2fab

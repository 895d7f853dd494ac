#pragma once
/// What the fem simulator observes and its goals and metric compare:
/// displacements of probes and nodes, and the stress (the observation type
/// lives with the one simulator that makes it).

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tuning/observation.h"

namespace spec2fab {

/// Displacements (mm), 3 per point: first `probe_count` probe points (at
/// the rest positions probe_rest_mm, 3 per probe), then every node of the
/// simulator's mesh (a goal may hold probes only).
struct DisplacementsObservation final : ObservationOf<DisplacementsObservation> {
  static constexpr std::string_view kType = "displacements";
  std::vector<double> xyz_mm;
  int probe_count = 0;
  std::vector<double> probe_rest_mm;
  /// Per-tet von Mises stress (MPa; 0 in void) and its largest value and
  /// 99th percentile over the solid's tets, for goals that bound stress.
  std::vector<double> von_mises_mpa;
  double stress_max_mpa = 0, stress_p99_mpa = 0;
  std::span<const double> probes() const { return {xyz_mm.data(), 3 * static_cast<size_t>(probe_count)}; }
  std::span<const double> values() const override { return xyz_mm; }
  std::span<double> values() override { return xyz_mm; }
  /// One row of x, y, z per point: the probes, then the mesh's nodes.
  std::vector<std::size_t> shape() const override { return {xyz_mm.size() / 3, 3}; }
  /// observation.csv: probes first, then nodes.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

}  // namespace spec2fab

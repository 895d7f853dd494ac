#pragma once
/// Counts how much of each material a bound tree assigns, on a voxel grid
/// over the solid's bounds (a cheap preview of what fabrication will print).

#include <array>
#include <vector>

#include "reducer/reducer_tree.h"

namespace spec2fab {

struct MaterialCensus {
  std::array<int, 3> grid{};       ///< voxels along x, y, z
  double voxel_mm = 0;             ///< cubic voxel edge
  std::vector<long long> voxels;   ///< per material id (index 0: void inside the bounds)
  double volume_mm3(MaterialId id) const { return static_cast<double>(voxels[id]) * voxel_mm * voxel_mm * voxel_mm; }
};

/// Evaluates the tree at the centres of cubic voxels of edge `voxel_mm`
/// filling the solid's bounds, z-slices in parallel. Deterministic.
MaterialCensus take_census(const ReducerTree& tree, double voxel_mm);

}  // namespace spec2fab

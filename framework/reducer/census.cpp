#include "reducer/census.h"

#include <cmath>

#include <tbb/parallel_for.h>

namespace spec2fab {

MaterialCensus take_census(const ReducerTree& tree, double voxel_mm) {
  const Bounds& bounds = tree.solid().bounds();
  MaterialCensus census;
  census.voxel_mm = voxel_mm;
  for (int k = 0; k < 3; ++k) {
    census.grid[k] = std::max(1, static_cast<int>(std::ceil(bounds.size()[k] / voxel_mm)));
  }
  const size_t materials = tree.palette().size();
  // One count vector per slice, summed in slice order: same result for any thread count.
  std::vector<std::vector<long long>> per_slice(static_cast<size_t>(census.grid[2]),
                                                std::vector<long long>(materials, 0));
  tbb::parallel_for(0, census.grid[2], [&](int z) {
    ReducerTree::Query query(tree);
    std::vector<MaterialId> row(static_cast<size_t>(census.grid[0]));
    auto& counts = per_slice[static_cast<size_t>(z)];
    for (int y = 0; y < census.grid[1]; ++y) {
      const Vec3 start = bounds.lower + voxel_mm * Vec3(0.5, y + 0.5, z + 0.5);
      query.material_row(start, Vec3(voxel_mm, 0, 0), census.grid[0], row.data());
      for (MaterialId id : row) ++counts[id];
    }
  });
  census.voxels.assign(materials, 0);
  for (const auto& counts : per_slice) {
    for (size_t m = 0; m < materials; ++m) census.voxels[m] += counts[m];
  }
  return census;
}

}  // namespace spec2fab

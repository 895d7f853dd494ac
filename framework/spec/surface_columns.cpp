#include "spec/surface_columns.h"

namespace spec2fab {

std::unique_ptr<ReducerTree> build_surface_column_tree(const Experiment& experiment, double shell_mm,
                                                       std::array<int, 2> columns, nlohmann::json layers,
                                                       const std::string& backing, const std::string& label) {
  layers.push_back({{"material", backing}});
  const nlohmann::json tree = {
      {"type", "stratum"},
      {"depth_mm", shell_mm},
      {"shell", {{"type", "column"}, {"count", columns}, {"child", {{"type", "layered"}, {"layers", layers}}}}},
      {"core", {{"type", "layered"}, {"material", backing}}}};
  auto out = std::make_unique<ReducerTree>(
      Properties::wrap(tree, experiment.file().string() + " (" + label + " tree)"), experiment.palette());
  out->bind(experiment.solid(), experiment.geometry_spec().field_voxel_mm);
  return out;
}

}  // namespace spec2fab

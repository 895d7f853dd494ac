#include "spec/surface_columns.h"

namespace spec2fab {

nlohmann::json surface_column_tree(double shell_mm, std::array<int, 2> columns, nlohmann::json layers,
                                   const std::string& backing) {
  layers.push_back({{"material", backing}});
  return {{"type", "stratum"},
          {"depth_mm", shell_mm},
          {"shell", {{"type", "column"}, {"count", columns}, {"child", {{"type", "layered"}, {"layers", layers}}}}},
          {"core", {{"type", "layered"}, {"material", backing}}}};
}

}  // namespace spec2fab

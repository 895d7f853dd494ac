#include "spec/surface_columns.h"

namespace spec2fab {

SurfaceColumnTree surface_column_tree(const Parameter& shell_depth, std::array<int, 2> columns,
                                      std::vector<LayeredOptions::Layer> layers, const Parameter& backing,
                                      const Limits& limits, NodePtr core) {
  LayeredOptions stack;
  stack.layers = std::move(layers);
  stack.layers.emplace_back().material.parameter = backing;
  ColumnOptions grid;
  grid.count = columns;
  grid.cells.child.node = make_layered(std::move(stack));
  StratumOptions stratum;
  stratum.depth_mm = shell_depth;
  stratum.shell.node = make_column(std::move(grid), limits);
  ReducerNode* column_node = stratum.shell.node.get();
  stratum.core.node = core ? std::move(core) : make_solid_material(backing);
  return {make_stratum(std::move(stratum)), column_node};
}

}  // namespace spec2fab

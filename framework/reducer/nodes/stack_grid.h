#pragma once
/// The stack grid: a texture's columns as one node. Column (i, j) of a grid
/// over the incoming frame's (a, b) holds stack cells[i + na·j] of a table
/// of ink stacks (each ink's thickness, from the surface down, over the
/// fill). It is what a Column node with one Layered child per column
/// expresses, without a node and parameters per column: a photograph
/// printed at printer resolution has millions of columns (issue 21). The
/// stacks are chosen by the texture lookup (translators/pieces/texture.h),
/// not by tuners: the node has no free parameters.

#include <array>
#include <cstdint>
#include <vector>

#include "reducer/node.h"

namespace spec2fab {

class StackGridNode final : public ClonableNode<StackGridNode, MaterialNode> {
 public:
  StackGridNode(const Properties& properties, const NodeContext& context);
  static TypeDoc doc();
  std::string type_name() const override { return "stack_grid"; }

  std::array<int, 2> count() const { return count_; }
  size_t stack_count() const { return thickness_mm_.size() / inks_.size(); }
  /// Sets every column's stack (cells[i + na·j] < stack_count()).
  void set_cells(std::vector<std::uint32_t> cells);
  const std::vector<std::uint32_t>& cells() const { return cells_; }
  /// The column (i + na·j) holding lateral position (a, b), edge columns
  /// extending beyond the grid.
  size_t column_at(double a, double b) const;

  void bind(const FrameDomain& incoming, BindContext& context) override;
  MaterialId material(const QueryPoint& point, const LocalFrame& frame) const override;
  bool possible_materials(std::vector<MaterialId>& out) const override;
  nlohmann::json to_json(const MaterialPalette& palette) const override;

 private:
  std::array<int, 2> count_{1, 1};
  std::vector<MaterialId> inks_;
  MaterialId fill_ = kVoid;
  std::vector<double> thickness_mm_;  ///< stack s, ink k at s·inks + k
  std::vector<double> bottom_mm_;     ///< depth where ink k of stack s ends (cumulative)
  std::vector<std::uint32_t> cells_;
  std::array<double, 2> lower_{0, 0}, cell_{1, 1}, inverse_cell_{1, 1};
};

}  // namespace spec2fab

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
#include <string>
#include <vector>

#include <fmt/format.h>

#include "core/options.h"
#include "reducer/node.h"

namespace spec2fab {

/// "stack_grid"'s options.
struct StackGridOptions {
  std::array<int, 2> count{};
  std::vector<std::string> inks;
  std::vector<std::vector<double>> stacks;
  std::string fill;
  std::vector<int> cells;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.required(o.count, "count", Range::at_least(1), "columns along a and b; column (i, j) is cell i + na·j");
    d.required(o.inks, "inks", "the inks' materials, from the surface down");
    d.required(o.stacks, "stacks", "each stack's ink thicknesses (mm), one per ink, in the inks' order");
    d.required(o.fill, "fill", "the material below every stack");
    d.value(o.cells, "cells", "each column's stack (an index into stacks), column i + na·j", Default{"stack 0 everywhere"});
  }
  bool check(std::string* why) const {
    if (static_cast<long long>(count[0]) * count[1] > 64'000'000) *why = "count: more than 64 million columns";
    else if (inks.empty()) *why = "inks: at least one ink";
    else if (stacks.empty()) *why = "stacks: at least one stack";
    else if (!cells.empty() && cells.size() != static_cast<size_t>(count[0]) * static_cast<size_t>(count[1]))
      *why = fmt::format("cells: {} given for {} x {} columns", cells.size(), count[0], count[1]);
    else return true;
    return false;
  }
};


class StackGridNode final : public ClonableNode<StackGridNode, MaterialNode> {
 public:
  StackGridNode(const Properties& properties, const NodeContext& context);
  /// Built in C++ (the albedo translator keeps it to set its cells):
  /// `where` names the node in errors about inks and stacks ("exp.json:
  /// /goal/tree", which "/stacks/0" follows).
  StackGridNode(StackGridOptions options, const MaterialPalette& palette, const std::string& where);
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

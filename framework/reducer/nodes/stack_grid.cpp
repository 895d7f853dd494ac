// Stack grid material node: a texture's columns, each one of a table of ink
// stacks, in one node (see stack_grid.h).

#include "reducer/nodes/stack_grid.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "core/options.h"

namespace spec2fab {

StackGridNode::StackGridNode(const Properties& properties, const NodeContext& context)
    : StackGridNode(read_options<StackGridOptions>(properties), context.palette,
                    properties.origin() + ": " + properties.pointer()) {}

StackGridNode::StackGridNode(StackGridOptions o, const MaterialPalette& palette, const std::string& where) {
  require_valid(o, "stack_grid");
  count_ = o.count;
  for (size_t k = 0; k < o.inks.size(); ++k) inks_.push_back(palette.id(o.inks[k], where + "/inks"));
  fill_ = palette.id(o.fill, where + "/fill");
  for (size_t s = 0; s < o.stacks.size(); ++s) {
    const std::vector<double>& stack = o.stacks[s];
    const std::string at = where + "/stacks/" + std::to_string(s) + ": ";
    if (stack.size() != inks_.size())
      throw InputError(at + fmt::format("{} thicknesses for {} inks", stack.size(), inks_.size()));
    double depth = 0;
    for (double t : stack) {
      if (!(t >= 0 && t <= 1e4)) throw InputError(at + "thicknesses must lie in [0, 1e4] mm");
      thickness_mm_.push_back(t);
      bottom_mm_.push_back(depth += t);
    }
  }
  const size_t columns = static_cast<size_t>(count_[0]) * static_cast<size_t>(count_[1]);
  if (o.cells.empty()) o.cells.assign(columns, 0);
  cells_.reserve(columns);
  for (int c : o.cells) {
    if (c < 0 || static_cast<size_t>(c) >= o.stacks.size())
      throw InputError(where + "/cells: " + fmt::format("no stack {} (there are {})", c, o.stacks.size()));
    cells_.push_back(static_cast<std::uint32_t>(c));
  }
}

TypeDoc StackGridNode::doc() {
  return {"Material node: a grid of columns over the incoming frame's (a, b), each column one stack of a "
          "table of ink stacks (each ink's thickness from the surface along w, then the fill) — a Column "
          "node with a Layered child per column, in one node without parameters, for textures of millions "
          "of columns (the albedo translator's lookup fills it). Points outside the grid take the nearest "
          "edge column.",
          option_docs<StackGridOptions>(),
          R"({"type": "stack_grid", "count": [2, 1], "inks": ["VeroCyan"], "stacks": [[0], [0.054]], )"
          R"("fill": "VeroWhitePlus", "cells": [0, 1]})"};
}

void StackGridNode::set_cells(std::vector<std::uint32_t> cells) {
  if (cells.size() != cells_.size()) throw std::invalid_argument("StackGridNode::set_cells: wrong column count");
  const size_t stacks = stack_count();
  if (std::any_of(cells.begin(), cells.end(), [&](std::uint32_t c) { return c >= stacks; }))
    throw std::invalid_argument("StackGridNode::set_cells: no such stack");
  cells_ = std::move(cells);
}

void StackGridNode::bind(const FrameDomain& incoming, BindContext& /*context*/) {
  lower_ = {incoming.box.min().x(), incoming.box.min().y()};
  for (int k = 0; k < 2; ++k) {
    cell_[k] = (incoming.box.max()[k] - lower_[k]) / count_[k];
    inverse_cell_[k] = 1.0 / cell_[k];
  }
}

size_t StackGridNode::column_at(double a, double b) const {
  const int i = std::clamp(static_cast<int>(std::floor((a - lower_[0]) * inverse_cell_[0])), 0, count_[0] - 1);
  const int j = std::clamp(static_cast<int>(std::floor((b - lower_[1]) * inverse_cell_[1])), 0, count_[1] - 1);
  return static_cast<size_t>(i) + static_cast<size_t>(count_[0]) * static_cast<size_t>(j);
}

MaterialId StackGridNode::material(const QueryPoint& /*point*/, const LocalFrame& frame) const {
  const size_t inks = inks_.size();
  const double* bottom = bottom_mm_.data() + cells_[column_at(frame.a, frame.b)] * inks;
  for (size_t k = 0; k < inks; ++k)
    if (frame.w < bottom[k]) return inks_[k];
  return fill_;
}

bool StackGridNode::possible_materials(std::vector<MaterialId>& out) const {
  out.insert(out.end(), inks_.begin(), inks_.end());
  out.push_back(fill_);
  return true;
}

nlohmann::json StackGridNode::to_json(const MaterialPalette& palette) const {
  nlohmann::json inks = nlohmann::json::array(), stacks = nlohmann::json::array();
  for (MaterialId id : inks_) inks.push_back(palette.name(id));
  for (size_t s = 0; s < stack_count(); ++s)
    stacks.push_back(std::vector<double>(thickness_mm_.begin() + static_cast<std::ptrdiff_t>(s * inks_.size()),
                                         thickness_mm_.begin() + static_cast<std::ptrdiff_t>((s + 1) * inks_.size())));
  return {{"type", type_name()}, {"count", count_}, {"inks", inks},   {"stacks", stacks},
          {"fill", palette.name(fill_)}, {"cells", cells_}};
}

}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::NodeRegistry, spec2fab::StackGridNode, "stack_grid")

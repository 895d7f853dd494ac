// Nodes composed in C++ (reducer/nodes/nodes.h) are the nodes the registry
// reads from JSON: a typed tree and the same tree written as JSON give the
// same node, parameter for parameter (to_json, which tree.json writes), and
// options a translator gets wrong are refused as its bug (std::logic_error),
// not as the user's input.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "reducer/height_surface.h"
#include "reducer/nodes/nodes.h"
#include "reducer/nodes/stack_grid.h"
#include "reducer_test_support.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

class TypedNodes : public ::testing::Test {
 protected:
  TypedNodes() : palette_(testing::make_palette({"A", "B", "C"})) {}

  Parameter material(const std::string& name) const { return fixed_material(*palette_, name, "test"); }
  NodePtr leaf(const std::string& name) const { return make_solid_material(material(name)); }
  // The node JSON describes, written back as build_node's reader sees it.
  nlohmann::json from_json(const std::string& json) const {
    return testing::make_tree(json, *palette_)->root().to_json(*palette_);
  }

  std::shared_ptr<MaterialPalette> palette_;
};

TEST_F(TypedNodes, LayeredWithFreeStepsAndChoicesIsTheJsonOne) {
  LayeredOptions o;
  o.layers.resize(2);
  o.layers[0].material.parameter = material_choice(*palette_, "B", {"A", "B"}, "test");
  o.layers[0].thickness_mm = free_steps(0.1, 0, 0.5, 0.1);
  o.layers[1].material.parameter = material("C");
  o.layers[1].thickness_mm = number_choice(0.2, {0.1, 0.2, 0.4});
  o.fill.parameter = material("A");
  EXPECT_EQ(make_layered(std::move(o))->to_json(*palette_),
            from_json(R"({"type": "layered", "layers": [
                {"material": {"value": "B", "choices": ["A", "B"]},
                 "thickness_mm": {"value": 0.1, "min": 0, "max": 0.5, "step": 0.1}},
                {"material": "C", "thickness_mm": {"value": 0.2, "choices": [0.1, 0.2, 0.4]}}],
                "fill": "A"})"));
}

TEST_F(TypedNodes, ColumnOfParaboloidsIsTheJsonOne) {
  ParaboloidOptions lens;
  lens.cut.axis = "z";
  lens.offset_mm = fixed_number(5, lens.offset_mm);
  lens.slope_a = lens.slope_b = free_number(0, -1, 1);
  lens.curvature_aa = lens.curvature_ab = lens.curvature_bb = free_number(0, -0.5, 0.5);
  lens.cut.below.node = leaf("A");
  lens.cut.above.node = leaf("void");
  ColumnOptions grid;
  grid.count = {3, 2};
  grid.domain = {0, 0, 30, 20};
  grid.cells.child.node = make_paraboloid(std::move(lens));
  const NodePtr typed = make_column(std::move(grid), Limits());
  EXPECT_EQ(typed->to_json(*palette_), from_json(R"({"type": "column", "count": [3, 2], "domain": [0, 0, 30, 20],
      "child": {"type": "paraboloid", "axis": "z", "offset_mm": 5,
        "slope_a": {"value": 0, "min": -1, "max": 1}, "slope_b": {"value": 0, "min": -1, "max": 1},
        "curvature_aa": {"value": 0, "min": -0.5, "max": 0.5}, "curvature_ab": {"value": 0, "min": -0.5, "max": 0.5},
        "curvature_bb": {"value": 0, "min": -0.5, "max": 0.5},
        "below": {"type": "layered", "material": "A"}, "above": {"type": "layered", "material": "void"}}})"));
  // The capability a caller needs is declared, not found by a cast.
  ASSERT_NE(typed->child(4).height_surface(), nullptr);
  EXPECT_EQ(typed->child(4).height_surface()->height_axis(), 2);
  EXPECT_EQ(typed->height_surface(), nullptr);
}

TEST_F(TypedNodes, StratumOverBSplineAndVoxelAreTheJsonOnes) {
  BSplineOptions spline;
  spline.cut.axis = "w";
  spline.control = {4, 3};
  spline.heights_mm.common = free_number(2, 1, 3);
  spline.cut.below.node = leaf("B");
  spline.cut.above.node = leaf("void");
  StratumOptions stratum;
  stratum.depth_mm = fixed_number(1.5, stratum.depth_mm);
  stratum.shell.node = make_bspline(std::move(spline));
  VoxelOptions cells;
  cells.size_mm.edges = {2, 2, 4};
  cells.origin = {0, 0, 0};
  cells.cells.child.node = make_solid_material(material_choice(*palette_, "A", {"A", "C"}, "test"));
  stratum.core.node = make_voxel(std::move(cells));
  EXPECT_EQ(make_stratum(std::move(stratum))->to_json(*palette_),
            from_json(R"({"type": "stratum", "depth_mm": 1.5,
      "shell": {"type": "bspline", "axis": "w", "control": [4, 3], "heights_mm": {"value": 2, "min": 1, "max": 3},
        "below": {"type": "layered", "material": "B"}, "above": {"type": "layered", "material": "void"}},
      "core": {"type": "voxel", "size_mm": [2, 2, 4], "origin": [0, 0, 0],
        "child": {"type": "layered", "material": {"value": "A", "choices": ["A", "C"]}}}})"));
}

TEST_F(TypedNodes, StackGridIsTheJsonOne) {
  StackGridOptions o;
  o.count = {2, 1};
  o.inks = {"A", "B"};
  o.stacks = {{0.1, 0}, {0, 0.2}};
  o.fill = "C";
  o.cells = {1, 0};
  const StackGridNode typed(o, *palette_, "test");
  EXPECT_EQ(typed.to_json(*palette_), from_json(R"({"type": "stack_grid", "count": [2, 1], "inks": ["A", "B"],
      "stacks": [[0.1, 0], [0, 0.2]], "fill": "C", "cells": [1, 0]})"));
}

// What a translator gets wrong is its own bug, never the user's input.
TEST_F(TypedNodes, OptionsATranslatorGetsWrongAreItsBug) {
  PlaneOptions childless;
  EXPECT_THROW(make_plane(std::move(childless)), std::logic_error);
  ColumnOptions none;
  none.count = {2, 2};
  EXPECT_THROW(make_column(std::move(none), Limits()), std::logic_error) << "neither child nor children";
  ColumnOptions empty;
  empty.count = {0, 2};
  empty.cells.child.node = leaf("A");
  try {
    make_column(std::move(empty), Limits());
    ADD_FAILURE() << "a column of 0 x 2 was built";
  } catch (const std::logic_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("column: options built in C++ do not hold: count"));
  }
  EXPECT_THROW(fixed_number(2e5, PlaneOptions{}.offset_mm), std::logic_error) << "beyond the declared limits";
  EXPECT_THROW(free_number(2, 0, 1), std::logic_error);
  EXPECT_THROW(material_choice(*palette_, "C", {"A", "B"}, "test"), std::logic_error);
  EXPECT_THROW(number_choice(0.3, {0.1, 0.2}), std::logic_error);
  StratumOptions coreless;
  coreless.shell.node = leaf("A");
  EXPECT_THROW(make_stratum(std::move(coreless)), std::logic_error);
}

}  // namespace
}  // namespace spec2fab

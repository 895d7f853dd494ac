// Routing and local frames of each node type in the world frame of a box, and
// parameter/search-space semantics of trees built from JSON.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "reducer/height_surface.h"
#include "reducer_test_support.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

class NodesInBox : public ::testing::Test {
 protected:
  NodesInBox()
      : solid_(make_box(Vec3(-10, -10, -10), Vec3(10, 10, 10), 2), UvSource::planar, 2),
        palette_(testing::make_palette({"A", "B", "C", "D"})) {}

  std::unique_ptr<ReducerTree> bound(const std::string& json) {
    auto tree = testing::make_tree(json, *palette_);
    tree->bind(solid_);
    return tree;
  }
  std::string at(const ReducerTree& tree, const Vec3& p) { return palette_->name(tree.material_at(p)); }

  Solid solid_;
  std::shared_ptr<MaterialPalette> palette_;
};

TEST_F(NodesInBox, TiltedPlaneSplitsAndMeasuresDepthAlongAxis) {
  // Height = 1 + 0.5·x − 0.25·y about the domain centre (0, 0); below: 1 mm of A then B.
  auto tree = bound(R"({"type": "plane", "offset_mm": 1, "slope_a": 0.5, "slope_b": -0.25,
      "below": {"type": "layered", "layers": [{"material": "A", "thickness_mm": 1}], "fill": "B"},
      "above": {"type": "layered", "material": "C"}})");
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> coord(-9.5, 9.5);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(coord(rng), coord(rng), coord(rng));
    const double height = 1 + 0.5 * p.x() - 0.25 * p.y();
    const double depth = height - p.z();
    if (std::abs(depth) < 1e-6 || std::abs(depth - 1) < 1e-6) continue;
    const std::string expected = depth < 0 ? "C" : depth < 1 ? "A" : "B";
    ASSERT_EQ(at(*tree, p), expected) << p.transpose();
  }
}

// A paraboloid: height 1 + 0.5·x − 0.25·y + ½(0.1·x² + 2·0.04·x·y − 0.06·y²)
// about the domain centre (0, 0); below A, above C.
TEST_F(NodesInBox, ParaboloidSplitsAlongItsCurvedHeight) {
  auto tree = bound(R"({"type": "paraboloid", "offset_mm": 1, "slope_a": 0.5, "slope_b": -0.25,
      "curvature_aa": 0.1, "curvature_ab": 0.04, "curvature_bb": -0.06,
      "below": {"type": "layered", "material": "A"}, "above": {"type": "layered", "material": "C"}})");
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-9.5, 9.5);
  int below = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(coord(rng), coord(rng), coord(rng));
    const double height = 1 + 0.5 * p.x() - 0.25 * p.y() +
                          0.5 * (0.1 * p.x() * p.x() + 0.08 * p.x() * p.y() - 0.06 * p.y() * p.y());
    if (std::abs(height - p.z()) < 1e-6) continue;
    below += p.z() < height;
    ASSERT_EQ(at(*tree, p), p.z() < height ? "A" : "C") << p.transpose();
  }
  EXPECT_GT(below, 200);
  EXPECT_LT(below, 1800);
}

// The paraboloid's height is linear in its six parameters: the derivatives
// it reports are the change of height a step in each parameter makes.
TEST_F(NodesInBox, ParaboloidHeightDerivativesMatchSteps) {
  auto tree = bound(R"({"type": "paraboloid", "offset_mm": 1, "slope_a": 0.5, "slope_b": -0.25,
      "curvature_aa": 0.1, "curvature_ab": 0.04, "curvature_bb": -0.06,
      "below": {"type": "layered", "material": "A"}, "above": {"type": "layered", "material": "C"}})");
  ASSERT_NE(tree->root().height_surface(), nullptr) << "a paraboloid declares its height surface";
  EXPECT_EQ(tree->root().child(0).height_surface(), nullptr) << "a layered node has none";
  const HeightSurface& surface = *tree->root().height_surface();
  const double a = 3.5, b = -2;
  std::map<const Parameter*, double> reported;
  surface.visit_height_derivatives(a, b, [&](const Parameter& p, double d) { reported[&p] += d; });
  int checked = 0;
  tree->root().visit_parameters([&](const std::string& name, Parameter& p) {
    const double before = surface.surface_height(a, b), value = p.value();
    p.set(value + 0.5);
    tree->root().evaluate();
    EXPECT_NEAR((surface.surface_height(a, b) - before) / 0.5, reported[&p], 1e-12) << name;
    p.set(value);
    tree->root().evaluate();
    ++checked;
  });
  EXPECT_EQ(checked, 6);
}

TEST_F(NodesInBox, PlaneAlongXAxis) {
  auto tree = bound(R"({"type": "plane", "axis": "x", "offset_mm": 2,
      "below": {"type": "layered", "material": "A"}, "above": {"type": "layered", "material": "B"}})");
  EXPECT_EQ(at(*tree, Vec3(1.9, 5, -5)), "A");
  EXPECT_EQ(at(*tree, Vec3(2.1, -5, 5)), "B");
}

TEST_F(NodesInBox, BSplineReproducesLinearHeights) {
  // Uniform cubic B-splines reproduce linear functions: control heights
  // h_i = -2 + i over 5 control points along x spanning [-10, 10] give the
  // surface z = x / 5 away from the clamped ends (|x| <= 5).
  std::string heights;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 5; ++i) heights += (heights.empty() ? "" : ", ") + std::to_string(-2 + i);
  }
  auto tree = bound(R"({"type": "bspline", "control": [5, 3], "heights_mm": [)" + heights + R"(],
      "below": {"type": "layered", "layers": [{"material": "A", "thickness_mm": 0.5}], "fill": "B"},
      "above": {"type": "layered", "material": "C"}})");
  for (double x = -5; x <= 5; x += 0.37) {
    for (double y : {-7.0, 0.0, 6.0}) {
      const double surface = x / 5;
      EXPECT_EQ(at(*tree, Vec3(x, y, surface + 0.05)), "C") << x;
      EXPECT_EQ(at(*tree, Vec3(x, y, surface - 0.25)), "A") << x;
      EXPECT_EQ(at(*tree, Vec3(x, y, surface - 0.75)), "B") << x;
    }
  }
}

TEST_F(NodesInBox, BSplineConstantHeightIsFlat) {
  auto tree = bound(R"({"type": "bspline", "control": [6, 6], "heights_mm": 3.5,
      "below": {"type": "layered", "material": "A"}, "above": {"type": "layered", "material": "B"}})");
  for (double x = -9.5; x <= 9.5; x += 1.9) {
    EXPECT_EQ(at(*tree, Vec3(x, -x / 2, 3.45)), "A");
    EXPECT_EQ(at(*tree, Vec3(x, -x / 2, 3.55)), "B");
  }
}

TEST_F(NodesInBox, VoxelCellsAndCellLocalFrame) {
  // 20 mm box, 5 mm cells: 4×4×4; within each cell, A in the lower 2 mm, B above.
  auto tree = bound(R"({"type": "voxel", "size_mm": 5,
      "child": {"type": "layered", "layers": [{"material": "A", "thickness_mm": 2}], "fill": "B"}})");
  EXPECT_EQ(tree->root().child_count(), 64u);
  for (double z = -9.75; z < 10; z += 0.5) {
    const double local = std::fmod(z + 10, 5.0);
    EXPECT_EQ(at(*tree, Vec3(1.3, -4.1, z)), local < 2 ? "A" : "B") << z;
  }
}

TEST_F(NodesInBox, VoxelExplicitChildrenCountIsChecked) {
  const auto palette = testing::make_palette({"A"});
  auto tree = testing::make_tree(
      R"({"type": "voxel", "size_mm": 10, "children": [{"type": "layered", "material": "A"}]})", *palette);
  try {
    tree->bind(solid_);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("tree.json: /children: the domain holds 8 cells (2×2×2), but 1 children are given"));
  }
}

TEST_F(NodesInBox, ColumnsOverWorldXY) {
  auto tree = bound(R"({"type": "column", "count": [4, 1], "children": [
      {"type": "layered", "material": "A"}, {"type": "layered", "material": "B"},
      {"type": "layered", "material": "C"}, {"type": "layered", "material": "D"}]})");
  EXPECT_EQ(at(*tree, Vec3(-9, 0, 0)), "A");
  EXPECT_EQ(at(*tree, Vec3(-4, 3, 0)), "B");
  EXPECT_EQ(at(*tree, Vec3(1, -3, 9)), "C");
  EXPECT_EQ(at(*tree, Vec3(9, 9, -9)), "D");
}

TEST_F(NodesInBox, ColumnLocalFrameFeedsAPlanePerColumn) {
  // Column -> Plane, the paper's facet-caustic tree: each 5 mm column has a
  // plane at height 0 tilted by slope 1 about the column's own centre.
  auto tree = bound(R"({"type": "column", "count": [4, 4], "child": {"type": "plane",
      "offset_mm": 0, "slope_a": 1, "below": {"type": "layered", "material": "A"},
      "above": {"type": "layered", "material": "void"}}})");
  for (double x = -9.8; x < 10; x += 0.4) {
    const double column_centre = -7.5 + 5 * std::floor((x + 10) / 5);
    const double surface = x - column_centre;
    EXPECT_EQ(at(*tree, Vec3(x, 1, surface - 0.1)), "A") << x;
    EXPECT_EQ(tree->material_at(Vec3(x, 1, surface + 0.1)), kVoid) << x;
  }
}

TEST_F(NodesInBox, SearchSpaceListsFreeParametersByPath) {
  auto tree = bound(R"({"type": "stratum", "depth_mm": {"value": 1, "min": 0.5, "max": 3},
      "shell": {"type": "column", "count": [2, 1], "child": {"type": "layered", "layers": [
        {"material": {"value": "A", "choices": ["A", "B"]}, "thickness_mm": {"value": 0.3, "min": 0, "max": 1, "step": 0.1}},
        {"material": "C"}]}},
      "core": {"type": "layered", "material": "D"}})");
  SearchSpace all = tree->all_parameters();
  SearchSpace free = tree->search_space();
  EXPECT_EQ(all.dimension(), 8u);  // depth + 2 columns × (material, thickness, material)
  ASSERT_EQ(free.dimension(), 5u);
  std::vector<std::string> names;
  for (const auto& e : free.entries()) names.push_back(e.name);
  EXPECT_EQ(names, (std::vector<std::string>{"depth_mm", "shell/0/layers/0/material",
                                             "shell/0/layers/0/thickness_mm",
                                             "shell/1/layers/0/material",
                                             "shell/1/layers/0/thickness_mm"}));
  EXPECT_EQ(tree->search_space("shell/1").dimension(), 2u);
  EXPECT_EQ(free.parameter(1).kind(), ParameterKind::choice);
  EXPECT_EQ(free.parameter(2).cardinality(), 11);

  // Changing parameters through the vector changes what the tree assigns.
  const Vec3 p(-5, 0, 10 - 0.2);  // 0.2 mm below the top face, column 0
  EXPECT_EQ(at(*tree, p), "A");
  const double a = palette_->id("A", ""), b = palette_->id("B", "");
  free.set_values({1, b, 0.1, a, 0.3});
  tree->evaluate();
  EXPECT_EQ(at(*tree, p), "C");  // first layer is now 0.1 mm of B
  EXPECT_EQ(at(*tree, Vec3(-5, 0, 10 - 0.05)), "B");
  free.set_values({0.5, b, 0.1, a, 0.3});
  tree->evaluate();
  EXPECT_EQ(at(*tree, Vec3(-5, 0, 10 - 0.7)), "D");  // shell is now 0.5 mm deep
}

TEST_F(NodesInBox, JsonRoundTripAndClone) {
  const std::string json = R"({"type": "stratum", "depth_mm": 1.5,
      "shell": {"type": "column", "count": [3, 2], "child": {"type": "layered", "layers": [
          {"material": "A", "thickness_mm": 0.25}, {"material": "B"}]}},
      "core": {"type": "bspline", "control": [3, 3], "heights_mm": {"value": 0, "min": -5, "max": 5},
          "below": {"type": "voxel", "size_mm": [4, 5, 6], "child": {"type": "layered", "material": "C"}},
          "above": {"type": "plane", "axis": "y", "slope_b": 0.5,
                    "below": {"type": "layered", "material": "D"}, "above": {"type": "layered", "material": "void"}}}})";
  auto tree = bound(json);
  const nlohmann::json written = tree->to_json();
  auto again = testing::make_tree(written.dump(), *palette_);
  again->bind(solid_);
  EXPECT_EQ(again->to_json(), written);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-10, 10);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(coord(rng), coord(rng), coord(rng));
    ASSERT_EQ(tree->material_at(p), again->material_at(p));
  }
  EXPECT_EQ(tree->root().clone()->to_json(*palette_), tree->root().to_json(*palette_));
}

std::string build_error(const std::string& json, const MaterialPalette& palette) {
  try {
    testing::make_tree(json, palette);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// A stack grid assigns what a Column node with one Layered child per cell
// assigns, at any point of the shell and the core.
TEST_F(NodesInBox, StackGridAssignsWhatColumnsOfLayersDo) {
  auto grid = bound(R"({"type": "stratum", "depth_mm": 3,
      "shell": {"type": "stack_grid", "count": [3, 2], "inks": ["A", "B"],
                "stacks": [[0, 0], [1, 0], [0.5, 1.5], [2, 0.25]], "fill": "C", "cells": [0, 1, 2, 3, 2, 1]},
      "core": {"type": "layered", "material": "D"}})");
  auto stack = [](double a, double b) {
    return R"({"type": "layered", "layers": [{"material": "A", "thickness_mm": )" + std::to_string(a) +
           R"(}, {"material": "B", "thickness_mm": )" + std::to_string(b) + R"(}], "fill": "C"})";
  };
  auto columns = bound(R"({"type": "stratum", "depth_mm": 3,
      "shell": {"type": "column", "count": [3, 2], "children": [)" +
                       stack(0, 0) + "," + stack(1, 0) + "," + stack(0.5, 1.5) + "," + stack(2, 0.25) + "," +
                       stack(0.5, 1.5) + "," + stack(1, 0) + R"(]},
      "core": {"type": "layered", "material": "D"}})");
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> coord(-9.9, 9.9);
  std::map<std::string, int> seen;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 p(coord(rng), coord(rng), coord(rng));
    const std::string expected = at(*columns, p);
    ASSERT_EQ(at(*grid, p), expected) << p.transpose();
    ++seen[expected];
  }
  EXPECT_EQ(seen.size(), 4u);  // both inks, the fill and the core were reached
  // Written back, it reads the same.
  const nlohmann::json written = grid->root().child(0).to_json(*palette_);
  EXPECT_EQ(written["cells"], nlohmann::json({0, 1, 2, 3, 2, 1}));
  EXPECT_EQ(written["stacks"][2], nlohmann::json({0.5, 1.5}));
  EXPECT_EQ(written["inks"], nlohmann::json({"A", "B"}));
}

TEST_F(NodesInBox, StackGridRefusesCellsThatNameNoStack) {
  EXPECT_EQ(build_error(R"({"type": "stack_grid", "count": [2, 1], "inks": ["A"], "stacks": [[0], [1]],
      "fill": "B", "cells": [0, 2]})", *palette_),
            "tree.json: /cells: no stack 2 (there are 2)");
  EXPECT_EQ(build_error(R"({"type": "stack_grid", "count": [2, 1], "inks": ["A"], "stacks": [[0, 1]],
      "fill": "B"})", *palette_),
            "tree.json: /stacks/0: 2 thicknesses for 1 inks");
  EXPECT_THAT(build_error(R"({"type": "stack_grid", "count": [2, 1], "inks": ["A"], "stacks": [[0]],
      "fill": "B", "cells": [0]})", *palette_),
              HasSubstr("cells: 1 given for 2 x 1 columns"));
}

TEST_F(NodesInBox, UnknownNodeTypeListsKnownOnes) {
  EXPECT_THAT(build_error(R"({"type": "stratun", "shell": {}, "core": {}})", *palette_),
              HasSubstr("tree.json: /type: unknown node 'stratun'; did you mean 'stratum'? (known: "
                        "bspline, column, layered, paraboloid, plane, stack_grid, stratum, voxel)"));
}

TEST_F(NodesInBox, UnknownKeyInNestedNode) {
  EXPECT_EQ(build_error(R"({"type": "stratum", "shell": {"type": "layered", "material": "A"},
      "core": {"type": "layered", "layers": [{"material": "B", "thicknes_mm": 1}]}})", *palette_),
            "tree.json: /core/layers/0/thicknes_mm: unknown key; did you mean 'thickness_mm'?");
}

TEST_F(NodesInBox, MaterialMustBeInPalette) {
  EXPECT_THAT(build_error(R"({"type": "layered", "material": "VeroCyan"})", *palette_),
              HasSubstr("tree.json: /material: material 'VeroCyan' is not"));
}

TEST_F(NodesInBox, StructuralErrors) {
  EXPECT_THAT(build_error(R"({"type": "layered", "layers": [{"material": "A"}, {"material": "B"}]})", *palette_),
              HasSubstr("/layers/0/thickness_mm: missing: only the last layer may be unbounded"));
  EXPECT_THAT(build_error(R"({"type": "column", "count": [2, 2], "children": [{"type": "layered", "material": "A"}]})", *palette_),
              HasSubstr("/children: expected 4 nodes, got 1"));
  EXPECT_THAT(build_error(R"({"type": "plane", "axis": "q", "below": {}, "above": {}})", *palette_),
              HasSubstr("tree.json: /axis: unknown value 'q' (known: a, b, w, x, y, z)"));
}

}  // namespace
}  // namespace spec2fab

// The mass_properties simulator against closed forms: two bonded blocks
// (exact on a grid whose cells the interface does not cut), a sphere (the
// mesh's own volume; 2/5 M R²), a print that weighs nothing; its metrics;
// the same sums for any thread count; and a tuner that moves a material
// interface to put the centre of mass where a goal asks.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "mass/mass_properties.h"
#include "materials/palette.h"
#include "simulators/mass_test_palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/optimizer.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;

class MassProperties : public ::testing::Test {
 protected:
  MassProperties() : palette_(light_and_heavy()) {}

  std::unique_ptr<ReducerTree> bound(const std::string& json, const Solid& solid) {
    const Properties properties = Properties::parse(json, "tree.json");
    auto tree = std::make_unique<ReducerTree>(properties, palette_);
    properties.check_all_read();
    tree->bind(solid);
    return tree;
  }
  MassPropertiesObservation simulate(ReducerTree& tree, double voxel_mm) {
    auto simulator = make_mass_properties_simulator({voxel_mm}, PartContext{palette_});
    simulator->setup(tree.root(), SimulationDomain(tree, tree.root()));
    MassPropertiesObservation out;
    simulator->simulate(tree.root(), out);
    failure_ = simulator->failure();
    return out;
  }

  MaterialPalette palette_;
  std::string failure_;
};

// A 40 × 30 × 20 mm box centred on the origin, light for x < 5 and heavy
// above: two blocks whose mass, centre and inertia are textbook sums (each
// block m/12 (a² + b²) about its centre, moved by the parallel-axis
// theorem). Cells of 1 mm are not cut by the interface or the box's faces,
// and a cell's sums with its own inertia integrate x² exactly: equal to
// rounding.
TEST_F(MassProperties, TwoBondedBlocksMatchTheClosedForm) {
  const Solid box(make_box(Vec3(-20, -15, -10), Vec3(20, 15, 10), 2), UvSource::planar, 2);
  auto tree = bound(R"({"type": "plane", "axis": "x", "offset_mm": 5,
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "heavy"}})",
                    box);
  const MassPropertiesObservation out = simulate(*tree, 1.0);

  const double m_light = 25.0 * 30 * 20 * 1e-6, m_heavy = 15.0 * 30 * 20 * 3e-6;  // kg
  const double x_light = -7.5, x_heavy = 12.5;
  const double mass = m_light + m_heavy;
  const double cx = (m_light * x_light + m_heavy * x_heavy) / mass;
  const auto block = [](double m, double a, double b) { return m / 12 * (a * a + b * b); };
  const double ixx = block(m_light, 30, 20) + block(m_heavy, 30, 20);
  const double iyy = block(m_light, 25, 20) + m_light * (x_light - cx) * (x_light - cx) + block(m_heavy, 15, 20) +
                     m_heavy * (x_heavy - cx) * (x_heavy - cx);
  const double izz = block(m_light, 25, 30) + m_light * (x_light - cx) * (x_light - cx) + block(m_heavy, 15, 30) +
                     m_heavy * (x_heavy - cx) * (x_heavy - cx);

  EXPECT_NEAR(out.mass_kg(), mass, 1e-12);
  EXPECT_NEAR(out.centre_mm()[0], cx, 1e-9);
  EXPECT_NEAR(out.centre_mm()[1], 0, 1e-9);
  EXPECT_NEAR(out.centre_mm()[2], 0, 1e-9);
  const double* inertia = out.data.data() + MassPropertiesObservation::kInertia;
  EXPECT_NEAR(inertia[0], ixx, 1e-9 * ixx);
  EXPECT_NEAR(inertia[1], iyy, 1e-9 * iyy);
  EXPECT_NEAR(inertia[2], izz, 1e-9 * izz);
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(inertia[k], 0, 1e-9 * ixx) << "product of inertia " << k;
  EXPECT_NEAR(out.volume_mm3(1), 25.0 * 30 * 20, 1e-6);
  EXPECT_NEAR(out.volume_mm3(2), 15.0 * 30 * 20, 1e-6);
  EXPECT_NEAR(out.volume_mm3(0), 0, 1e-6) << "no void inside";
  EXPECT_EQ(failure_, "");
}

// Eight 20 × 15 × 10 mm blocks (a 2 × 2 × 2 voxel grid over the box), three
// of them heavy and out of symmetry: every product of inertia is non-zero.
// The closed form sums each block's own inertia, m/12 (b² + c²) and so on,
// and m (|d|² I − d dᵀ) for its centre's offset d from the centre of mass.
TEST_F(MassProperties, AsymmetricBlocksMatchTheClosedFormWithProductsOfInertia) {
  const Solid box(make_box(Vec3(-20, -15, -10), Vec3(20, 15, 10), 2), UvSource::planar, 2);
  const std::vector<int> heavy = {0, 3, 5};  // cell i + 2 (j + 2 k)
  std::string children;
  for (int c = 0; c < 8; ++c) {
    const bool is_heavy = std::find(heavy.begin(), heavy.end(), c) != heavy.end();
    children += std::string(c ? ", " : "") + R"({"type": "layered", "material": ")" + (is_heavy ? "heavy" : "light") +
                "\"}";
  }
  auto tree = bound(R"({"type": "voxel", "size_mm": [20, 15, 10], "children": [)" + children + "]}", box);
  const MassPropertiesObservation out = simulate(*tree, 1.0);

  struct Block {
    double m;
    Eigen::Vector3d centre;
  };
  std::vector<Block> blocks;
  for (int c = 0; c < 8; ++c) {
    const int i = c % 2, j = (c / 2) % 2, k = c / 4;
    const bool is_heavy = std::find(heavy.begin(), heavy.end(), c) != heavy.end();
    blocks.push_back({20.0 * 15 * 10 * (is_heavy ? 3e-6 : 1e-6), Eigen::Vector3d(i ? 10 : -10, j ? 7.5 : -7.5, k ? 5 : -5)});
  }
  double mass = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Block& b : blocks) mass += b.m, centre += b.m * b.centre;
  centre /= mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // the tensor, products negative: I = Σ m (|d|² 1 − d dᵀ)
  for (const Block& b : blocks) {
    const Eigen::Vector3d d = b.centre - centre;
    inertia += b.m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    inertia += b.m / 12 * Eigen::Vector3d(15 * 15 + 10 * 10, 20 * 20 + 10 * 10, 20 * 20 + 15 * 15).asDiagonal().toDenseMatrix();
  }
  EXPECT_NEAR(out.mass_kg(), mass, 1e-12);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out.centre_mm()[k], centre[k], 1e-9) << "axis " << k;
  const double* got = out.data.data() + MassPropertiesObservation::kInertia;
  const double expected[] = {inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(got[k], expected[k], 1e-9 * inertia(0, 0)) << "component " << k;
    if (k >= 3) {
      EXPECT_GT(std::abs(expected[k]), 1e-3) << "the case has products of inertia";
    }
  }
}

// A sphere of radius 10 mm (a polyhedron of 64 × 32 facets): its mass is
// the density times the mesh's exact volume, its centre the origin, and its
// inertia 2/5 M R² on every axis with R the radius of a ball of that volume
// (the sampled surface is off by under a cell). Half void carved out of it
// (the upper half) moves the centre down by 3R/8, the hemisphere's centroid.
TEST_F(MassProperties, ABallAndAHemisphereMatchTheirClosedForms) {
  const Solid ball(make_sphere(10, 64, 32), UvSource::planar, 2);
  const double volume = ball.volume(), r = std::cbrt(3 * volume / (4 * std::numbers::pi));
  auto solid_tree = bound(R"({"type": "layered", "material": "heavy"})", ball);
  const MassPropertiesObservation whole = simulate(*solid_tree, 0.25);
  const double mass = 3e-6 * volume;
  EXPECT_NEAR(whole.mass_kg(), mass, 0.005 * mass);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(whole.centre_mm()[k], 0, 0.01) << "axis " << k;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(whole.data[MassPropertiesObservation::kInertia + k], 0.4 * mass * r * r, 0.01 * 0.4 * mass * r * r);
  }

  auto half_tree = bound(R"({"type": "plane", "offset_mm": 0,
      "below": {"type": "layered", "material": "heavy"}, "above": {"type": "layered", "material": "void"}})", ball);
  const MassPropertiesObservation half = simulate(*half_tree, 0.25);
  EXPECT_NEAR(half.mass_kg(), mass / 2, 0.01 * mass);
  EXPECT_NEAR(half.centre_mm()[2], -3 * r / 8, 0.05);
  EXPECT_NEAR(half.volume_mm3(0), volume / 2, 0.01 * volume) << "the carved half is void inside the solid";
}

TEST_F(MassProperties, AllVoidWeighsNothingAndSaysSo) {
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(10, 10, 10)), UvSource::planar, 2);
  auto tree = bound(R"({"type": "layered", "material": "void"})", box);
  const MassPropertiesObservation out = simulate(*tree, 1.0);
  EXPECT_EQ(out.mass_kg(), 0);
  EXPECT_TRUE(std::isnan(out.centre_mm()[0]));
  EXPECT_THAT(failure_, HasSubstr("weighs nothing"));
  const auto metric = make_centre_offset_metric({});
  const auto goal = make_mass_properties_goal(std::nullopt, std::array<double, 3>{0, 0, 0});
  EXPECT_TRUE(std::isnan(metric->error(out, goal->target()))) << "the worst error, for an optimizer";
}

TEST_F(MassProperties, SumsAreTheSameForAnyThreadCount) {
  const Solid ball(make_sphere(10, 48, 24), UvSource::planar, 2);
  auto tree = bound(R"({"type": "plane", "axis": "y", "offset_mm": 1.3,
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "heavy"}})", ball);
  std::vector<double> one, two;
  {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 1);
    one = simulate(*tree, 0.4).data;
  }
  {
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
    two = simulate(*tree, 0.4).data;
  }
  EXPECT_EQ(one, two);
}

// Voxel cells and layers are integrated exactly over the solid's mesh, on
// any sampling grid: the eight blocks above, one of them two layers (heavy
// below 4 mm of its cell, light above) and one void, at a 7.3 mm grid that
// no face lies on, against the blocks' closed form; and a polyhedral
// sphere under a voxel grid weighs its mesh's volume to rounding, where 3 mm
// cells sampled would be off by per cent.
TEST_F(MassProperties, VoxelCellsAndLayersAreExactOnAnyGrid) {
  const Solid box(make_box(Vec3(-20, -15, -10), Vec3(20, 15, 10), 2), UvSource::planar, 2);
  std::string children;
  for (int c = 0; c < 8; ++c) {
    const char* cell = c == 0   ? R"({"type": "layered", "layers": [{"material": "heavy", "thickness_mm": 4}, {"material": "light"}]})"
                       : c == 6 ? R"({"type": "layered", "material": "void"})"
                       : c % 3  ? R"({"type": "layered", "material": "light"})"
                                : R"({"type": "layered", "material": "heavy"})";
    children += std::string(c ? ", " : "") + cell;
  }
  auto tree = bound(R"({"type": "voxel", "size_mm": [20, 15, 10], "children": [)" + children + "]}", box);
  const MassPropertiesObservation out = simulate(*tree, 7.3);
  struct Block {
    double m;
    Eigen::Vector3d centre, size;
  };
  std::vector<Block> blocks;
  for (int c = 0; c < 8; ++c) {
    const int i = c % 2, j = (c / 2) % 2, k = c / 4;
    const Eigen::Vector3d corner(i ? 0 : -20, j ? 0 : -15, k ? 0 : -10), size(20, 15, 10);
    const auto add = [&](double density, double z0, double z1) {
      const Eigen::Vector3d lo = corner + Eigen::Vector3d(0, 0, z0), dims(20, 15, z1 - z0);
      blocks.push_back({density * dims.prod(), lo + dims / 2, dims});
    };
    if (c == 0) add(3e-6, 0, 4), add(1e-6, 4, 10);
    else if (c != 6) add(c % 3 ? 1e-6 : 3e-6, 0, 10);
  }
  double mass = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Block& b : blocks) mass += b.m, centre += b.m * b.centre;
  centre /= mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const Block& b : blocks) {
    const Eigen::Vector3d d = b.centre - centre, q = b.size.cwiseProduct(b.size);
    inertia += b.m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
    inertia += b.m / 12 * Eigen::Vector3d(q.y() + q.z(), q.x() + q.z(), q.x() + q.y()).asDiagonal().toDenseMatrix();
  }
  EXPECT_NEAR(out.mass_kg(), mass, 1e-12 * mass);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out.centre_mm()[k], centre[k], 1e-9) << "axis " << k;
  const double* got = out.data.data() + MassPropertiesObservation::kInertia;
  const double expected[] = {inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(got[k], expected[k], 1e-9 * inertia(0, 0)) << "component " << k;
  EXPECT_NEAR(out.volume_mm3(0), 3000, 1e-6) << "the void cell";

  const Solid ball(make_sphere(10, 32, 16), UvSource::planar, 2);
  auto cells = bound(R"({"type": "voxel", "size_mm": 6.1, "child": {"type": "layered", "material": "light"}})", ball);
  const double exact = 1e-6 * ball.mesh().signed_volume();
  EXPECT_NEAR(simulate(*cells, 3).mass_kg(), exact, 1e-12 * exact);
  auto whole = bound(R"({"type": "stratum", "depth_mm": 0.5, "shell": {"type": "layered", "material": "light"},
      "core": {"type": "layered", "material": "light"}})", ball);
  const double sampled = simulate(*whole, 3).mass_kg();
  std::printf("sphere: exact %.9g kg, sampled on 3 mm cells %.9g kg (%+.2f %%)\n", exact, sampled,
              100 * (sampled / exact - 1));
  EXPECT_GT(std::abs(sampled / exact - 1), 1e-3) << "the grid the exact path does not need";
}

// Tuned voxel cells on the exact path: a grid whose origin lies inside the
// box (its outer cells reach past the grid, as route() clamps to them),
// each cell light, heavy or void, against the cells' boxes in closed form
// at a 6.7 mm grid; and the mass bound, complete, is the metric's error.
TEST_F(MassProperties, TunedVoxelCellsAreExactAndSoIsTheirBound) {
  const Solid box(make_box(Vec3(-20, -15, -10), Vec3(20, 15, 10), 2), UvSource::planar, 2);
  auto tree = bound(R"({"type": "voxel", "size_mm": 15, "origin": [-12, -8, -4],
      "child": {"type": "layered", "material": {"value": "light", "choices": ["light", "heavy", "void"]}}})", box);
  SearchSpace space = tree->search_space();
  ASSERT_EQ(space.dimension(), 6u) << "3 x 2 x 1 cells";
  const std::vector<double> ids = {0, 1, 2, 2, 0, 1};  // void, light, heavy, ...
  space.set_values(ids);
  tree->evaluate();
  const MassPropertiesObservation out = simulate(*tree, 6.7);
  // The cells' boxes: x at -20 | 3 | 18 | 20, y at -15 | 7 | 15, z whole.
  const double xs[] = {-20, 3, 18, 20}, ys[] = {-15, 7, 15};
  const double density[] = {0, 1e-6, 3e-6};  // void, light, heavy (kg/mm³)
  double mass = 0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // ∫ρ x xᵀ
  for (int c = 0; c < 6; ++c) {
    const int i = c % 3, j = c / 3;
    const Eigen::Vector3d lo(xs[i], ys[j], -10), hi(xs[i + 1], ys[j + 1], 10), size = hi - lo, mid = (lo + hi) / 2;
    const double m = density[static_cast<size_t>(ids[static_cast<size_t>(c)])] * size.prod();
    mass += m;
    first += m * mid;
    second += m * mid * mid.transpose();
    second += m / 12 * size.cwiseProduct(size).asDiagonal().toDenseMatrix();
  }
  const Eigen::Vector3d centre = first / mass;
  const Eigen::Matrix3d spread = second - mass * centre * centre.transpose();  // ∫ρ d dᵀ about the centre
  const Eigen::Matrix3d inertia = spread.trace() * Eigen::Matrix3d::Identity() - spread;
  EXPECT_NEAR(out.mass_kg(), mass, 1e-12 * mass);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(out.centre_mm()[k], centre[k], 1e-9) << "axis " << k;
  const double* got = out.data.data() + MassPropertiesObservation::kInertia;
  const double expected[] = {inertia(0, 0), inertia(1, 1), inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2)};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(got[k], expected[k], 1e-9 * inertia(0, 0)) << "component " << k;
  const MassBound lower = make_mass_bound(*tree, space, {6.7}, PartContext{palette_});
  ASSERT_TRUE(lower);
  EXPECT_NEAR(lower(ids, 6, 0.01), std::abs(mass - 0.01) * 1e3, 1e-9);
}

// A voxel core whose cells' materials are the only free parameters is summed
// per cell once and reweighed (the leaf sums); a free stratum depth (one
// choice: the same geometry) makes the simulator sample every cell each
// time. Both must give the same mass properties, for any assignment, and
// after a fixed parameter changed under the simulator.
TEST_F(MassProperties, LeafSumsEqualSamplingEveryCell) {
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  const auto tree_json = [](const std::string& depth, const std::string& shell = "heavy") {
    return R"({"type": "stratum", "depth_mm": )" + depth + R"(,
      "shell": {"type": "layered", "material": {"value": ")" + shell + R"(", "choices": ["heavy", "light"], "free": false}},
      "core": {"type": "voxel", "size_mm": [9.5, 28, 18], "origin": [2, 2, 2],
        "child": {"type": "layered", "material": {"value": "light", "choices": ["light", "heavy", "void"]}}}})";
  };
  auto reweighed = bound(tree_json("2"), box);
  // Which path each tree takes: the leaf sums hold the core's four cells
  // (together the 36 × 26 × 16 mm core on 0.7 mm cells, within a cell layer
  // of its faces), and none where a geometry parameter is free.
  const auto volumes = tuned_leaf_volumes(*reweighed, {0.7}, PartContext{palette_});
  ASSERT_EQ(volumes.size(), 4u);
  double core = 0;
  for (const auto& [leaf, mm3] : volumes) core += mm3;
  EXPECT_NEAR(core, 36.0 * 26 * 16, 0.7 * 2 * (36 * 26 + 36 * 16 + 26 * 16));
  {
    const Solid other(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
    auto free_depth = bound(tree_json(R"({"value": 2, "choices": [2]})"), other);
    EXPECT_TRUE(tuned_leaf_volumes(*free_depth, {0.7}, PartContext{palette_}).empty());
  }
  auto fast = make_mass_properties_simulator({0.7}, PartContext{palette_});
  fast->setup(reweighed->root(), SimulationDomain(*reweighed, reweighed->root()));
  // The same assignment on a tree that must be sampled cell by cell.
  const auto expect_same = [&](const std::vector<double>& ids, const std::string& depth,
                                const std::string& shell = "heavy") {
    SearchSpace cells = reweighed->search_space();
    ASSERT_EQ(cells.dimension(), 4u);
    cells.set_values(ids);
    reweighed->evaluate();
    // A solid of its own: a deeper band would rebuild a shared solid's
    // field under the first tree (Solid::field keeps one).
    const Solid same_box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
    auto sampled = bound(tree_json(depth, shell), same_box);
    SearchSpace same = sampled->search_space("core");
    same.set_values(ids);
    sampled->evaluate();
    MassPropertiesObservation a, b;
    fast->simulate(reweighed->root(), a);
    auto slow = make_mass_properties_simulator({0.7}, PartContext{palette_});
    slow->setup(sampled->root(), SimulationDomain(*sampled, sampled->root()));
    slow->simulate(sampled->root(), b);
    ASSERT_EQ(a.data.size(), b.data.size());
    for (size_t k = 0; k < a.data.size(); ++k) {
      EXPECT_NEAR(a.data[k], b.data[k], 1e-9 * (1 + std::abs(b.data[k]))) << depth << ", value " << k;
    }
  };
  expect_same({1, 1, 1, 1}, R"({"value": 2, "choices": [2]})");
  expect_same({0, 2, 1, 2}, R"({"value": 2, "choices": [2]})");
  expect_same({2, 2, 2, 0}, R"({"value": 2, "choices": [2]})");
  // A fixed parameter (the shell's material) changed after setup: the sums are taken again.
  reweighed->node("shell").visit_parameters([](const std::string&, Parameter& p) { p.set(1); });
  reweighed->evaluate();
  expect_same({0, 2, 1, 2}, R"({"value": 2, "choices": [2]})", "light");
}

// The mass bound for branch and bound: complete, it is the metric's error;
// partial, it is never above the least error of any completion (all 3^k of
// them tried), and it is 0 where the target lies within reach.
TEST_F(MassProperties, TheMassBoundIsExactWhenCompleteAndBelowEveryCompletion) {
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  auto tree = bound(R"({"type": "stratum", "depth_mm": 2, "shell": {"type": "layered", "material": "heavy"},
      "core": {"type": "voxel", "size_mm": [9.5, 28, 18], "origin": [2, 2, 2],
        "child": {"type": "layered", "material": {"value": "light", "choices": ["light", "heavy", "void"]}}}})",
                    box);
  SearchSpace space = tree->search_space();
  ASSERT_EQ(space.dimension(), 4u);
  const MassBound lower = make_mass_bound(*tree, space, {0.7}, PartContext{palette_});
  ASSERT_TRUE(lower);
  const double target_kg = 0.05;
  const auto error_of = [&](const std::vector<double>& ids) {
    space.set_values(ids);
    tree->evaluate();
    return std::abs(simulate(*tree, 0.7).mass_kg() - target_kg) * 1e3;
  };
  const std::vector<double> ids = {2, 0, 1, 2};  // heavy, void, light, heavy
  EXPECT_NEAR(lower(ids, 4, target_kg), error_of(ids), 1e-9);
  for (int assigned = 0; assigned < 4; ++assigned) {
    double least = 1e300;
    std::vector<double> x = ids;
    for (int code = 0; code < 81; ++code) {  // every completion of the unassigned tail
      int c = code;
      bool repeat = false;
      for (int k = 0; k < 4; ++k, c /= 3) {
        if (k < assigned) repeat = repeat || c % 3 != 0;
        else x[static_cast<size_t>(k)] = c % 3;
      }
      if (!repeat) least = std::min(least, error_of(x));
    }
    EXPECT_LE(lower(ids, assigned, target_kg), least + 1e-9) << assigned << " assigned";
  }
  EXPECT_EQ(lower(ids, 0, target_kg), 0) << "50 g lies between the lightest and the heaviest core";
  EXPECT_GT(lower(ids, 0, 1.0), 0) << "1 kg lies beyond the heaviest";
  // Choices that weigh the same (void filled with a gel as dense as
  // "heavy"): each leaf still counts once, so the complete bound is exact.
  Material gel;
  gel.name = "gel";
  gel.density_kg_m3.value = 3000;
  palette_.set_cavity_fill(gel);
  const Solid same_box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  auto even = bound(R"({"type": "stratum", "depth_mm": 2, "shell": {"type": "layered", "material": "light"},
      "core": {"type": "voxel", "size_mm": [9.5, 28, 18], "origin": [2, 2, 2],
        "child": {"type": "layered", "material": {"value": "heavy", "choices": ["heavy", "void"]}}}})",
                    same_box);
  SearchSpace even_space = even->search_space();
  const MassBound even_lower = make_mass_bound(*even, even_space, {0.7}, PartContext{palette_});
  ASSERT_TRUE(even_lower);
  const std::vector<double> carved = {2, 0, 2, 0};
  even_space.set_values(carved);
  even->evaluate();
  const double even_error = std::abs(simulate(*even, 0.7).mass_kg() - target_kg) * 1e3;
  EXPECT_NEAR(even_lower(carved, 4, target_kg), even_error, 1e-9);
  EXPECT_NEAR(even_lower(carved, 0, target_kg), even_error, 1e-9) << "no choice changes the mass";
  // A free shell depth is no leaf's material: no bound.
  auto depth = bound(R"({"type": "stratum", "depth_mm": {"value": 2, "choices": [1, 2]},
      "shell": {"type": "layered", "material": "heavy"}, "core": {"type": "layered", "material": "light"}})", box);
  EXPECT_FALSE(make_mass_bound(*depth, depth->search_space(), {0.7}, PartContext{palette_}));
}

// A shell's thickness tuned in steps (a stratum depth with a step, first in
// the space) with the cells: each depth has its own leaf sums, which agree
// with sampling every cell of the same tree at that depth, whichever depth
// came before; and the mass bound is exact when complete and never above
// the least error of any completion (every depth and cell value tried),
// with the depth assigned or not; a space of the cells alone, the depth
// free outside it, has none.
TEST_F(MassProperties, AShellThicknessInStepsHasLeafSumsAndABoundPerThickness) {
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  const std::string core = R"("core": {"type": "voxel", "size_mm": [20, 30, 20], "origin": [0, 0, 0],
        "child": {"type": "layered", "material": {"value": "light", "choices": ["light", "heavy", "void"]}}}})";
  auto tree = bound(R"({"type": "stratum", "depth_mm": {"value": 2, "min": 2, "max": 4, "step": 1},
      "shell": {"type": "layered", "material": "heavy"}, )" + core, box);
  SearchSpace space = tree->search_space();
  ASSERT_EQ(space.dimension(), 3u);
  EXPECT_EQ(space.entries()[0].name, "depth_mm");
  const MassBound lower = make_mass_bound(*tree, space, {0.7}, PartContext{palette_});
  ASSERT_TRUE(lower) << "a stepped depth ahead of the cells has a bound";
  EXPECT_EQ(space.values(), (std::vector<double>{2, 1, 1})) << "the tree is left as it was";
  auto fast = make_mass_properties_simulator({0.7}, PartContext{palette_});
  fast->setup(tree->root(), SimulationDomain(*tree, tree->root()));
  const double target_kg = 0.01;
  const auto error_of = [&](const std::vector<double>& x) {
    space.set_values(x);
    tree->evaluate();
    MassPropertiesObservation out;
    fast->simulate(tree->root(), out);
    return std::abs(out.mass_kg() - target_kg) * 1e3;
  };
  // Against the same depth fixed and every cell sampled (a one-value choice).
  for (const std::vector<double>& x : {std::vector<double>{3, 2, 0}, {2, 0, 1}, {4, 1, 2}, {3, 0, 0}}) {
    const double fast_error = error_of(x);
    const Solid same_box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
    auto sampled = bound(R"({"type": "stratum", "depth_mm": {"value": )" + std::to_string(x[0]) +
                             R"(, "choices": [)" + std::to_string(x[0]) + R"(]},
        "shell": {"type": "layered", "material": "heavy"}, )" + core, same_box);
    EXPECT_TRUE(tuned_leaf_volumes(*sampled, {0.7}, PartContext{palette_}).empty());
    SearchSpace cells = sampled->search_space("core");
    cells.set_values({x[1], x[2]});
    sampled->evaluate();
    const double sampled_error = std::abs(simulate(*sampled, 0.7).mass_kg() - target_kg) * 1e3;
    EXPECT_NEAR(fast_error, sampled_error, 1e-9) << "depth " << x[0];
    EXPECT_NEAR(lower(x, 3, target_kg), fast_error, 1e-9) << "depth " << x[0];
  }
  // Every completion of every prefix of x.
  const std::vector<double> x = {3, 2, 0};
  for (int assigned = 0; assigned < 3; ++assigned) {
    double least = 1e300;
    for (double depth : {2.0, 3.0, 4.0}) {
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          const std::vector<double> y = {depth, static_cast<double>(a), static_cast<double>(b)};
          bool agrees = true;
          for (int k = 0; k < assigned; ++k) agrees = agrees && y[static_cast<size_t>(k)] == x[static_cast<size_t>(k)];
          if (agrees) least = std::min(least, error_of(y));
        }
      }
    }
    EXPECT_LE(lower(x, assigned, target_kg), least + 1e-9) << assigned << " assigned";
    EXPECT_GT(lower(x, assigned, target_kg), 0) << "10 g is lighter than any completion";
  }
  EXPECT_LT(lower(x, 0, target_kg), lower(x, 1, target_kg)) << "the thinnest shell, open, weighs less than 3 mm";
  // The cells alone, the depth left free for someone else to move: no bound.
  EXPECT_FALSE(make_mass_bound(*tree, tree->search_space("core"), {0.7}, PartContext{palette_}));
}

// A printer whose cavities fill with its support (PolyJet): void inside the
// solid weighs the fill's density, on both paths. A 40 × 30 × 20 box, light
// for x < 10 and void above: 10 and 30 mm blocks of 1000 and 1100 kg/m³
// (closed form, cells not cut); the voxel core of the leaf-sum test, its
// cells void, light and heavy, against the same tree sampled cell by cell.
TEST_F(MassProperties, CavitiesWeighWhatFillsThePrintersCavities) {
  Material gel;
  gel.name = "gel";
  gel.density_kg_m3.value = 1100;
  palette_.set_cavity_fill(gel);
  const Solid box(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
  auto split = bound(R"({"type": "plane", "axis": "x", "offset_mm": 10,
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "void"}})", box);
  const MassPropertiesObservation out = simulate(*split, 1.0);
  const double m_light = 10.0 * 30 * 20 * 1e-6, m_gel = 30.0 * 30 * 20 * 1.1e-6;
  EXPECT_NEAR(out.mass_kg(), m_light + m_gel, 1e-12);
  EXPECT_NEAR(out.centre_mm()[0], (m_light * 5 + m_gel * 25) / (m_light + m_gel), 1e-9);
  EXPECT_NEAR(out.volume_mm3(0), 30.0 * 30 * 20, 1e-6) << "the void inside, which the gel fills";

  const auto tree_json = [](const std::string& depth) {
    return R"({"type": "stratum", "depth_mm": )" + depth + R"(, "shell": {"type": "layered", "material": "heavy"},
      "core": {"type": "voxel", "size_mm": [9.5, 28, 18], "origin": [2, 2, 2],
        "child": {"type": "layered", "material": {"value": "light", "choices": ["light", "heavy", "void"]}}}})";
  };
  const std::vector<double> ids = {0, 1, 2, 0};
  MassPropertiesObservation a, b;
  for (const std::string depth : {"2", R"({"value": 2, "choices": [2]})"}) {  // leaf sums, then every cell
    const Solid own(make_box(Vec3(0, 0, 0), Vec3(40, 30, 20), 2), UvSource::planar, 2);
    auto tree = bound(tree_json(depth), own);
    SearchSpace cells = tree->search_space("core");
    cells.set_values(ids);
    tree->evaluate();
    (depth == "2" ? a : b) = simulate(*tree, 0.7);
  }
  for (size_t k = 0; k < a.data.size(); ++k) EXPECT_NEAR(a.data[k], b.data[k], 1e-9 * (1 + std::abs(b.data[k]))) << k;
  EXPECT_GT(a.mass_kg(), 0.0) << "void cells weigh the gel";
}

TEST(MassMetrics, CentreOffsetIsAcrossGravityAndMassDifferenceInGrams) {
  MassPropertiesObservation simulated;
  simulated.data[MassPropertiesObservation::kMass] = 0.042;
  simulated.data[MassPropertiesObservation::kCentre] = 3;
  simulated.data[MassPropertiesObservation::kCentre + 1] = 4;
  simulated.data[MassPropertiesObservation::kCentre + 2] = 12;
  const auto goal = make_mass_properties_goal(0.040, std::array<double, 3>{0, 0, 0});
  EXPECT_DOUBLE_EQ(make_centre_offset_metric({})->error(simulated, goal->target()), 5);  // √(3² + 4²)
  EXPECT_DOUBLE_EQ(make_centre_offset_metric({{0, -2, 0}})->error(simulated, goal->target()), std::hypot(3, 12));
  EXPECT_NEAR(make_mass_difference_metric()->error(simulated, goal->target()), 2, 1e-12);
  const auto no_centre = make_mass_properties_goal(0.040, std::nullopt);
  EXPECT_THROW(make_centre_offset_metric({})->error(simulated, no_centre->target()), InputError);
  std::string why;
  EXPECT_FALSE((CentreOffsetOptions{{0, 0, 0}}.check(&why)));
  EXPECT_THAT(why, HasSubstr("gravity"));
}

// Make It Stand in one dimension: the interface between the light and the
// heavy part of the box is free (1 mm steps); the tuner moves it to put the
// centre of mass over x = 2 across gravity (−z). The interface it chooses is
// the one whose closed-form centre lies nearest x = 2.
TEST_F(MassProperties, ATunerMovesTheInterfaceToPutTheCentreOverATarget) {
  const Solid box(make_box(Vec3(-20, -15, -10), Vec3(20, 15, 10), 2), UvSource::planar, 2);
  auto tree = bound(R"({"type": "plane", "axis": "x", "offset_mm": {"value": 0, "min": -19, "max": 19, "step": 1},
      "below": {"type": "layered", "material": "light"}, "above": {"type": "layered", "material": "heavy"}})",
                    box);
  Tuner tuner("stand", make_mass_properties_simulator({1.0}, PartContext{palette_}), make_centre_offset_metric({}),
              make_mass_properties_goal(std::nullopt, std::array<double, 3>{2, 0, 0}),
              build_optimizer(Properties::parse(R"({"type": "exhaustive"})", "optimizer.json")));
  tuner.set_node(*tree, tree->root());
  const Summary summary = tuner.tune();
  ASSERT_TRUE(summary.usable()) << summary.full_report();
  // The closed form's centre for an interface at o: light block [−20, o], heavy [o, 20].
  const auto centre = [](double o) {
    const double ml = (o + 20) * 1e-6, mh = (20 - o) * 3e-6;
    return (ml * (o - 20) / 2 + mh * (o + 20) / 2) / (ml + mh);
  };
  double best = 1e9, best_o = 0;
  for (double o = -19; o <= 19; o += 1) {
    if (std::abs(centre(o) - 2) < best) best = std::abs(centre(o) - 2), best_o = o;
  }
  const double chosen = tuner.search_space().values()[0];
  EXPECT_EQ(chosen, best_o);
  EXPECT_NEAR(summary.final_error, best, 1e-9);
}

}  // namespace
}  // namespace spec2fab

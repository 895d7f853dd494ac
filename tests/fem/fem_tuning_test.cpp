// The FEM's goal and metric, and a tuner that drives the `fem` simulator
// through a reducer tree: the pieces the elastic experiments compose.

#include <gmock/gmock.h>

#include "fem_support.h"
#include "tuning/tuner.h"

namespace spec2fab::fem {
namespace {

std::unique_ptr<Observation> goal_target(const MaterialPalette& palette, const std::string& json) {
  auto goal = GoalRegistry::instance().create(Properties::parse(json, "goal.json"), "goal", PartContext{palette});
  return goal->target().clone();
}

TEST(ShapeMse, IsTheMeanSquaredDistanceAndHalfTheSquaredResiduals) {
  const MaterialPalette palette({testing::elastic_material("m", 1e9, 0.3)});
  const auto target = goal_target(palette, R"({"type": "deformed_shape", "points": [[0, 0, 0], [1, 0, 0]],
                                               "targets": [[0, 0, -1], [1, 0.5, 0]]})");
  DisplacementsObservation simulated;
  simulated.probe_count = 2;
  simulated.probe_rest_mm = {0, 0, 0, 1, 0, 0};
  simulated.xyz_mm = {0, 0, 0, 0, 0, 0, 9, 9, 9};  // two probes, then one node (ignored)
  auto metric = MetricRegistry::instance().create(Properties::parse(R"({"type": "shape_mse"})", "m.json"),
                                                  "metric", PartContext{palette});
  // Distances² 1 and 0.25: mean 0.625 mm².
  EXPECT_DOUBLE_EQ(metric->error(simulated, *target), 0.625);
  ASSERT_EQ(metric->residual_count(*target), 6);
  std::vector<double> r(6);
  metric->residuals(simulated, *target, r);
  double half = 0;
  for (double v : r) half += 0.5 * v * v;
  EXPECT_DOUBLE_EQ(half, 0.625);

  simulated.probe_rest_mm[3] = 2;  // another point than the goal's
  EXPECT_THROW(metric->error(simulated, *target), InputError);
  simulated.probe_count = 1;
  EXPECT_THROW(metric->error(simulated, *target), InputError);
}

// A bar of two halves along x (ν = 0); the far half's material is free among
// three moduli. The goal is the end displacement the middle modulus gives;
// exhaustive search through the tuner finds that material.
TEST(FemTuner, RecoversTheMaterialThatGivesTheGoalDeformation) {
  const MaterialPalette palette({testing::elastic_material("stiff", 1e9, 0.0),
                                 testing::elastic_material("medium", 3e8, 0.0),
                                 testing::elastic_material("soft", 1e8, 0.0)});
  auto tree = std::make_unique<ReducerTree>(
      Properties::parse(R"({"type": "plane", "axis": "x", "offset_mm": 10,
          "below": {"type": "layered", "material": "stiff"},
          "above": {"type": "layered", "material": {"value": "soft", "choices": ["stiff", "medium", "soft"]}}})",
                        "tree.json"),
      palette);
  Solid solid(make_box(Vec3(0, 0, 0), Vec3(20, 2, 2), 1), UvSource::planar);
  tree->bind(solid);
  // u(20) = F/A (10/E_stiff + 10/E_medium) with F = 4 N, A = 4 mm², E in MPa.
  const double goal_u = 1.0 * (10.0 / 1000.0 + 10.0 / 300.0);
  const std::string tuner_json = R"({
      "simulator": {"type": "fem", "max_tet_volume_mm3": 0.5, "nonlinear": false,
                    "fixed": [{"min": [0, 0, 0], "max": [0, 2, 2]}],
                    "loads": [{"min": [20, 0, 0], "max": [20, 2, 2], "force_n": [4, 0, 0]}],
                    "probes": [[20, 1, 1]]},
      "metric": {"type": "shape_mse"},
      "goal": {"type": "deformed_shape", "points": [[20, 1, 1]], "targets": [[)" +
                                 std::to_string(20 + goal_u) + R"(, 1, 1]]},
      "optimizer": {"type": "exhaustive"}})";
  auto tuner = build_tuner(Properties::parse(tuner_json, "tuner.json"), "bar", PartContext{palette});
  tuner->set_node(tree->root(), SimulationDomain(*tree, tree->root()));
  ASSERT_EQ(tuner->search_space().dimension(), 1u);
  const Summary summary = tuner->tune();
  EXPECT_TRUE(summary.usable()) << summary.full_report();
  EXPECT_EQ(palette.name(static_cast<MaterialId>(tuner->search_space().parameter(0).value())), "medium");
  EXPECT_LT(summary.final_error, 1e-12);
  EXPECT_GT(summary.initial_error, 1e-4);
}

TEST(FemSimulator, NeedsASolid) {
  const MaterialPalette palette({testing::elastic_material("m", 1e9, 0.3)});
  auto simulator = SimulatorRegistry::instance().create_named(
      "fem", Properties::parse(R"({"fixed": [{"min": [0, 0, 0], "max": [0, 1, 1]}]})", "s.json"), "simulator",
      PartContext{palette});
  const NodePtr node = build_node(Properties::parse(R"({"type": "layered", "material": "m"})", "n.json"),
                                  NodeContext{palette});
  try {
    simulator->setup(*node, SimulationDomain());
    FAIL() << "setup without a solid must fail";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("needs a solid"));
  }
}

}  // namespace
}  // namespace spec2fab::fem

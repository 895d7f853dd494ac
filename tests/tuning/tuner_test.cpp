// Tuners, tuner networks and schedules on real reducer trees, with the
// optimizers of optimizers/ built through the registry as users build them.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>

#include "build_gates.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"
#include "tuning/tuner.h"
#include "tuning_test_parts.h"

namespace spec2fab {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using testing::optimizer;

SPEC2FAB_REGISTER(SimulatorRegistry, testing::ZeroDisplacements, "test_displacements")
SPEC2FAB_REGISTER(MetricRegistry, testing::ImageMse, "test_image_mse")
SPEC2FAB_REGISTER(GoalRegistry, testing::BlackImageGoal, "test_black_image")

std::shared_ptr<MaterialPalette> palette() {
  std::vector<Material> m(2);
  m[0].name = "paper";
  m[1].name = "ink";
  return std::make_shared<MaterialPalette>(m);
}

// A grid of halftone cells: Column[w,h] -> Layered whose material is free.
std::unique_ptr<ReducerTree> halftone_tree(const MaterialPalette& p, int width, int height) {
  const std::string json = R"({"type": "column", "count": [)" + std::to_string(width) + ", " +
                           std::to_string(height) + R"(], "child": {"type": "layered",
      "material": {"value": "paper", "choices": ["paper", "ink"]}}})";
  return std::make_unique<ReducerTree>(Properties::parse(json, "tree.json"), p);
}

// Tuners that run in parallel must not share parameters: the same node, or
// one's node inside the other's subtree, is refused.
TEST(Schedule, ParallelTunersMustNotOverlap) {
  auto p = palette();
  auto tree = halftone_tree(*p, 2, 1);
  TunerNetwork network;
  auto add = [&](ReducerNode& node, const char* name) {
    auto tuner = std::make_unique<Tuner>(name, std::make_unique<testing::FirstLayerSimulator>(),
                                         std::make_unique<testing::SquaredError>(),
                                         std::make_unique<testing::ConstantGoal>(std::vector<double>{0}),
                                         optimizer(R"({"type": "exhaustive"})"));
    tuner->set_node(node);
    return network.add(std::move(tuner));
  };
  const size_t left = add(tree->root().child(0), "left");
  const size_t right = add(tree->root().child(1), "right");
  const size_t whole = add(tree->root(), "whole");
  const size_t left_again = add(tree->root().child(0), "left_again");
  EXPECT_EQ(overlapping_tuners(network, {left, right}), std::nullopt);
  EXPECT_EQ(overlapping_tuners(network, {left, whole}), (std::pair<size_t, size_t>{whole, left}));
  EXPECT_EQ(overlapping_tuners(network, {right, whole}), (std::pair<size_t, size_t>{whole, right}));
  EXPECT_EQ(overlapping_tuners(network, {left, left_again}), (std::pair<size_t, size_t>{left, left_again}));
  Schedule schedule;
  Phase phase;
  phase.name = "both";
  phase.tuners = {left, whole};
  phase.mode = Phase::Mode::parallel;
  schedule.add(phase);
  EXPECT_THAT([&] { schedule.run(network, 1, Limits()); },
              ThrowsMessage<std::invalid_argument>(HasSubstr("runs tuners 'whole' and 'left' in parallel, but their "
                                                             "subtrees overlap")));
}

TEST(Tuner, IncompatiblePartsFailAtRunTimeNamingBoth) {
  try {
    Tuner tuner("t", std::make_unique<testing::ZeroDisplacements>(Properties::parse("{}", "")),
                std::make_unique<testing::ImageMse>(Properties::parse("{}", "")),
                std::make_unique<testing::BlackImageGoal>(Properties::parse("{}", "")),
                optimizer(R"({"type": "exhaustive"})"));
    FAIL() << "accepted a displacement simulator with an image metric";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "tuner 't': metric 'test_image_mse' compares image observations, but simulator "
              "'test_displacements' produces displacements");
  }
}

TEST(Tuner, IncompatiblePartsFailAtLoadTimeFromJson) {
  const Properties p = Properties::parse(R"({"tuners": [{
      "simulator": {"type": "test_displacements"}, "metric": {"type": "test_image_mse"},
      "goal": {"type": "test_black_image"}, "optimizer": {"type": "exhaustive"}}]})", "exp.json");
  try {
    const MaterialPalette no_materials{std::vector<Material>{}};
    build_tuner(p.objects("tuners")[0], "t", PartContext{no_materials});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("exp.json: /tuners/0: metric 'test_image_mse' compares image "
                                    "observations, but simulator 'test_displacements' produces "
                                    "displacements"));
  }
}

TEST(Tuner, RegisteredAlbedoSimulatorRefusesAnImageMetricFromJson) {
  const Properties p = Properties::parse(R"({"tuners": [{
      "simulator": {"type": "albedo"}, "metric": {"type": "test_image_mse"},
      "goal": {"type": "albedo", "srgb": [1, 1, 1]}, "optimizer": {"type": "exhaustive"}}]})",
                                         "exp.json");
  const MaterialPalette no_materials{std::vector<Material>{}};
  EXPECT_THAT([&] { build_tuner(p.objects("tuners")[0], "t", PartContext{no_materials}); },
              ThrowsMessage<InputError>(HasSubstr(
                  "exp.json: /tuners/0: metric 'test_image_mse' compares image observations, but "
                  "simulator 'albedo' produces albedo")));
}

TEST(Tuner, TunesItsSubtreeToTheGoal) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  const auto p = palette();
  auto tree = std::make_unique<ReducerTree>(
      Properties::parse(R"({"type": "layered", "layers": [
          {"material": "ink", "thickness_mm": {"value": 0.1, "min": 0, "max": 2}},
          {"material": "paper"}]})", "tree.json"), *p);
  Tuner tuner("t", std::make_unique<testing::FirstLayerSimulator>(),
              std::make_unique<testing::SquaredError>(),
              std::make_unique<testing::ConstantGoal>(std::vector<double>{0.73}),
              optimizer(R"({"type": "nlopt", "algorithm": "LN_BOBYQA", "xtol_rel": 1e-6})"));
  tuner.set_node(tree->root());
  ASSERT_EQ(tuner.search_space().dimension(), 1u);
  EXPECT_EQ(tuner.search_space().entries()[0].name, "layers/0/thickness_mm");
  const Summary summary = tuner.tune();
  EXPECT_TRUE(summary.usable()) << summary.full_report();
  EXPECT_LT(summary.final_error, summary.initial_error);
  EXPECT_NEAR(tuner.search_space().parameter(0).value(), 0.73, 2e-3);
}

// Error diffusion: 1-bit cells whose targets are grey levels. Alone, each cell
// rounds to the nearer of 0 and 1 and the mean is badly off; with the
// neighbours' residuals diffused, the mean coverage matches the mean target.
double mean_coverage_error(bool diffuse, int neighbourhood) {
  const auto p = palette();
  const int w = 32, h = 32;
  auto tree = halftone_tree(*p, w, h);
  TunerNetwork network;
  double target_sum = 0;
  for (int i = 0; i < w * h; ++i) {
    const double grey = 0.1 + 0.3 * (i % w) / (w - 1.0);  // 0.1 .. 0.4, all round to 0
    target_sum += grey;
    auto tuner = make_tuner("cell" + std::to_string(i), std::make_unique<testing::CoverageSimulator>(1),
                            std::make_unique<testing::SquaredError>(),
                            std::make_unique<testing::ConstantGoal>(std::vector<double>{grey}),
                            optimizer(R"({"type": "exhaustive"})"));
    tuner->set_node(tree->node(std::to_string(i)));
    network.add(std::move(tuner));
  }
  network.connect_grid(w, h, neighbourhood);
  Phase phase;
  phase.name = "halftone";
  if (diffuse) phase.coupling = std::make_shared<ErrorDiffusion>(w);
  Schedule schedule;
  schedule.add(phase);
  schedule.run(network, 1, Limits());
  double coverage_sum = 0;
  for (size_t i = 0; i < network.size(); ++i) coverage_sum += network.tuner(i).simulated().values()[0];
  return (coverage_sum - target_sum) / (w * h);
}

TEST(TunerNetwork, ErrorDiffusionDrivesMeanErrorToZero) {
  EXPECT_NEAR(mean_coverage_error(false, 4), -0.25, 1e-9);
  EXPECT_NEAR(mean_coverage_error(true, 4), 0.0, 2e-3);
  EXPECT_NEAR(mean_coverage_error(true, 8), 0.0, 2e-3);
}

TEST(TunerNetwork, GridBuildersAndColouring) {
  TunerNetwork network;
  for (int i = 0; i < 12; ++i) {
    network.add(std::make_unique<Tuner>("t", std::make_unique<testing::FirstLayerSimulator>(),
                                        std::make_unique<testing::SquaredError>(),
                                        std::make_unique<testing::ConstantGoal>(std::vector<double>{0}),
                                        optimizer(R"({"type": "exhaustive"})")));
  }
  network.connect_grid(4, 3, 4);
  EXPECT_EQ(network.neighbours(5), (std::vector<size_t>{1, 4, 6, 9}));
  EXPECT_EQ(network.neighbours(0), (std::vector<size_t>{1, 4}));
  std::vector<size_t> all(12);
  std::iota(all.begin(), all.end(), 0);
  auto classes = network.colour_classes(all);
  EXPECT_EQ(classes.size(), 2u);  // a 4-neighbour grid is bipartite
  for (const auto& c : classes) {
    for (size_t a : c) {
      for (size_t b : c) EXPECT_FALSE(network.connected(a, b));
    }
  }
  network.connect_grid(4, 3, 8);
  EXPECT_EQ(network.colour_classes(all).size(), 4u);
  TunerNetwork groups;
  for (int i = 0; i < 4; ++i) groups.add(std::make_unique<Tuner>("g", std::make_unique<testing::FirstLayerSimulator>(),
                                                                 std::make_unique<testing::SquaredError>(),
                                                                 std::make_unique<testing::ConstantGoal>(std::vector<double>{0}),
                                                                 optimizer(R"({"type": "exhaustive"})")));
  groups.connect_groups({{0, 1}, {2, 3}});
  EXPECT_TRUE(groups.connected(0, 1));
  EXPECT_FALSE(groups.connected(1, 2));
}

// 8×8 tuners with stochastic optimizers in a parallel phase: the same result
// on 1 and 2 threads, and the same as running the phase serially.
std::vector<double> tuned_thicknesses(int threads, Phase::Mode mode) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
  const auto p = palette();
  const int w = 8, h = 8;
  auto tree = std::make_unique<ReducerTree>(
      Properties::parse(R"({"type": "column", "count": [8, 8], "child": {"type": "layered", "layers": [
          {"material": "ink", "thickness_mm": {"value": 0.5, "min": 0, "max": 2}}, {"material": "paper"}]}})",
                        "tree.json"), *p);
  TunerNetwork network;
  for (int i = 0; i < w * h; ++i) {
    auto tuner = make_tuner("cell" + std::to_string(i), std::make_unique<testing::FirstLayerSimulator>(),
                            std::make_unique<testing::SquaredError>(),
                            std::make_unique<testing::ConstantGoal>(std::vector<double>{0.02 * i}),
                            optimizer(R"({"type": "annealing", "iterations": 200})"));
    tuner->set_node(tree->node(std::to_string(i)));
    network.add(std::move(tuner));
  }
  network.connect_grid(w, h, 4);
  Phase phase;
  phase.mode = mode;
  phase.sweeps = 2;
  Schedule schedule;
  schedule.add(phase);
  const RunRecord record = schedule.run(network, 42, Limits());
  EXPECT_EQ(record.runs.size(), 128u);
  std::vector<double> values;
  for (size_t i = 0; i < network.size(); ++i) values.push_back(network.tuner(i).search_space().parameter(0).value());
  return values;
}

TEST(Schedule, ParallelPhaseIsIdenticalForAnyThreadCount) {
  const auto one = tuned_thicknesses(1, Phase::Mode::parallel);
  const auto two = tuned_thicknesses(2, Phase::Mode::parallel);
  const auto serial = tuned_thicknesses(2, Phase::Mode::serial);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, serial);
  EXPECT_NEAR(one[10], 0.2, 0.05);  // annealing got close to its goal
}

TEST(Schedule, LaterPhaseSeesWhatAnEarlierPhaseFixed) {
  const auto p = palette();
  auto tree = halftone_tree(*p, 2, 1);
  TunerNetwork network;
  for (int i = 0; i < 2; ++i) {
    auto tuner = make_tuner("cell" + std::to_string(i), std::make_unique<testing::CoverageSimulator>(1),
                            std::make_unique<testing::SquaredError>(),
                            std::make_unique<testing::ConstantGoal>(std::vector<double>{1.0}),
                            optimizer(R"({"type": "exhaustive"})"));
    tuner->set_node(tree->node(std::to_string(i)));
    network.add(std::move(tuner));
  }
  Schedule schedule;
  Phase first;
  first.name = "first";
  first.tuners = {0};
  first.fix_after = true;
  Phase second;
  second.name = "second";
  schedule.add(first).add(second);
  const RunRecord record = schedule.run(network, 1, Limits());
  ASSERT_EQ(record.runs.size(), 3u);
  EXPECT_EQ(record.runs[1].summary.message, "no free parameters");  // tuner 0, fixed by phase 1
  EXPECT_EQ(record.runs[2].summary.final_error, 0.0);
  EXPECT_THAT(record.convergence_csv(network), HasSubstr("phase,sweep,tuner,iteration,evaluations,error,best_error\n"));
  const nlohmann::json json = write_section(record.report(network));
  EXPECT_EQ(json["phases"].size(), 2u);
  Phase parallel_diffusion;
  parallel_diffusion.mode = Phase::Mode::parallel;
  parallel_diffusion.coupling = std::make_shared<ErrorDiffusion>(2);
  Schedule bad;
  bad.add(parallel_diffusion);
  EXPECT_THROW(bad.run(network, 1, Limits()), std::invalid_argument);
}

// Neighbour swaps: six cells on a chain hold targets 5..0 in reverse; an
// energy Σ (target − position)² rewards each target reaching its own
// position. Annealing (a phase optimizer in place of the tuners' own) swaps
// neighbours' states until every target is home; states travel with their
// parameter values.
TEST(Schedule, NeighbourSwapsExchangeTargetsAndValuesUntilTheEnergyIsLowest) {
  const auto p = palette();
  const int n = 6;
  auto tree = halftone_tree(*p, n, 1);
  TunerNetwork network;
  for (int i = 0; i < n; ++i) {
    auto tuner = make_tuner("cell" + std::to_string(i), std::make_unique<testing::CoverageSimulator>(1),
                            std::make_unique<testing::SquaredError>(),
                            std::make_unique<testing::ConstantGoal>(std::vector<double>{double(n - 1 - i)}),
                            optimizer(R"({"type": "exhaustive"})"));
    tuner->set_node(tree->node(std::to_string(i)));
    network.add(std::move(tuner));
  }
  network.connect_grid(n, 1, 4);
  const double paper = network.tuner(0).problem().domain(0).smallest(), ink = network.tuner(0).problem().domain(0).largest();
  network.tuner(0).error_at(std::vector<double>{ink});  // cell 0 (target 5) is ink, the others paper
  const auto target = [&](size_t t) { return network.tuner(t).effective_target().values()[0]; };
  const auto energy = [&](TunerNetwork&) {
    double e = 0;
    for (size_t t = 0; t < network.size(); ++t) e += (target(t) - double(t)) * (target(t) - double(t));
    return e;
  };
  auto swaps = std::make_shared<NeighbourSwaps>(
      [&](TunerNetwork&, size_t a, size_t b) {
        const auto cost = [](double value, size_t at) { return (value - double(at)) * (value - double(at)); };
        return cost(target(a), b) + cost(target(b), a) - cost(target(a), a) - cost(target(b), b);
      },
      energy);
  Phase phase;
  phase.name = "swap";
  phase.sweeps = 30;
  phase.coupling = swaps;
  phase.record_every_sweep = false;
  phase.optimizer = nlohmann::json::parse(R"({"type": "annealing", "iterations": 3, "schedule_iterations": 90,
      "swap_probability": 1, "initial_temperature": 0.5, "cooling": 0.9})");
  Schedule schedule;
  schedule.add(phase);
  const RunRecord record = schedule.run(network, 7, Limits());
  for (size_t t = 0; t < network.size(); ++t) EXPECT_EQ(target(t), double(t)) << t;
  EXPECT_EQ(swaps->energies().front(), 70.0);
  EXPECT_EQ(swaps->energies().back(), 0.0);
  EXPECT_EQ(swaps->energies().size(), 31u);
  // The ink went with target 5 to the far end.
  EXPECT_EQ(network.tuner(n - 1).search_space().values(), std::vector<double>{ink});
  EXPECT_EQ(network.tuner(0).search_space().values(), std::vector<double>{paper});
  // Only the last sweep's runs are kept, every run is counted; the tuners have
  // their own optimizers back and no neighbour moves outside the phase.
  EXPECT_EQ(record.runs.size(), size_t(n));
  EXPECT_EQ(record.phase_tuner_runs, std::vector<long long>{30 * n});
  EXPECT_EQ(record.report(network).phases[0].tuner_runs, 30 * n);
  EXPECT_EQ(network.tuner(0).optimizer().name(), "exhaustive");
  EXPECT_FALSE(network.tuner(0).problem().has(Capability::neighbour_moves));
}

}  // namespace
}  // namespace spec2fab

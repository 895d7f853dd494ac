// BM_IndependentGrid and BM_IndependentGridPaired (see bench_tuning.cpp for
// how to run them and what they measure).
#include "tuning_bench_parts.h"

namespace spec2fab::bench_tuning {
namespace {

// 64×64 independent cells, each tuned by annealing (~100 evaluations).
constexpr int kGrid = 64;
const std::string kGridAnnealing = R"({"type": "annealing", "iterations": 100})";

struct Grid {
  Grid() : palette(materials()) {
    const std::string json = R"({"type": "column", "count": [)" + std::to_string(kGrid) + ", " +
                             std::to_string(kGrid) + R"(], "child": )" + cell_json() + "}";
    tree = std::make_unique<ReducerTree>(Properties::parse(json, "bench"), palette);
    for (int i = 0; i < kGrid * kGrid; ++i) {
      // Targets that vary over the grid, each reachable at some admissible point.
      const double target = response(i % 2 == 0 ? 1.0 : 2.0, kThickness.admissible(i % 40));
      auto tuner = make_tuner("cell" + std::to_string(i), std::make_unique<CellSimulator>(),
                              std::make_unique<SquaredError>(),
                              std::make_unique<ConstantGoal>(target), optimizer(kGridAnnealing));
      tuner->set_node(tree->node(std::to_string(i)));
      network.add(std::move(tuner));
    }
    for (size_t t = 0; t < network.size(); ++t) {
      start.push_back(network.tuner(t).search_space().values());
    }
    Phase phase;
    phase.name = "cells";
    phase.mode = Phase::Mode::parallel;
    schedule.add(phase);
  }

  // Tunes every cell from the same start; returns the records' evaluations.
  long long tune() {
    for (size_t t = 0; t < network.size(); ++t) {
      network.tuner(t).search_space().set_values(start[t]);
    }
    const RunRecord record = schedule.run(network, 7, Limits());
    long long evaluations = 0;
    for (const TunerRun& run : record.runs) evaluations += run.summary.evaluations;
    return evaluations;
  }

  // Every tuned parameter and final error, for comparing runs.
  std::vector<double> result() {
    std::vector<double> out;
    for (size_t t = 0; t < network.size(); ++t) {
      for (double v : network.tuner(t).search_space().values()) out.push_back(v);
      out.push_back(network.tuner(t).error());
    }
    return out;
  }

  MaterialPalette palette;
  std::unique_ptr<ReducerTree> tree;
  TunerNetwork network;
  Schedule schedule;
  std::vector<std::vector<double>> start;
};

std::vector<double> tuned_once(size_t threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  Grid grid;
  grid.tune();
  return grid.result();
}

void BM_IndependentGrid(benchmark::State& state) {
  const auto threads = static_cast<size_t>(state.range(0));
  std::vector<double> timed;
  long long evaluations = 0;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Grid grid;
    for (auto _ : state) evaluations += grid.tune();
    timed = grid.result();
  }
  // Outside the timed run's global_control: nested controls take the minimum.
  if (tuned_once(threads == 1 ? 2 : 1) != timed) {
    state.SkipWithError("1 and 2 threads gave different results");
    return;
  }
  state.SetItemsProcessed(state.iterations() * kGrid * kGrid);
  state.counters["evaluations_per_tuner"] =
      static_cast<double>(evaluations) / static_cast<double>(state.iterations() * kGrid * kGrid);
}

// 1 and 2 threads alternating in one process (see run_paired): each speedup
// compares runs made a second apart, immune to the machine's drift.
void BM_IndependentGridPaired(benchmark::State& state) {
  Grid grid;
  const auto on = [&grid](size_t threads) {
    return [&grid, threads] {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      grid.tune();
    };
  };
  const std::vector<double> ratios =
      run_paired(state, {{"threads_1", on(1)}, {"threads_2", on(2)}}, 1, false);
  state.counters["speedup"] = 1 / ratios[1];
  on(1)();
  const std::vector<double> one = grid.result();
  on(2)();
  if (grid.result() != one) state.SkipWithError("1 and 2 threads gave different results");
}

BENCHMARK(BM_IndependentGridPaired)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IndependentGrid)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace spec2fab::bench_tuning

// Tuning overhead and parallel tuner networks (issue 3). Each line in its own
// process (see BM_IndependentGrid); RESULTS.md reports the medians:
//
//   R="--benchmark_min_time=2 --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//      --benchmark_enable_random_interleaving=true"
//   build/benchmarks/bench_tuning --benchmark_filter=BM_Error $R
//   build/benchmarks/bench_tuning --benchmark_filter=BM_Annealing $R
//   build/benchmarks/bench_tuning --benchmark_filter=BM_IndependentGrid/threads:1 $R
//   build/benchmarks/bench_tuning --benchmark_filter=BM_IndependentGrid/threads:2 $R
//   build/benchmarks/bench_tuning --benchmark_filter=BM_IndependentGridPaired $R
//
// Every evaluation is one call of response(): ~1 µs of dependent
// transcendental math seeded by a cell's (surface material, first-layer
// thickness), a stand-in for a small simulation.
//
// BM_ErrorDirect / BM_ErrorProblem / BM_ErrorTuner: one error evaluation
//   called directly, through a Problem (virtual call + span), and through
//   Tuner::error_at (set parameters, evaluate_subtree, simulate, metric),
//   whose simulator reads material and thickness back from the Layered node
//   (6-7 queries). BM_ErrorTunerNoReadBack: the same tuner with a simulator
//   that reads the parameters instead: the Tuner's own cost alone.
// BM_AnnealingDirect / BM_AnnealingProblem / BM_AnnealingTuner: the same
//   number of evaluations as a plain loop, as annealing on a Problem, and as
//   annealing through Tuner::tune.
// BM_ErrorPaired / BM_AnnealingPaired: the same, alternating batches in one
//   benchmark; their counters give the overheads (see run_paired for why).
// BM_IndependentGrid: 64×64 tuners without edges, one parallel schedule
//   phase; /threads:N caps oneTBB at N threads. Run each thread count in its
//   own process: bench_fabrication saw oneTBB's second worker stay idle after
//   a 1-thread benchmark in the same process. After timing, the grid is tuned
//   again with the other thread count and must give identical parameters and
//   errors.
// BM_IndependentGridPaired: 1 and 2 threads alternating in one process; its
//   counter `speedup` is the median ratio.

#include <benchmark/benchmark.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/properties.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"
#include "tuning/tuner.h"

namespace spec2fab {
namespace {

// ~1 µs on the project machine. Each step depends on the previous one, so
// the compiler can neither vectorise nor drop any of it. Not inlined: every
// path runs the same machine code, so differences between paths are overhead.
constexpr int kResponseSteps = 20;

[[gnu::noinline]] double response(double material, double thickness) {
  double a = 0.37 * material + thickness, b = 1.0 + thickness;
  for (int i = 0; i < kResponseSteps; ++i) {
    a = std::sin(1.3 * a + b);
    b = std::exp(-0.5 * a * a) + std::log1p(b);
  }
  return a * b;
}

// The free parameters of a cell: layer 0's material (paper or ink, over a
// base the choices never take) and its thickness on a grid the simulator
// can read back exactly.
const VariableDomain kThickness = VariableDomain::discrete(0.05, 2.0, 0.05);
const long long kThicknessCount = kThickness.cardinality();  // 40

// Grid depth k, computed as VariableDomain::admissible and Parameter::set do,
// so that read-back values are bit-identical to the tuner's.
double thickness_at(long long k) {
  return kThickness.lower + static_cast<double>(k) * kThickness.step;
}

std::vector<Material> materials() {
  std::vector<Material> m(3);
  m[0].name = "paper";
  m[1].name = "ink";
  m[2].name = "base";
  return m;
}

std::string cell_json() {
  return R"({"type": "layered", "layers": [
      {"material": {"value": "paper", "choices": ["paper", "ink"]},
       "thickness_mm": {"value": 0.5, "min": )" +
         std::to_string(kThickness.lower) + R"(, "max": )" + std::to_string(kThickness.upper) +
         R"(, "step": )" + std::to_string(kThickness.step) + R"(}},
      {"material": "base"}]})";
}

// Reads back what a Layered cell assigns — its surface material and where
// that material ends — and runs response() on it.
class CellSimulator final : public SimulatorFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_cell"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode& subtree, VectorObservation& out) override {
    const auto& node = static_cast<const MaterialNode&>(subtree);
    const MaterialId top = node.material(QueryPoint{}, LocalFrame{0, 0, 0});
    // Bisection over the thickness grid (5-6 queries for 40 values): the
    // largest k whose mid-step below grid depth k still shows the top material.
    const double half = 0.5 * kThickness.step;
    long long lo = 0, hi = kThicknessCount;
    while (hi - lo > 1) {
      const long long mid = (lo + hi) / 2;
      const LocalFrame probe{0, 0, thickness_at(mid) - half};
      const bool inside = node.material(QueryPoint{}, probe) == top;
      lo = inside ? mid : lo;
      hi = inside ? hi : mid;
    }
    out.data[0] = response(static_cast<double>(top), thickness_at(lo));
    ++calls;
  }

  long long calls = 0;
};

// Reads the tuner's parameters directly instead of querying the node: takes
// the read-back out of BM_ErrorTuner, leaving the Tuner's own cost.
class ParameterSimulator final : public SimulatorFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_parameters"; }
  std::unique_ptr<Observation> make_observation() const override {
    auto o = std::make_unique<VectorObservation>();
    o->data.assign(1, 0.0);
    return o;
  }
  void read_from(const SearchSpace& space) {
    material_ = &space.parameter(0);
    thickness_ = &space.parameter(1);
  }
  using SimulatorFor::simulate;
  void simulate(const ReducerNode&, VectorObservation& out) override {
    out.data[0] = response(material_->value(), thickness_->value());
    ++calls;
  }

  long long calls = 0;

 private:
  const Parameter* material_ = nullptr;
  const Parameter* thickness_ = nullptr;
};

class SquaredError final : public MetricFor<VectorObservation> {
 public:
  std::string name() const override { return "bench_squared_error"; }
  using MetricFor::error;
  double error(const VectorObservation& a, const VectorObservation& b) const override {
    const double d = a.data[0] - b.data[0];
    return d * d;
  }
};

class ConstantGoal final : public GoalFor<VectorObservation> {
 public:
  explicit ConstantGoal(double value) { target_.data.assign(1, value); }
  std::string name() const override { return "bench_constant"; }
  const VectorObservation& typed_target() const override { return target_; }

 private:
  VectorObservation target_;
};

double direct_error(std::span<const double> x, double target) {
  const double d = response(x[0], x[1]) - target;
  return d * d;
}

// The same error as a Problem, for an optimizer or a virtual call.
class DirectProblem final : public Problem {
 public:
  DirectProblem(std::vector<VariableDomain> domains, double target)
      : domains_(std::move(domains)), target_(target) {}
  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  double error(std::span<const double> x) override {
    ++calls;
    return direct_error(x, target_);
  }
  bool has(Capability c) const override { return c == Capability::discrete_only; }

  long long calls = 0;

 private:
  std::vector<VariableDomain> domains_;
  double target_;
};

std::unique_ptr<Optimizer> optimizer(const std::string& json) {
  return build_optimizer(Properties::parse(json, "bench"));
}

// One cell tree and one tuner bound to it; also the points at which every
// way of evaluating is called, in the same order.
template <class S = CellSimulator>
struct SingleCell {
  SingleCell(const std::string& optimizer_json, double target)
      : palette(materials()), tree(Properties::parse(cell_json(), "bench"), palette) {
    auto owned = std::make_unique<S>();
    simulator = owned.get();
    tuner = make_tuner("cell", std::move(owned), std::make_unique<SquaredError>(),
                       std::make_unique<ConstantGoal>(target), optimizer(optimizer_json));
    tuner->set_node(tree.root());
    if constexpr (std::is_same_v<S, ParameterSimulator>) {
      simulator->read_from(tuner->search_space());
    }
    const Problem& p = tuner->problem();
    for (int i = 0; i < p.dimension(); ++i) domains.push_back(p.domain(i));
    // Admissible points in a fixed random order, so that branch prediction
    // cannot learn the simulator's bisection (an optimizer's moves are random too).
    std::uint64_t r = 88172645463325252ull;
    auto next = [&](long long n) {  // xorshift64
      r ^= r << 13;
      r ^= r >> 7;
      r ^= r << 17;
      return static_cast<long long>(r % static_cast<std::uint64_t>(n));
    };
    for (int i = 0; i < 4096; ++i) {
      points.push_back({domains[0].admissible(next(domains[0].cardinality())),
                        domains[1].admissible(next(domains[1].cardinality()))});
    }
  }
  MaterialPalette palette;
  ReducerTree tree;
  S* simulator;  // owned by the tuner
  std::unique_ptr<Tuner> tuner;
  std::vector<VariableDomain> domains;
  std::vector<std::vector<double>> points;
};

constexpr double kTarget = 0.5;

void BM_ErrorDirect(benchmark::State& state) {
  SingleCell cell(R"({"type": "exhaustive"})", kTarget);
  size_t i = 0;
  for (auto _ : state) {
    double e = direct_error(cell.points[i], kTarget);
    benchmark::DoNotOptimize(e);
    if (++i == cell.points.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ErrorProblem(benchmark::State& state) {
  SingleCell cell(R"({"type": "exhaustive"})", kTarget);
  DirectProblem direct(cell.domains, kTarget);
  // Hide the dynamic type so that the call stays virtual.
  Problem* problem = &direct;
  benchmark::DoNotOptimize(problem);
  size_t i = 0;
  for (auto _ : state) {
    double e = problem->error(cell.points[i]);
    benchmark::DoNotOptimize(e);
    if (++i == cell.points.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}

template <class S>
void tuner_error(benchmark::State& state) {
  SingleCell<S> cell(R"({"type": "exhaustive"})", kTarget);
  // The tuner must see the same numbers as the direct call.
  for (const auto& x : cell.points) {
    if (cell.tuner->error_at(x) != direct_error(x, kTarget)) {
      state.SkipWithError("tuner and direct call disagree");
      return;
    }
  }
  size_t i = 0;
  for (auto _ : state) {
    double e = cell.tuner->error_at(cell.points[i]);
    benchmark::DoNotOptimize(e);
    if (++i == cell.points.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ErrorTuner(benchmark::State& state) { tuner_error<CellSimulator>(state); }
void BM_ErrorTunerNoReadBack(benchmark::State& state) { tuner_error<ParameterSimulator>(state); }

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Way {
  std::string name;
  std::function<void()> batch;
};

// The machine's speed drifts by 10-25 % between runs (a shared VM): more than
// the overheads sought. A paired benchmark therefore times one batch of every
// way per iteration, in alternating order, and reports for each way the
// median time per evaluation and, against the first way's batch of the same
// iteration, the median excess in ns and in percent; returns the median ratios.
std::vector<double> run_paired(benchmark::State& state, const std::vector<Way>& ways,
                               double evaluations_per_batch, bool overhead_counters = true) {
  const size_t n = ways.size();
  std::vector<double> t(n);
  std::vector<std::vector<double>> ns(n), excess_ns(n), ratio(n);
  bool forward = true;
  for (auto _ : state) {
    for (size_t j = 0; j < n; ++j) {
      const size_t w = forward ? j : n - 1 - j;
      const auto start = std::chrono::steady_clock::now();
      ways[w].batch();
      const std::chrono::duration<double, std::nano> elapsed =
          std::chrono::steady_clock::now() - start;
      t[w] = elapsed.count() / evaluations_per_batch;
    }
    forward = !forward;
    for (size_t w = 0; w < n; ++w) {
      ns[w].push_back(t[w]);
      excess_ns[w].push_back(t[w] - t[0]);
      ratio[w].push_back(t[w] / t[0]);
    }
  }
  std::vector<double> ratios(n);
  for (size_t w = 0; w < n; ++w) {
    state.counters[ways[w].name + "_ns"] = median(ns[w]);
    ratios[w] = median(ratio[w]);
    if (w == 0 || !overhead_counters) continue;
    state.counters[ways[w].name + "_overhead_ns"] = median(excess_ns[w]);
    state.counters[ways[w].name + "_overhead_pct"] = 100 * (ratios[w] - 1);
  }
  return ratios;
}

// Batches of 200 single evaluations at the same points for every way.
void BM_ErrorPaired(benchmark::State& state) {
  SingleCell<CellSimulator> cell(R"({"type": "exhaustive"})", kTarget);
  SingleCell<ParameterSimulator> bare(R"({"type": "exhaustive"})", kTarget);
  DirectProblem direct(cell.domains, kTarget);
  Problem* problem = &direct;
  benchmark::DoNotOptimize(problem);
  constexpr size_t kBatch = 200;
  const auto cycling = [&cell](auto call) {
    return [&cell, call, i = size_t{0}]() mutable {
      for (size_t k = 0; k < kBatch; ++k) {
        double e = call(cell.points[i]);
        benchmark::DoNotOptimize(e);
        if (++i == cell.points.size()) i = 0;
      }
    };
  };
  using X = const std::vector<double>&;
  run_paired(state,
             {{"direct", cycling([](X x) { return direct_error(x, kTarget); })},
              {"problem", cycling([problem](X x) { return problem->error(x); })},
              {"tuner", cycling([&cell](X x) { return cell.tuner->error_at(x); })},
              {"tuner_no_read_back", cycling([&bare](X x) { return bare.tuner->error_at(x); })}},
             kBatch);
}

// A full optimizer run: annealing with a fixed number of moves. minimize()
// adds the initial and the final error: kAnnealingMoves + 2 evaluations,
// counted where they happen; the direct loop makes as many calls.
constexpr int kAnnealingMoves = 1000;
constexpr long long kAnnealingCalls = kAnnealingMoves + 2;
const std::string kAnnealing =
    R"({"type": "annealing", "iterations": )" + std::to_string(kAnnealingMoves) + "}";

void BM_AnnealingDirect(benchmark::State& state) {
  SingleCell cell(kAnnealing, kTarget);
  size_t i = 0;
  for (auto _ : state) {
    for (long long k = 0; k < kAnnealingCalls; ++k) {
      double e = direct_error(cell.points[i], kTarget);
      benchmark::DoNotOptimize(e);
      if (++i == cell.points.size()) i = 0;
    }
  }
  state.SetItemsProcessed(state.iterations() * kAnnealingCalls);
}

void BM_AnnealingProblem(benchmark::State& state) {
  SingleCell cell(kAnnealing, kTarget);
  DirectProblem problem(cell.domains, kTarget);
  auto annealing = optimizer(kAnnealing);
  for (auto _ : state) {
    std::vector<double> x = cell.points.front();
    const Summary summary = annealing->minimize(problem, x);
    benchmark::DoNotOptimize(summary.final_error);
  }
  if (problem.calls != state.iterations() * kAnnealingCalls) {
    state.SkipWithError("unexpected number of evaluations");
  }
  state.SetItemsProcessed(problem.calls);
}

void BM_AnnealingTuner(benchmark::State& state) {
  SingleCell cell(kAnnealing, kTarget);
  Tuner& tuner = *cell.tuner;
  const long long before = cell.simulator->calls;
  for (auto _ : state) {
    tuner.search_space().set_values(cell.points.front());
    const Summary summary = tuner.tune();
    benchmark::DoNotOptimize(summary.final_error);
  }
  // tune() simulates once more to leave the best point set: overhead, not an
  // evaluation of the search.
  const long long calls = cell.simulator->calls - before;
  if (calls != state.iterations() * (kAnnealingCalls + 1)) {
    state.SkipWithError("unexpected number of simulations");
  }
  state.SetItemsProcessed(state.iterations() * kAnnealingCalls);
}

// One annealing run, as a plain loop, on a Problem and through a tuner,
// alternating (see run_paired).
void BM_AnnealingPaired(benchmark::State& state) {
  SingleCell cell(kAnnealing, kTarget);
  DirectProblem problem(cell.domains, kTarget);
  auto annealing = optimizer(kAnnealing);
  size_t i = 0;
  run_paired(state,
             {{"direct",
               [&] {
                 for (long long k = 0; k < kAnnealingCalls; ++k) {
                   double e = direct_error(cell.points[i], kTarget);
                   benchmark::DoNotOptimize(e);
                   if (++i == cell.points.size()) i = 0;
                 }
               }},
              {"problem",
               [&] {
                 std::vector<double> x = cell.points.front();
                 benchmark::DoNotOptimize(annealing->minimize(problem, x).final_error);
               }},
              {"tuner",
               [&] {
                 cell.tuner->search_space().set_values(cell.points.front());
                 benchmark::DoNotOptimize(cell.tuner->tune().final_error);
               }}},
             kAnnealingCalls);
}

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

BENCHMARK(BM_ErrorDirect);
BENCHMARK(BM_ErrorProblem);
BENCHMARK(BM_ErrorTuner);
BENCHMARK(BM_ErrorTunerNoReadBack);
BENCHMARK(BM_ErrorPaired)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingDirect)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingProblem)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingTuner)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingPaired)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IndependentGridPaired)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IndependentGrid)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace spec2fab

BENCHMARK_MAIN();

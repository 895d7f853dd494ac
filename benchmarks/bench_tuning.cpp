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

#include "tuning_bench_parts.h"

namespace spec2fab::bench_tuning {
namespace {

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

BENCHMARK(BM_ErrorDirect);
BENCHMARK(BM_ErrorProblem);
BENCHMARK(BM_ErrorTuner);
BENCHMARK(BM_ErrorTunerNoReadBack);
BENCHMARK(BM_ErrorPaired)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingDirect)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingProblem)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingTuner)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AnnealingPaired)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace spec2fab::bench_tuning

BENCHMARK_MAIN();

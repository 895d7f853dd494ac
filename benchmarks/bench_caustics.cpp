// One evaluation of the caustic tracer at the smooth-caustics size (paper
// Fig. 9, after Finckh et al. 2010): a 50 x 50 mm slab whose top is meshed
// on 181 x 181 vertices (three per span of a 60 x 60 B-spline control grid),
// 240 x 240 image, 480 x 480 stratified rays. Each iteration moves the
// heights (a different smooth bump field), refits and renders — what every
// optimizer step costs.
//
// The second argument picks the estimator: 0 rays, 1 facets, 2 smooth
// (CausticSetup::Estimator).
//
//   build/benchmarks/bench_caustics --benchmark_min_time=2

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/global_control.h>

#include "caustics/caustic_tracer.h"

namespace spec2fab {
namespace {

CausticSetup smooth_setup(int64_t estimator = 0) {
  CausticSetup s;
  s.estimator = static_cast<CausticSetup::Estimator>(estimator);
  s.width_mm = s.depth_mm = 50;
  s.vertices_x = s.vertices_y = 181;
  s.receiver_distance_mm = 200;
  s.receiver_width_mm = s.receiver_depth_mm = 50;
  s.image_width = s.image_height = 240;
  s.rays_x = s.rays_y = 480;
  return s;
}

// A smooth field of bumps 0.8 mm deep over a 5 mm slab, shifted by `phase`.
void bump_field(const CausticTracer& tracer, double phase, std::vector<double>& heights) {
  const CausticSetup& s = tracer.setup();
  for (int j = 0, k = 0; j < s.vertices_y; ++j)
    for (int i = 0; i < s.vertices_x; ++i, ++k) {
      const Eigen::Vector2d p = tracer.vertex_xy(i, j);
      heights[static_cast<size_t>(k)] =
          5 + 0.4 * std::sin(0.3 * p.x() + phase) * std::cos(0.25 * p.y() - phase);
    }
}

void BM_CausticEvaluation(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(0)));
  CausticTracer tracer(smooth_setup(state.range(1)));
  std::vector<double> heights(tracer.heights().size());
  std::vector<double> image(240 * 240);
  int step = 0;
  for (auto _ : state) {
    bump_field(tracer, 0.1 * step++, heights);
    tracer.set_heights(heights);
    const CausticFlux flux = tracer.render(image);
    benchmark::DoNotOptimize(flux);
  }
  state.counters["evaluations/s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                       benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CausticEvaluation)->ArgsProduct({{1, 2}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

// An evaluation with its derivative, as a gradient-based optimizer pays for
// it: render, then carry ∂E/∂pixel of an image MSE (against a uniform goal)
// back to every vertex height.
void BM_CausticEvaluationWithGradient(benchmark::State& state) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(0)));
  CausticTracer tracer(smooth_setup(state.range(1)));
  std::vector<double> heights(tracer.heights().size()), d_heights(heights.size());
  std::vector<double> image(240 * 240), d_image(image.size());
  int step = 0;
  for (auto _ : state) {
    bump_field(tracer, 0.1 * step++, heights);
    tracer.set_heights(heights);
    tracer.render(image);
    for (size_t p = 0; p < image.size(); ++p) d_image[p] = 2 * (image[p] - 1.0) / static_cast<double>(image.size());
    tracer.pull_back(d_image, d_heights);
    benchmark::DoNotOptimize(d_heights.data());
  }
  state.counters["evaluations/s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                       benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CausticEvaluationWithGradient)->ArgsProduct({{1, 2}, {0, 1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

// The refit alone (heights moved, normals recomputed, BVH refitted): the part
// of an evaluation that is not tracing.
void BM_CausticRefitOnly(benchmark::State& state) {
  CausticTracer tracer(smooth_setup());
  std::vector<double> heights(tracer.heights().size());
  int step = 0;
  for (auto _ : state) {
    bump_field(tracer, 0.1 * step++, heights);
    tracer.set_heights(heights);
  }
}
BENCHMARK(BM_CausticRefitOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace spec2fab

BENCHMARK_MAIN();

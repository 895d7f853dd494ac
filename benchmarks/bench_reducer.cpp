// Batch queries through the paper's texture tree (Stratum -> Column ->
// Layered) on a closed mesh of ~100k triangles.
//
//   build/benchmarks/bench_reducer --benchmark_min_time=2
//
// BM_TextureTreeGrid: rows of points on a regular grid over the bounds, the
//   workload of fabrication (most points are far from the surface).
// BM_TextureTreeShellRows: rows (latitude circles) inside the 2 mm shell:
//   every query needs depth and (u,v), but neighbours share cache lines.
// BM_TextureTreeShellRandom: the same number of shell points in random order —
//   the worst case, bound by cache misses.
// The /threads:N argument runs rows in parallel with oneTBB over N threads.

#include <benchmark/benchmark.h>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "core/properties.h"
#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "geometry/surface_field.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"

namespace spec2fab {
namespace {

struct Fixture {
  Fixture() : solid(make_sphere(25.0, 320, 160), UvSource::mesh, 2), palette(materials()) {
    const Properties tree_json = Properties::parse(R"({
      "type": "stratum", "depth_mm": 2.0,
      "shell": {"type": "column", "count": [256, 128], "child": {"type": "layered", "layers": [
          {"material": "cyan", "thickness_mm": 0.3}, {"material": "magenta", "thickness_mm": 0.3}],
          "fill": "white"}},
      "core": {"type": "layered", "material": "white"}})", "bench");
    tree = std::make_unique<ReducerTree>(tree_json, palette);
    tree->bind(solid);
  }
  static std::vector<Material> materials() {
    std::vector<Material> m(3);
    m[0].name = "cyan";
    m[1].name = "magenta";
    m[2].name = "white";
    return m;
  }
  Solid solid;
  MaterialPalette palette;
  std::unique_ptr<ReducerTree> tree;
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

constexpr int kRow = 1024;

// Runs `rows` rows of kRow points, row r starting at start(r), in parallel.
template <class Start>
void run_rows(benchmark::State& state, int rows, const Start& start, const Vec3& step) {
  Fixture& f = fixture();
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(0)));
  long long checksum = 0;
  for (auto _ : state) {
    std::vector<long long> sums(static_cast<size_t>(rows));
    tbb::parallel_for(tbb::blocked_range<int>(0, rows, 8), [&](const tbb::blocked_range<int>& range) {
      ReducerTree::Query query(*f.tree);
      std::vector<MaterialId> out(kRow);
      for (int r = range.begin(); r < range.end(); ++r) {
        query.material_row(start(r), step, kRow, out.data());
        long long s = 0;
        for (MaterialId id : out) s += id;
        sums[static_cast<size_t>(r)] = s;
      }
    });
    for (long long s : sums) checksum += s;
  }
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations() * rows * kRow);
  state.counters["triangles"] = static_cast<double>(f.solid.mesh().triangles.size());
}

void BM_TextureTreeGrid(benchmark::State& state) {
  const Bounds b = fixture().solid.bounds();
  const int ny = 64, nz = 64;
  const Vec3 size = b.size();
  run_rows(
      state, ny * nz,
      [&](int r) {
        return Vec3(b.lower.x(), b.lower.y() + (r % ny + 0.5) * size.y() / ny,
                    b.lower.z() + (r / ny + 0.5) * size.z() / nz);
      },
      Vec3(size.x() / kRow, 0, 0));
}

// Queries `points` in chunks of kRow, chunks in parallel.
void run_points(benchmark::State& state, const std::vector<Vec3>& points) {
  Fixture& f = fixture();
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(0)));
  const int chunks = static_cast<int>(points.size() / kRow);
  long long checksum = 0;
  for (auto _ : state) {
    std::vector<long long> sums(static_cast<size_t>(chunks));
    tbb::parallel_for(tbb::blocked_range<int>(0, chunks, 8), [&](const tbb::blocked_range<int>& range) {
      ReducerTree::Query query(*f.tree);
      for (int c = range.begin(); c < range.end(); ++c) {
        long long s = 0;
        for (int i = 0; i < kRow; ++i) s += query.material_at(points[static_cast<size_t>(c * kRow + i)]);
        sums[static_cast<size_t>(c)] = s;
      }
    });
    for (long long s : sums) checksum += s;
  }
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations() * static_cast<long long>(points.size()));
}

void BM_TextureTreeShellRows(benchmark::State& state) {
  static const std::vector<Vec3> points = [] {
    std::vector<Vec3> p;
    for (int ring = 0; ring < 1024; ++ring) {
      const double z = -0.95 + 1.9 * (ring + 0.5) / 1024, r = std::sqrt(1 - z * z);
      const double depth = 0.1 + 1.8 * (ring % 9) / 8.0;
      for (int i = 0; i < kRow; ++i) {
        const double phi = 2 * M_PI * (i + 0.5) / kRow;
        p.push_back((25.0 - depth) * Vec3(r * std::cos(phi), r * std::sin(phi), z));
      }
    }
    return p;
  }();
  run_points(state, points);
}

void BM_TextureTreeShellRandom(benchmark::State& state) {
  // Random points in the 2 mm shell of the 25 mm sphere.
  static const std::vector<Vec3> points = [] {
    std::vector<Vec3> p;
    uint64_t x = 88172645463325252ull;
    auto uniform = [&] {  // xorshift64: fixed points, no dependence on the standard library
      x ^= x << 13;
      x ^= x >> 7;
      x ^= x << 17;
      return static_cast<double>(x >> 11) * 0x1.0p-53;
    };
    for (int i = 0; i < kRow * 1024; ++i) {
      const double z = 2 * uniform() - 1, phi = 2 * M_PI * uniform();
      const double r = std::sqrt(1 - z * z), depth = 2 * uniform();
      p.push_back((25.0 - depth) * Vec3(r * std::cos(phi), r * std::sin(phi), z));
    }
    return p;
  }();
  run_points(state, points);
}

BENCHMARK(BM_TextureTreeGrid)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TextureTreeShellRows)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TextureTreeShellRandom)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace spec2fab

BENCHMARK_MAIN();

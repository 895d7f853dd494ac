// End-to-end fabrication throughput: the paper's texture tree on a 50 mm
// sphere evaluated at every voxel of a J750-class printer (600 × 300 dpi,
// 27 µm layers: 1181 × 590 × 1852 = 1.29e9 voxels) and written as a PNG
// slice stack, against the physical limit — memset and write of the same
// bytes (one 8-bit image's worth per layer, uncompressed).
//
//   build/benchmarks/bench_fabrication --benchmark_filter=.
//
// Arguments: threads; layers (0 = all 1852; a smaller count takes that many
// layers through the equator); zlib level of the PNGs. Run one benchmark per
// process (--benchmark_filter): after a 1-thread run, oneTBB's second worker
// was seen to stay idle in the next one in the same process. Counters: voxels/s
// (items_per_second), peak resident memory (MiB, getrusage), bytes written.

#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>

#include <tbb/global_control.h>

#include "core/properties.h"
#include "fabrication/fabricator.h"
#include "fabrication/slice_stack_writer.h"
#include "geometry/primitives.h"
#include "geometry/solid.h"
#include "materials/palette.h"
#include "reducer/reducer_tree.h"

namespace spec2fab {
namespace {

namespace fs = std::filesystem;

struct Fixture {
  Fixture() : solid(make_sphere(25.0, 320, 160), UvSource::mesh, 2), palette(materials()) {
    const Properties tree_json = Properties::parse(R"({
      "type": "stratum", "depth_mm": 2.0,
      "shell": {"type": "column", "count": [256, 128], "child": {"type": "layered", "layers": [
          {"material": "cyan", "thickness_mm": 0.3}, {"material": "magenta", "thickness_mm": 0.3}],
          "fill": "white"}},
      "core": {"type": "layered", "material": "white"}})",
                                                   "bench");
    tree = std::make_unique<ReducerTree>(tree_json, palette);
    tree->bind(solid);
    printer.name = "J750-class";
    printer.dpi = {600, 300};
    printer.layer_mm = 0.027;
    printer.build_volume_mm = {490, 390, 200};
  }
  static std::vector<Material> materials() {
    std::vector<Material> m(3);
    m[0].name = "cyan";
    m[0].display_srgb = {0, 0.62, 0.85};
    m[1].name = "magenta";
    m[1].display_srgb = {0.85, 0.1, 0.5};
    m[2].name = "white";
    m[2].display_srgb = {0.95, 0.95, 0.94};
    return m;
  }
  Solid solid;
  MaterialPalette palette;
  std::unique_ptr<ReducerTree> tree;
  PrinterProfile printer;
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

double peak_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

fs::path scratch() {
  const fs::path dir = fs::temp_directory_path() / ("spec2fab_bench_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::pair<int, int> layer_range(const FabricationGrid& grid, long long layers) {
  if (layers <= 0 || layers >= grid.size[2]) return {0, grid.size[2]};
  const int count = static_cast<int>(layers);
  return {(grid.size[2] - count) / 2, count};
}

size_t bytes_in(const fs::path& dir) {
  size_t total = 0;
  for (const auto& entry : fs::directory_iterator(dir)) total += entry.file_size();
  return total;
}

void BM_TreeAndPngSlices(benchmark::State& state) {
  Fixture& f = fixture();
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<size_t>(state.range(0)));
  const Fabricator fabricator(*f.tree, f.printer);
  const auto [first, count] = layer_range(fabricator.plan().grid, state.range(1));
  const fs::path dir = scratch();
  size_t bytes = 0;
  for (auto _ : state) {
    SliceStackWriter writer(dir, f.printer, static_cast<int>(state.range(2)));
    fabricator.run({&writer}, {}, first, count);
    state.PauseTiming();
    bytes = bytes_in(dir);
    fs::remove_all(dir);
    fs::create_directories(dir);
    state.ResumeTiming();
  }
  fs::remove_all(dir);
  state.SetItemsProcessed(state.iterations() * fabricator.plan().grid.slice_voxels() * count);
  state.counters["layers"] = count;
  state.counters["png_MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["peak_MiB"] = peak_mib();
}

// The physical limit: the same number of bytes (one per voxel), memset and
// written to one file per layer, no evaluation and no compression.
void BM_MemsetAndWrite(benchmark::State& state) {
  Fixture& f = fixture();
  const FabricationGrid grid = Fabricator(*f.tree, f.printer).plan().grid;
  const auto [first, count] = layer_range(grid, state.range(1));
  const fs::path dir = scratch();
  std::vector<unsigned char> slice(static_cast<size_t>(grid.slice_voxels()));
  for (auto _ : state) {
    for (int z = first; z < first + count; ++z) {
      std::memset(slice.data(), z & 0xff, slice.size());
      const fs::path file = dir / SliceStackWriter::slice_name(z);
      FILE* out = std::fopen(file.c_str(), "wb");
      std::fwrite(slice.data(), 1, slice.size(), out);
      std::fclose(out);
    }
    state.PauseTiming();
    fs::remove_all(dir);
    fs::create_directories(dir);
    state.ResumeTiming();
  }
  fs::remove_all(dir);
  state.SetItemsProcessed(state.iterations() * grid.slice_voxels() * count);
  state.counters["peak_MiB"] = peak_mib();
}

BENCHMARK(BM_TreeAndPngSlices)
    ->Args({1, 200, 1})
    ->Args({2, 200, 1})
    ->Args({2, 200, 6})
    ->Args({2, 0, 1})
    ->ArgNames({"threads", "layers", "zlib"})
    ->UseRealTime()
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK(BM_MemsetAndWrite)
    ->Args({1, 0})
    ->ArgNames({"threads", "layers"})
    ->UseRealTime()
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace spec2fab

BENCHMARK_MAIN();

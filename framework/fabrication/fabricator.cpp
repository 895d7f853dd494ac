#include "fabrication/fabricator.h"

#include <time.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <tbb/concurrent_queue.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>

#include "core/error.h"

namespace spec2fab {

FabricationGrid FabricationGrid::covering(const Bounds& bounds,
                                          const std::array<double, 3>& voxel_mm) {
  FabricationGrid grid;
  grid.voxel_mm = voxel_mm;
  const Vec3 size = bounds.size();
  grid.needed_voxels = 1;
  for (int axis = 0; axis < 3; ++axis) {
    // Centres span the bounds, centred on them, so the shape sits
    // symmetrically in its voxels.
    const double needed = std::max(1.0, std::ceil(size[axis] / voxel_mm[axis] - 1e-9));
    grid.needed_voxels *= needed;
    const int n = static_cast<int>(std::min(needed, static_cast<double>(std::numeric_limits<int>::max())));
    grid.size[axis] = n;
    grid.origin_mm[axis] = bounds.center()[axis] - 0.5 * (n - 1) * voxel_mm[axis];
  }
  return grid;
}

namespace {

// Throughput assumed by the estimate, per core: tree evaluation plus PNG
// writing measured about 25 M voxels/s per core (benchmarks/RESULTS.md).
constexpr double kVoxelsPerSecondPerCore = 25e6;
// Compressed palette PNGs of typical prints take ~0.02 byte/voxel; assume
// more so that the disk estimate errs on the safe side.
constexpr double kDiskBytesPerVoxel = 0.05;
// Calibrated on the shipped experiments (benchmarks/RESULTS.md, "Fabrication
// at scale"): the share of two cores' tree evaluation that overlaps, and the
// surfaces' cost per voxel beyond it (the slice writers' hides in the first).
constexpr double kParallelEfficiency = 0.9;
constexpr double kSurfaceSecondsPerVoxel = 2e-9;

std::string human_bytes(double bytes) {
  if (bytes >= 1e9) return fmt::format("{:.1f} GB", bytes / 1e9);
  if (bytes >= 1e6) return fmt::format("{:.1f} MB", bytes / 1e6);
  return fmt::format("{:.0f} kB", bytes / 1e3);
}

struct Slice {
  int z = 0;
  std::vector<MaterialId> ids;
  std::vector<long long> counts;
};

}  // namespace

std::string FabricationPlan::describe() const {
  return fmt::format(
      "{} x {} x {} voxels ({:.3g}) of {:.4g} x {:.4g} x {:.4g} mm, ~{:.{}f} s, ~{} on disk",
      grid.size[0], grid.size[1], grid.size[2], grid.needed_voxels, grid.voxel_mm[0],
      grid.voxel_mm[1], grid.voxel_mm[2], estimated_seconds, estimated_seconds < 10 ? 1 : 0,
      human_bytes(static_cast<double>(estimated_bytes)));
}

Fabricator::Fabricator(const ReducerTree& tree, const PrinterProfile& printer, int threads)
    : tree_(tree), printer_(printer) {
  if (!tree.is_bound()) throw std::logic_error("Fabricator: the tree is not bound to a solid");
  plan_.grid = FabricationGrid::covering(tree.solid().bounds(), printer.voxel_mm());
  plan_.voxels = plan_.grid.needed_voxels < 9e18 ? plan_.grid.voxels() : std::numeric_limits<long long>::max();
  // The arena's width, as narrowed by a global_control (--threads).
  const int cores = threads > 0 ? threads
                                : static_cast<int>(std::min<size_t>(
                                      static_cast<size_t>(tbb::this_task_arena::max_concurrency()),
                                      tbb::global_control::active_value(
                                          tbb::global_control::max_allowed_parallelism)));
  cores_ = cores;
  plan_.estimated_seconds = static_cast<double>(plan_.voxels) / (kVoxelsPerSecondPerCore * cores);
  plan_.estimated_bytes =
      static_cast<long long>(kDiskBytesPerVoxel * static_cast<double>(plan_.voxels));
  // In floating point: a grid held to an int per axis (refused by check())
  // would overflow the product.
  plan_.working_bytes = static_cast<long long>(
      std::min(4.0 * (cores + 1) * static_cast<double>(plan_.grid.slice_voxels()) * sizeof(MaterialId), 9e18));
}

void Fabricator::time_sample_rows(bool surfaces) {
  const FabricationGrid& grid = plan_.grid;
  const int width = grid.size[0];
  // About 1 % of the voxels, at most 2e6 (a few tens of ms), whole rows so
  // that runs along x cost what they cost in the real thing.
  const long long budget = std::clamp(plan_.voxels / 100, 1LL, 2'000'000LL);
  const long long rows_total = static_cast<long long>(grid.size[1]) * grid.size[2];
  const long long rows = std::clamp(budget / std::max(width, 1), 1LL, rows_total);
  const int slices = static_cast<int>(std::clamp(std::llround(std::sqrt(static_cast<double>(rows))), 1LL,
                                                 static_cast<long long>(grid.size[2])));
  const int per_slice = static_cast<int>(std::clamp((rows + slices - 1) / slices, 1LL,
                                                    static_cast<long long>(grid.size[1])));
  std::vector<MaterialId> row(static_cast<size_t>(width));
  ReducerTree::Query query(tree_);
  const Vec3 step(grid.voxel_mm[0], 0, 0);
  // Timed in this thread's CPU time, not wall time: a solver's threads still
  // spinning after tuning share the cores while the sample runs but not
  // while fabrication does (on wall time the estimate was 1.8x the actual
  // time after the elastic book's FEM). Twice, keeping the faster: the
  // first pass warms the caches.
  const auto thread_seconds = [] {
    timespec now{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
    return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
  };
  double per_voxel = std::numeric_limits<double>::infinity();
  for (int pass = 0; pass < 2; ++pass) {
    const double start = thread_seconds();
    long long timed = 0;
    for (int s = 0; s < slices; ++s) {
      const int z = static_cast<int>((s + 0.5) * grid.size[2] / slices);
      for (int r = 0; r < per_slice; ++r) {
        const int y = static_cast<int>((r + 0.5) * grid.size[1] / per_slice);
        query.material_row(grid.centre_mm(0, y, z), step, width, row.data());
        timed += width;
      }
    }
    per_voxel = std::min(per_voxel, (thread_seconds() - start) / static_cast<double>(std::max(timed, 1LL)));
  }
  const double voxels = static_cast<double>(plan_.voxels);
  // Tree evaluation spreads over the cores at kParallelEfficiency; the
  // surfaces' counting and meshing come on top.
  plan_.estimated_seconds = voxels * per_voxel / (kParallelEfficiency * cores_) +
                            (surfaces ? voxels * kSurfaceSecondsPerVoxel : 0);
  plan_.sampled_seconds_per_voxel = per_voxel;
}

void Fabricator::check(long long max_voxels, const std::string& option) const {
  const Vec3 size = tree_.solid().bounds().size();
  for (int axis = 0; axis < 3; ++axis) {
    const double room = printer_.build_volume_mm[static_cast<size_t>(axis)];
    if (room > 0 && size[axis] > room) {
      throw InputError(
          fmt::format("{}: the object ({:.1f} x {:.1f} x {:.1f} mm) does not fit the build volume "
                      "of {} ({} x {} x {} mm)",
                      printer_.origin.empty() ? printer_.name : printer_.origin, size.x(), size.y(),
                      size.z(), printer_.name, printer_.build_volume_mm[0],
                      printer_.build_volume_mm[1], printer_.build_volume_mm[2]));
    }
  }
  if (plan_.grid.needed_voxels > static_cast<double>(max_voxels)) {
    throw InputError(fmt::format(
        "fabrication at {}'s resolution needs {}, more than the limit of {:.3g} voxels; "
        "raise {} to go ahead, or turn print files off",
        printer_.name, plan_.describe(), static_cast<double>(max_voxels), option));
  }
}

std::vector<long long> Fabricator::run(const std::vector<SliceSink*>& sinks,
                                       const std::function<void(int, int)>& progress,
                                       int first_layer, int layer_count) const {
  const FabricationGrid& grid = plan_.grid;
  const MaterialPalette& palette = tree_.palette();
  std::vector<SliceSink*> parallel_sinks, serial_sinks;
  for (SliceSink* sink : sinks) {
    sink->begin(grid, palette);
    (sink->parallel() ? parallel_sinks : serial_sinks).push_back(sink);
  }
  const int width = grid.size[0], height = grid.size[1];
  const int begin_z = std::clamp(first_layer, 0, grid.size[2]);
  const int end_z = layer_count < 0 ? grid.size[2] : std::min(grid.size[2], begin_z + layer_count);
  const size_t materials = palette.size();
  std::vector<long long> totals(materials, 0);

  // A few slices in flight: enough to keep every core busy while one slice is
  // being written, and the bound on memory (tokens × one slice).
  const size_t tokens = static_cast<size_t>(2 * tbb::this_task_arena::max_concurrency() + 1);
  // Slices are owned here, so an exception from a sink frees them too.
  std::vector<std::unique_ptr<Slice>> slices(tokens);
  tbb::concurrent_queue<Slice*> pool;
  for (auto& slice : slices) {
    slice = std::make_unique<Slice>();
    pool.push(slice.get());
  }
  int next_z = begin_z;
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, Slice*>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& control) -> Slice* {
                                       if (next_z >= end_z) {
                                         control.stop();
                                         return nullptr;
                                       }
                                       Slice* slice = nullptr;
                                       // At most `tokens` slices are in flight, so one is free.
                                       if (!pool.try_pop(slice))
                                         throw std::logic_error("slice pool empty");
                                       slice->ids.resize(static_cast<size_t>(grid.slice_voxels()));
                                       slice->z = next_z++;
                                       return slice;
                                     }) &
          tbb::make_filter<Slice*, Slice*>(
              tbb::filter_mode::parallel,
              [&](Slice* slice) {
                tbb::parallel_for(tbb::blocked_range<int>(0, height, 4),
                                  [&](const tbb::blocked_range<int>& rows) {
                                    ReducerTree::Query query(tree_);
                                    const Vec3 step(grid.voxel_mm[0], 0, 0);
                                    for (int y = rows.begin(); y < rows.end(); ++y) {
                                      query.material_row(
                                          grid.centre_mm(0, y, slice->z), step, width,
                                          slice->ids.data() +
                                              static_cast<size_t>(y) * static_cast<size_t>(width));
                                    }
                                  });
                slice->counts.assign(materials, 0);
                for (MaterialId id : slice->ids) ++slice->counts[id];
                for (SliceSink* sink : parallel_sinks) sink->consume(slice->z, slice->ids.data());
                return slice;
              }) &
          tbb::make_filter<Slice*, void>(tbb::filter_mode::serial_in_order, [&](Slice* slice) {
            for (SliceSink* sink : serial_sinks) sink->consume(slice->z, slice->ids.data());
            for (size_t id = 0; id < materials; ++id) totals[id] += slice->counts[id];
            if (progress) progress(slice->z + 1 - begin_z, end_z - begin_z);
            pool.push(slice);
          }));
  for (SliceSink* sink : sinks) sink->finish();
  return totals;
}

}  // namespace spec2fab

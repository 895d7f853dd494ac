#pragma once
/// Print-resolution material assignment: evaluates a bound reducer tree at the
/// centre of every printer voxel over the solid's bounds, one z-slice at a
/// time, and hands each finished slice to sinks (the writers). Memory is a few
/// slices whatever the object's size; the slices are identical for any thread
/// count (every voxel is one independent tree query).

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "materials/printer_profile.h"
#include "reducer/reducer_tree.h"

namespace spec2fab {

/// The printer's voxel grid over a solid's bounds. Voxel (x, y, z) has its
/// centre at origin_mm + (x, y, z) ⊙ voxel_mm; x varies fastest in a slice.
struct FabricationGrid {
  std::array<int, 3> size{};         ///< voxels along x, y, z
  std::array<double, 3> voxel_mm{};  ///< voxel edge along x, y, z
  Vec3 origin_mm = Vec3::Zero();     ///< centre of voxel (0, 0, 0)
  /// The voxels the bounds need, counted in floating point: `size` is held
  /// to an int per axis, so a grid beyond that (a 1e-12 mm layer) is judged
  /// by this figure, never by a wrapped or clamped count.
  double needed_voxels = 0;

  long long voxels() const { return static_cast<long long>(size[0]) * size[1] * size[2]; }
  long long slice_voxels() const { return static_cast<long long>(size[0]) * size[1]; }
  double voxel_volume_mm3() const { return voxel_mm[0] * voxel_mm[1] * voxel_mm[2]; }
  Vec3 centre_mm(int x, int y, int z) const {
    return origin_mm + Vec3(x * voxel_mm[0], y * voxel_mm[1], z * voxel_mm[2]);
  }
  /// The grid of `voxel_mm` voxels covering `bounds` (centres inside it,
  /// the voxel layout centred on the bounds).
  static FabricationGrid covering(const Bounds& bounds, const std::array<double, 3>& voxel_mm);
};

/// What a fabrication will cost, estimated before any work.
struct FabricationPlan {
  FabricationGrid grid;
  long long voxels = 0;
  double estimated_seconds = 0;   ///< tree evaluation and slice writing on `threads` cores
  long long estimated_bytes = 0;  ///< files on disk (rough: PNGs compress by content)
  long long working_bytes = 0;    ///< slice buffers in memory
  double sampled_seconds_per_voxel = 0;  ///< from time_sample_rows (0: not timed)
  std::string describe() const;   ///< "1181 x 590 x 1852 voxels (1.29e9), ~26 s, ~0.4 GB"
};

/// Receives finished slices. `ids` holds size[0] × size[1] material ids, row
/// y at ids + y·size[0]. The buffer is only valid during the call.
class SliceSink {
 public:
  virtual ~SliceSink() = default;
  /// True when consume() may run for several slices at once, in any order
  /// (each slice is independent, e.g. one PNG per slice); otherwise slices
  /// arrive in z order, one at a time.
  virtual bool parallel() const { return false; }
  virtual void begin(const FabricationGrid& grid, const MaterialPalette& palette) = 0;
  virtual void consume(int z, const MaterialId* ids) = 0;
  /// After the last slice (not called when fabrication fails).
  virtual void finish() {}
};

class Fabricator {
 public:
  /// `tree` must be bound (and outlive the fabricator).
  Fabricator(const ReducerTree& tree, const PrinterProfile& printer, int threads = 0);

  const FabricationPlan& plan() const { return plan_; }
  /// Times the tree on a sample of whole rows (evenly spread over y and z,
  /// about 1 % of a large print, one thread) and re-estimates the plan's
  /// seconds from it; the first estimate assumes a fixed rate per core.
  /// `surfaces`: the run meshes the materials too. Call after check().
  void time_sample_rows(bool surfaces);
  /// Throws InputError naming the figures and `option` (the setting that
  /// raises the limit) when the plan exceeds `max_voxels`, or when the object
  /// does not fit the printer's build volume.
  void check(long long max_voxels, const std::string& option) const;

  /// Streams every slice through the sinks; returns voxels per material id
  /// (index 0: void voxels of the grid). `progress(done, total)` is called
  /// in slice order from one thread.
  /// `first_layer`, `layer_count` (−1: to the top) restrict the run to a
  /// slab of layers (benchmarks, partial previews).
  std::vector<long long> run(const std::vector<SliceSink*>& sinks,
                             const std::function<void(int, int)>& progress = {},
                             int first_layer = 0, int layer_count = -1) const;

 private:
  const ReducerTree& tree_;
  const PrinterProfile& printer_;
  FabricationPlan plan_;
  int cores_ = 1;
};

}  // namespace spec2fab

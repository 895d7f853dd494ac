#pragma once
/// The bound callback of branch and bound for a stack of layers (paper §7.2,
/// after Hašan et al. 2010): a lower bound on the profile error of every
/// stack that completes a partial assignment of the top layers.
///
/// Why it holds. In the frequency domain the stack's reflectance is
/// f(x) = R_top + T_down T_up x / (1 − R_bottom x), where (R, T) belong to the
/// fixed top part and x is the reflectance of whatever lies below it; f is
/// monotone in x at every frequency (|R_bottom x| < 1). So an interval that
/// holds the reflectance of every possible remainder at each frequency maps
/// to an interval that holds the whole stack's, and the squared distance from
/// the target's coefficients to those intervals — the basis is orthonormal,
/// so that distance is the profile error (profile_l2) — bounds the error of
/// every completion from below. The remainder intervals are built once from
/// the bottom up over every material and thickness a layer may take.
///
/// What the simulator merges, the bound must too: adjacent layers of one
/// material are one layer, and a layer of the backing's material above the
/// backing is backing. The last fixed run may therefore still grow into the
/// layers below it; the bound keeps it open and covers every way it can.

#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <span>
#include <tuple>
#include <vector>

#include "subsurface/layer_stack.h"
#include "tuning/observation.h"
#include "subsurface/radial_profile.h"

namespace spec2fab {

/// What one layer of a searched stack may be: materials, and thicknesses in model steps.
struct LayerOptions {
  std::vector<MaterialId> materials;
  std::vector<int> steps;
};

class StackBound {
 public:
  /// Variables, in search order: material id of layer 0, its thickness (mm), layer 1's, ...
  StackBound(std::shared_ptr<LayerStackModel> model, std::vector<LayerOptions> layers,
             MaterialId backing);

  double lower_bound(std::span<const double> x, int assigned, const RadialProfileObservation& target);

 private:
  /// Per-frequency intervals, RGB interleaved.
  struct Interval {
    std::vector<double> lo, hi;
  };
  Interval point(const std::vector<double>& spectrum) const;
  void include(Interval& hull, const Interval& other) const;
  /// Every reflectance of `layer` over anything in `below`.
  Interval over(const LayerSpectra& layer, const Interval& below) const;
  /// The fixed prefix (materials and steps of its layers) bounded.
  double bound_prefix(std::span<const StackRun> prefix, const RadialProfileObservation& target);
  /// Every reflectance of an open run (m, steps) that starts at layer `next`'s
  /// top (it may absorb the layers below of its material) over what follows.
  const Interval& open_run(size_t next, MaterialId material, int steps, bool at_surface);
  bool all_may_be(size_t from, size_t to, MaterialId material) const;

  std::shared_ptr<LayerStackModel> model_;
  std::vector<LayerOptions> layers_;
  MaterialId backing_;
  std::vector<Interval> remainder_;                        ///< [j]: layers j.. over the backing
  std::vector<std::vector<std::set<int>>> step_sums_;      ///< [j][k]: thickness of layers j..j+k-1
  std::mutex mutex_;
  std::map<std::tuple<size_t, MaterialId, int, bool>, std::unique_ptr<Interval>> open_runs_;
};

}  // namespace spec2fab

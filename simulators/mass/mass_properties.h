#pragma once
/// Mass properties of a print: its mass, centre of mass and inertia tensor
/// from the materials the whole tree assigns and the library's densities
/// (void inside the solid weighs what fills the printer's cavities: a
/// PolyJet printer's support gel, nothing on FDM). What standing (Make It Stand: the centre of mass
/// over the support) and lightness depend on.
///
/// The "mass_properties" simulator is exact per voxel cell and layer where
/// the tree allows: where every node down to the material leaves splits its
/// region into axis-aligned boxes (voxel cells, layered slabs:
/// ReducerNode::box_pieces), each piece is integrated over the solid's mesh
/// exactly (geometry/box_moments.h), whatever the grid — where the leaf
/// sums below apply (no free parameter but one-material leaves' materials
/// and stepped ones) and the pieces times the mesh's triangles stay under
/// 2e6; a debug line says which path ran. Otherwise (a
/// stratum's shell, a slanted plane) it samples the tree at the centres of
/// cubic cells of a stated edge covering the solid's bounds (each cell a
/// small cube of its material: its own inertia counts), summed in runs of z
/// slices added in a fixed order, so the result is the same for any thread
/// count. The goal
/// "mass_properties" holds a target mass and centre; the metrics
/// "centre_offset" (the centres' distance across the direction of gravity,
/// mm) and "mass_difference" (grams) compare them.

#include <array>
#include <functional>
#include <limits>
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/options.h"
#include "core/search_space.h"
#include "tuning/parts.h"

namespace spec2fab {

/// An observation entry that is not known (no support polygon, no target given).
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class ReducerTree;
class Tuner;

/// Mass (kg), centre of mass (mm, the run's frame), inertia about the centre
/// of mass (kg·mm²: xx, yy, zz, xy, xz, yz, products of inertia as
/// −∫ρ x y dV) and each material's volume (mm³, per palette id; id 0: the
/// void inside the solid), one flat array.
struct MassPropertiesObservation final : ObservationOf<MassPropertiesObservation> {
  static constexpr std::string_view kType = "mass_properties";
  static constexpr std::size_t kMass = 0, kCentre = 1, kInertia = 4, kVolumes = 10;
  std::vector<double> data = std::vector<double>(kVolumes, 0.0);

  std::span<const double> values() const override { return data; }
  std::span<double> values() override { return data; }
  double mass_kg() const { return data[kMass]; }
  std::array<double, 3> centre_mm() const { return {data[kCentre], data[kCentre + 1], data[kCentre + 2]}; }
  /// Volume (mm³) of material `id`; 0 for ids past the palette it was made with.
  double volume_mm3(std::size_t id) const { return kVolumes + id < data.size() ? data[kVolumes + id] : 0.0; }
  std::size_t materials() const { return data.size() - kVolumes; }
  /// mass_properties.csv: each quantity by name, with its unit.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

struct MassPropertiesOptions {
  double voxel_mm = 0;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.voxel_mm, "voxel_mm", Range::at_least(0),
             "edge of the sampling cells where the tree is not integrated exactly; 0: the solid's longest extent / 96",
             Default{"longest extent / 96"});
  }
};

/// The centre of mass across gravity: the distance (mm) between the
/// simulated and the target centres, projected on the plane normal to
/// `gravity` (Make It Stand's centre-of-mass energy, as a distance).
struct CentreOffsetOptions {
  std::array<double, 3> gravity{0, 0, -1};
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.gravity, "gravity", "direction of gravity (any length but 0)");
  }
  bool check(std::string* why) const;
};

std::unique_ptr<SimulatorFor<MassPropertiesObservation>> make_mass_properties_simulator(
    const MassPropertiesOptions& options, const PartContext& context);

/// The volume (mm³) mass_properties samples in each leaf its free
/// parameters tune — one-material leaves whose cells it sums once (the
/// leaf sums) — on `options`' grid over the whole tree, at the values its
/// stepped parameters have now; empty where the leaf sums do not apply (a
/// free parameter that is no one-material leaf's and takes no steps).
std::vector<std::pair<const ReducerNode*, double>> tuned_leaf_volumes(ReducerTree& tree,
                                                                      const MassPropertiesOptions& options,
                                                                      const PartContext& context);

/// Fixes the free parameters of each child of `cells` (a node of `tree`,
/// e.g. a voxel node of one-material leaves) that mass_properties samples
/// no volume of on `options`' grid with the tree as it is now — cells
/// outside the solid, or wholly under a shell (a tuned shell at its
/// thinnest, then) — since a tuner has nothing to gain from them; returns how
/// many children hold some volume (they stay free).
int fix_cells_without_volume(ReducerTree& tree, ReducerNode& cells, const MassPropertiesOptions& options,
                             const PartContext& context);

/// A lower bound of mass_difference (grams) over every completion of a
/// partial assignment — the first `assigned` values of x fixed, in the order
/// of `space` (a tuner's search space on `tree`) — against a target mass
/// (kg): the mass lies between the lightest and the heaviest choice of each
/// unassigned leaf, summed over the same grid as the simulator's. For
/// branch and bound (Tuner::set_lower_bound). Stepped parameters of no leaf
/// (a stratum's depth with a step, at most 64 combinations) may come first
/// in the space: each combination of their values has its leaf volumes,
/// and the bound is the least over the combinations the assigned ones
/// allow. Empty where any other free parameter is not the material of a
/// one-material leaf (ReducerNode::assigns_one_material), or a leaf's
/// material turns on more than one.
using MassBound = std::function<double(std::span<const double> x, int assigned, double target_kg)>;
MassBound make_mass_bound(ReducerTree& tree, const SearchSpace& space, const MassPropertiesOptions& options,
                          const PartContext& context);
/// Sets make_mass_bound's bound as the lower bound of `tuner` (bound to a
/// node of `tree`), whose objective is mass_difference against a goal's
/// mass; false (and nothing set) where there is none.
bool set_mass_bound(Tuner& tuner, ReducerTree& tree, const MassPropertiesOptions& options, const PartContext& context);
/// A target mass and centre of mass (either may be left out: the metric that
/// needs it says so).
std::unique_ptr<GoalFor<MassPropertiesObservation>> make_mass_properties_goal(
    std::optional<double> mass_kg, std::optional<std::array<double, 3>> centre_mm);
std::unique_ptr<MetricFor<MassPropertiesObservation>> make_centre_offset_metric(const CentreOffsetOptions& options);
std::unique_ptr<MetricFor<MassPropertiesObservation>> make_mass_difference_metric();

}  // namespace spec2fab

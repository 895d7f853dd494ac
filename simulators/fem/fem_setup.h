#pragma once
/// What the `fem` simulator reads from JSON and turns into a mesh and
/// boundary conditions: the mesh options, fixed regions, prescribed
/// displacements, loads and probes. All boxes are axis-aligned, in the rest
/// shape's world coordinates (mm); a node on a box's face is inside it.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/limits.h"
#include "core/properties.h"
#include "core/registry.h"
#include "fem/elastic_solver.h"
#include "fem/tet_mesher.h"

namespace spec2fab::fem {

struct BoxRegion {
  Eigen::AlignedBox3d box;
  Vec3 value = Vec3::Zero();  ///< displacement (mm) or total force (N), where it has one
  std::string where;          ///< JSON location, for errors
};

/// The "linear_solver" names: "cholesky", "amg", "gamg", "block_amg", "cg".
const char* to_string(LinearSolver solver);
inline constexpr LinearSolver kLinearSolvers[] = {LinearSolver::cholesky, LinearSolver::multigrid,
                                                  LinearSolver::elastic_multigrid, LinearSolver::block_multigrid,
                                                  LinearSolver::conjugate_gradient};

struct FemSettings {
  TetgenOptions mesh;
  bool follow_interfaces = true;
  std::vector<BoxRegion> fixed, displacements, loads;
  std::vector<Vec3> probes;
  SolveOptions solve;
  LinearSolver linear_solver = LinearSolver::cholesky;
  /// Under mpirun, with gamg: spread each solve over the ranks. Unset: as
  /// the command does (PartContext: simulate spreads, run does not).
  std::optional<bool> spread_over_ranks;
  bool write_calculix_deck = false;  ///< write_report also writes calculix.inp

  static FemSettings read(const Properties& properties);
  /// The documented defaults, with no regions and no probes: what a
  /// translator composing the simulator in C++ starts from.
  static FemSettings defaults();
  static std::vector<PropertyDoc> docs();
};

/// Boundary conditions on `mesh`: nodes in fixed/displacement boxes are
/// prescribed; each load's force is spread over the boundary faces that lie
/// wholly in its box, in proportion to area (a uniform traction), a third
/// of each face's share on each corner. Throws InputError naming the box
/// when a fixed or displacement box holds no node or a load box touches no
/// boundary face, and when nothing is fixed at all.
Constraints make_constraints(const TetMesh& mesh, const std::vector<Face>& boundary,
                             const FemSettings& settings);

/// A probe's place in the mesh: its tet and barycentric weights.
struct ProbeLocation {
  int tet = -1;
  std::array<double, 4> weights{};
};
/// Throws InputError for a probe outside the mesh.
std::vector<ProbeLocation> locate_probes(const TetMesh& mesh, const std::vector<Vec3>& probes,
                                         const std::string& where);
/// A nodal field (3 per node) at a located point, interpolated in its tet.
inline Vec3 interpolate(const TetMesh& mesh, const ProbeLocation& at, std::span<const double> field) {
  Vec3 sum = Vec3::Zero();
  for (size_t k = 0; k < 4; ++k) {
    const auto v = static_cast<size_t>(mesh.tets[static_cast<size_t>(at.tet)][k]);
    sum += at.weights[k] * Vec3(field[3 * v], field[3 * v + 1], field[3 * v + 2]);
  }
  return sum;
}

/// Refuses a tet size whose mesh would not fit in memory, before meshing.
void check_mesh_fits(double solid_volume_mm3, const TetgenOptions& options, const std::string& where,
                     const Limits& limits);

}  // namespace spec2fab::fem

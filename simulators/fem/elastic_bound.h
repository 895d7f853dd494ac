#pragma once
/// The bound callback of branch and bound for material assignments under
/// small-strain elasticity (paper §6.2: the same search as the subsurface
/// stacks, another bound): a lower bound on shape_mse for every assignment
/// that completes a partial one.
///
/// Why it holds. With clamped supports and dead loads f, the displacement is
/// u = K⁻¹f, and a probe's displacement along an axis is gᵀK⁻¹f for a fixed
/// vector g (the probe's interpolation weights). An isotropic tet's
/// stiffness is λ·A + μ·B with A, B positive semidefinite, so K grows (in
/// the Loewner order) with every element's λ and μ. Give each undecided
/// element the largest λ and μ any of its choices has (K⁺, stiffer than every
/// completion) and, separately, the smallest (K⁻, softer than all): every
/// completion's K⁻¹ lies between K⁺⁻¹ and K⁻⁻¹. Writing K⁻¹ = K⁺⁻¹ + D with
/// 0 ⪯ D ⪯ Δ = K⁻⁻¹ − K⁺⁻¹, Cauchy–Schwarz gives
///   |gᵀK⁻¹f − gᵀK⁺⁻¹f| ≤ √(gᵀΔg · fᵀΔf),
/// and the same about K⁻⁻¹. Each probe component therefore lies in an
/// interval, and shape_mse = (1/n) Σ ‖u_probe − u_goal‖² is at least the
/// mean squared distance from the goal to those intervals. On a complete
/// assignment K⁺ = K⁻ and the bound is the error itself.
///
/// What it does not cover: large deformation (the co-rotated model's
/// stiffness depends on the displacement; the simulator must be
/// "nonlinear": false), prescribed non-zero displacements (they make the
/// right-hand side depend on K; only clamps), and void among a cell's
/// choices (the softest completion would lose elements, and with them the
/// ordering): each is refused when the bound is built. It also assumes that
/// every element's material is set by at most one variable of the search
/// space (a Voxel or Column of Layered nodes: the mesh follows the cells),
/// which it checks by trying every value of every variable once.
///
/// The elements no variable sets are read from the tree again at every call:
/// an earlier schedule phase may have changed them (a texture printed into a
/// shell over the tuned core), and the bound must see the print as it is.
///
/// Cost of one bound: one pass over the elements' materials, and for each
/// of K⁺ and K⁻ a factorisation and 1 + 3·probes forward triangular
/// solves (one block) on the tuner's mesh, unless the same matrix was met
/// before. It usually was: a child that gives the next variable its
/// stiffest value has its parent's K⁺, one that gives the softest its
/// parent's K⁻, and a complete assignment has K⁺ = K⁻. So the products are
/// kept per matrix, named exactly by what each variable contributes (a
/// value, or its elementwise stiffest or softest), and dropped when the
/// elements no variable sets change: a search factorises once per call or
/// less instead of twice (earth_deformable: 118 times in 177 calls), with
/// the same numbers.

#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/properties.h"
#include "fem/elastic_solver.h"
#include "fem/fem_setup.h"
#include "fem/mesh_cache.h"
#include "tuning/observation.h"
#include "tuning/simulation_domain.h"
#include "fem/displacements.h"

namespace spec2fab {
class ReducerTree;
class ReducerNode;
class Tuner;
struct PartContext;
}  // namespace spec2fab

namespace spec2fab::fem {

class ElasticBound {
 public:
  /// `simulator` is the tuner's "fem" options; `tuner` must be bound to
  /// `node` of `tree` (its parameters are tried, then set back).
  ElasticBound(const Properties& simulator, const PartContext& context, ReducerTree& tree, ReducerNode& node,
               Tuner& tuner);
  /// The same for the tuner's settings built in C++; `where` names them in errors.
  ElasticBound(FemSettings settings, const std::string& where, const PartContext& context, ReducerTree& tree,
               ReducerNode& node, Tuner& tuner);
  ~ElasticBound();

  /// Variables 0..assigned-1 take x[0..assigned); the rest are free.
  double lower_bound(std::span<const double> x, int assigned, const DisplacementsObservation& target);

  /// How often the bound was asked.
  long calls() const { return calls_; }
  /// How many stiffness matrices it factorised (at most two per call; the
  /// rest were met before).
  long factorizations() const { return factorizations_; }
  /// Every call in order: how many variables were assigned, and the bound
  /// (on a complete assignment, its error) — the search's progress through
  /// the subtrees, as the paper's Fig. 10 plots it.
  struct Call {
    int assigned = 0;
    double bound = 0;
  };
  const std::vector<Call>& history() const { return history_; }
  size_t variables() const { return admissible_.size(); }

 private:
  struct Element {
    int variable = -1;                  ///< the search variable that sets its material, or -1
    std::vector<double> lambda, mu;     ///< per admissible value of that variable; one entry when fixed
  };
  /// What a variable contributes to a stiffness: the index of its value, or
  /// one of these when that is the elementwise stiffest or softest.
  static constexpr int kStiffest = -1, kSoftest = -2;
  using MatrixKey = std::vector<int>;  ///< one code per variable
  /// K⁻¹'s products for the matrix `key` names: assembled from the key and
  /// factorised on first need, kept after.
  const std::optional<ElasticSolver::InverseProducts>& products(const MatrixKey& key);
  /// Setup: which variable sets each element's material and its λ, μ per value.
  void find_element_variables(Tuner& tuner, const std::string& where);
  /// Setup: each value's code (kStiffest, kSoftest or itself).
  void code_values();
  /// Setup: the loads' and the probes' right-hand sides on the free DOFs.
  void set_loads();
  FemSettings settings_;
  std::shared_ptr<const ConformedMesh> meshed_;
  const TetMesh* mesh_ = nullptr;
  Constraints constraints_;
  std::vector<ProbeLocation> probes_;
  std::unique_ptr<ElasticSolver> solver_;
  std::vector<Element> elements_;
  std::vector<char> active_;
  SimulationDomain domain_;
  std::vector<Vec3> centroids_;
  std::vector<MaterialId> current_;                 ///< the tree's materials at the centroids, per call
  std::vector<std::pair<double, double>> lame_;  ///< (λ, μ) in MPa per material id; void (0, 0)
  std::vector<double> lambda_, mu_;  ///< the matrix products() assembles, kept to reuse
  Eigen::MatrixXd loads_;  ///< free DOFs' rows of f, then of one g per probe component
  std::vector<std::vector<double>> admissible_;  ///< per variable, its values in search order
  /// Per variable and value: its MatrixKey code (kStiffest, kSoftest or
  /// the value's index).
  std::vector<std::vector<int>> value_code_;
  std::vector<int> free_stiffest_, free_softest_;  ///< per variable: the codes of an undecided one
  std::map<MatrixKey, std::optional<ElasticSolver::InverseProducts>> products_;
  long calls_ = 0, factorizations_ = 0;
  std::vector<Call> history_;
};

}  // namespace spec2fab::fem

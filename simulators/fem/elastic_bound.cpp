#include "fem/elastic_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "fem/corotated_tet.h"
#include "reducer/reducer_tree.h"
#include "tuning/simulation_domain.h"
#include "tuning/tuner.h"

namespace spec2fab::fem {

ElasticBound::ElasticBound(const Properties& simulator, const PartContext& context, ReducerTree& tree,
                           ReducerNode& node, Tuner& tuner)
    : settings_(FemSettings::read(simulator)) {
  const std::string where = simulator.where();
  if (settings_.solve.nonlinear)
    throw InputError(where + ": the elastic bound holds for small strain only; set \"nonlinear\": false");
  for (const BoxRegion& box : settings_.displacements)
    if (!box.value.isZero())
      throw InputError(box.where + ": the elastic bound needs clamped supports; a prescribed displacement makes "
                                   "the loads depend on the stiffness");
  if (settings_.probes.empty()) throw InputError(where + "/probes: the elastic bound needs probe points");

  domain_ = SimulationDomain(tree, node);
  const Solid& solid = domain_.require_solid("fem");
  meshed_ = conformed_mesh(solid, tree, settings_.mesh, settings_.follow_interfaces, context.cache);
  mesh_ = &meshed_->mesh;
  constraints_ = make_constraints(*mesh_, mesh_->boundary_faces(), settings_);
  probes_ = locate_probes(*mesh_, settings_.probes, where + "/probes");
  solver_ = std::make_unique<ElasticSolver>(*mesh_, constraints_.fixed, LinearSolver::cholesky);

  // Lamé parameters (MPa) of each material; void is inactive.
  lame_.assign(context.palette.size(), {0.0, 0.0});
  for (MaterialId id = 1; id < context.palette.size(); ++id) {
    const Material& m = context.palette.material(id);
    const double e = m.youngs_modulus_pa.value * 1e-6, nu = m.poisson_ratio.value;
    lame_[id] = {lame_lambda(e, nu), lame_mu(e, nu)};
  }

  // Which variable sets each element's material: try every value of every
  // variable once from the current assignment, and see which elements change.
  const size_t tets = mesh_->tets.size();
  centroids_.resize(tets);
  current_.resize(tets);
  for (size_t t = 0; t < tets; ++t) centroids_[t] = mesh_->centroid(t);
  SearchSpace& space = tuner.search_space();
  const std::vector<double> start = space.values();
  std::vector<MaterialId> base(tets), trial(tets);
  tuner.set_values(start);
  domain_.materials_at(centroids_, base);
  // Elements no variable sets hold one entry, which lower_bound reads afresh.
  elements_.assign(tets, Element{-1, {0.0}, {0.0}});
  active_.assign(tets, 1);
  admissible_.resize(space.dimension());
  for (size_t v = 0; v < space.dimension(); ++v) {
    const Parameter& p = space.parameter(v);
    if (p.kind() == ParameterKind::continuous)
      throw InputError(where + ": the elastic bound needs discrete variables; '" + space.entries()[v].name +
                       "' is continuous");
    for (long long k = 0; k < p.cardinality(); ++k) admissible_[v].push_back(p.admissible(k));
    std::vector<std::vector<MaterialId>> per_value;
    for (double value : admissible_[v]) {
      std::vector<double> x = start;
      x[v] = value;
      tuner.set_values(x);
      domain_.materials_at(centroids_, trial);
      per_value.push_back(trial);
    }
    for (size_t t = 0; t < tets; ++t) {
      bool varies = false;
      for (const auto& materials : per_value) varies |= materials[t] != base[t];
      if (!varies) continue;
      Element& e = elements_[t];
      if (e.variable >= 0)
        throw InputError(fmt::format("{}: element {} takes its material from two variables ('{}' and '{}'); the "
                                     "elastic bound needs one variable per element (a Voxel or Column of Layered "
                                     "nodes)",
                                     where, t, space.entries()[static_cast<size_t>(e.variable)].name,
                                     space.entries()[v].name));
      e.variable = static_cast<int>(v);
      e.lambda.clear();
      e.mu.clear();
      for (const auto& materials : per_value) {
        if (materials[t] == kVoid)
          throw InputError(where + ": '" + space.entries()[v].name + "' may make an element void; the elastic "
                                   "bound needs a solid material in every choice");
        e.lambda.push_back(lame_[materials[t]].first);
        e.mu.push_back(lame_[materials[t]].second);
      }
    }
  }
  tuner.set_values(start);

  // Right-hand sides: the loads, then each probe component's weights.
  loads_.push_back(constraints_.force_n);
  for (const ProbeLocation& probe : probes_) {
    for (int d = 0; d < 3; ++d) {
      std::vector<double>& g = loads_.emplace_back(3 * mesh_->nodes.size(), 0.0);
      for (size_t k = 0; k < 4; ++k) {
        const auto node_index = static_cast<size_t>(mesh_->tets[static_cast<size_t>(probe.tet)][k]);
        g[3 * node_index + static_cast<size_t>(d)] += probe.weights[k];
      }
    }
  }
}

ElasticBound::~ElasticBound() = default;

double ElasticBound::lower_bound(std::span<const double> x, int assigned, const DisplacementsObservation& target) {
  ++calls_;
  const size_t tets = elements_.size();
  domain_.materials_at(centroids_, current_);
  for (size_t t = 0; t < tets; ++t) {
    Element& e = elements_[t];
    if (e.variable >= 0) continue;
    e.lambda[0] = lame_[current_[t]].first;
    e.mu[0] = lame_[current_[t]].second;
    active_[t] = current_[t] != kVoid;
  }
  lambda_stiff_.resize(tets);
  mu_stiff_.resize(tets);
  lambda_soft_.resize(tets);
  mu_soft_.resize(tets);
  for (size_t t = 0; t < tets; ++t) {
    const Element& e = elements_[t];
    if (e.variable >= 0 && e.variable < assigned) {
      const std::vector<double>& values = admissible_[static_cast<size_t>(e.variable)];
      const auto k = static_cast<size_t>(
          std::find(values.begin(), values.end(), x[static_cast<size_t>(e.variable)]) - values.begin());
      if (k == values.size()) throw std::logic_error("ElasticBound: a value that is not admissible");
      lambda_stiff_[t] = lambda_soft_[t] = e.lambda[k];
      mu_stiff_[t] = mu_soft_[t] = e.mu[k];
    } else {
      lambda_stiff_[t] = *std::max_element(e.lambda.begin(), e.lambda.end());
      mu_stiff_[t] = *std::max_element(e.mu.begin(), e.mu.end());
      lambda_soft_[t] = *std::min_element(e.lambda.begin(), e.lambda.end());
      mu_soft_[t] = *std::min_element(e.mu.begin(), e.mu.end());
    }
  }
  // M(i, k) = loads[i]ᵀ K⁻¹ loads[k]: loads[0] is f, loads[j + 1] probe component j's g.
  solver_->set_materials(lambda_stiff_, mu_stiff_, active_);
  const Eigen::MatrixXd stiff = solver_->solve_linear(loads_, loads_);
  solver_->set_materials(lambda_soft_, mu_soft_, active_);
  const Eigen::MatrixXd soft = solver_->solve_linear(loads_, loads_);
  if (stiff.size() == 0) {  // even the stiffest completion is singular: nothing to bound
    history_.push_back({assigned, 0.0});
    return 0;
  }
  // fᵀΔf, ≥ 0 up to rounding; infinite when the softest completion is singular.
  const double spread_f =
      soft.size() == 0 ? std::numeric_limits<double>::infinity() : std::max(0.0, soft(0, 0) - stiff(0, 0));
  const std::span<const double> goal = target.probes();
  double sum = 0;
  for (Eigen::Index j = 1; j < static_cast<Eigen::Index>(loads_.size()); ++j) {
    const double at_stiff = stiff(j, 0);
    double low = at_stiff, high = at_stiff, width = spread_f;
    if (soft.size() != 0) {
      const double at_soft = soft(j, 0);
      low = std::max(at_stiff, at_soft);
      high = std::min(at_stiff, at_soft);
      width = std::sqrt(spread_f * std::max(0.0, soft(j, j) - stiff(j, j)));
    }
    // Both intervals hold every completion's value: their intersection.
    low -= width;
    high += width;
    const double u = goal[static_cast<size_t>(j - 1)];
    const double outside = u < low ? low - u : u > high ? u - high : 0.0;
    sum += outside * outside;
  }
  const double bound = sum / static_cast<double>(target.probe_count);
  history_.push_back({assigned, bound});
  return bound;
}

}  // namespace spec2fab::fem

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
    : ElasticBound(FemSettings::read(simulator), simulator.where(), context, tree, node, tuner) {}

ElasticBound::ElasticBound(FemSettings settings, const std::string& where, const PartContext& context,
                           ReducerTree& tree, ReducerNode& node, Tuner& tuner)
    : settings_(std::move(settings)) {
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
  find_element_variables(tuner, where);
  code_values();
  set_loads();
}

// Which variable sets each element's material: try every value of every
// variable once from the current assignment, and see which elements change.
void ElasticBound::find_element_variables(Tuner& tuner, const std::string& where) {
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
}

// Each value's code: is it, on every element of its variable, the stiffest
// (largest λ and μ) or the softest of the choices?
void ElasticBound::code_values() {
  const size_t variables = admissible_.size();
  value_code_.resize(variables);
  free_stiffest_.assign(variables, kStiffest);
  free_softest_.assign(variables, kSoftest);
  for (size_t v = 0; v < variables; ++v) {
    const size_t values = admissible_[v].size();
    std::vector<char> stiffest(values, 1), softest(values, 1);
    bool uniform = true;  // every value gives every element the same λ and μ
    for (const Element& e : elements_) {
      if (e.variable != static_cast<int>(v)) continue;
      const auto [lambda_low, lambda_high] = std::minmax_element(e.lambda.begin(), e.lambda.end());
      const auto [mu_low, mu_high] = std::minmax_element(e.mu.begin(), e.mu.end());
      uniform &= *lambda_low == *lambda_high && *mu_low == *mu_high;
      for (size_t k = 0; k < values; ++k) {
        stiffest[k] &= e.lambda[k] == *lambda_high && e.mu[k] == *mu_high;
        softest[k] &= e.lambda[k] == *lambda_low && e.mu[k] == *mu_low;
      }
    }
    if (uniform) free_softest_[v] = kStiffest;
    for (size_t k = 0; k < values; ++k)
      value_code_[v].push_back(stiffest[k] ? kStiffest : softest[k] ? kSoftest : static_cast<int>(k));
  }
}

// Right-hand sides: the loads, then each probe component's weights.
void ElasticBound::set_loads() {
  std::vector<std::vector<double>> loads{constraints_.force_n};
  for (const ProbeLocation& probe : probes_) {
    for (int d = 0; d < 3; ++d) {
      std::vector<double>& g = loads.emplace_back(3 * mesh_->nodes.size(), 0.0);
      for (size_t k = 0; k < 4; ++k) {
        const auto node_index = static_cast<size_t>(mesh_->tets[static_cast<size_t>(probe.tet)][k]);
        g[3 * node_index + static_cast<size_t>(d)] += probe.weights[k];
      }
    }
  }
  loads_ = solver_->free_rows(loads);
}

ElasticBound::~ElasticBound() = default;

const std::optional<ElasticSolver::InverseProducts>& ElasticBound::products(const MatrixKey& key) {
  if (const auto found = products_.find(key); found != products_.end()) return found->second;
  // The matrix is made from its key alone, so a kept one is the same matrix.
  const size_t tets = elements_.size();
  lambda_.resize(tets);
  mu_.resize(tets);
  for (size_t t = 0; t < tets; ++t) {
    const Element& e = elements_[t];
    const int code = e.variable < 0 ? 0 : key[static_cast<size_t>(e.variable)];
    if (code == kStiffest) {
      lambda_[t] = *std::max_element(e.lambda.begin(), e.lambda.end());
      mu_[t] = *std::max_element(e.mu.begin(), e.mu.end());
    } else if (code == kSoftest) {
      lambda_[t] = *std::min_element(e.lambda.begin(), e.lambda.end());
      mu_[t] = *std::min_element(e.mu.begin(), e.mu.end());
    } else {
      lambda_[t] = e.lambda[static_cast<size_t>(code)];
      mu_[t] = e.mu[static_cast<size_t>(code)];
    }
  }
  solver_->set_materials(lambda_, mu_, active_);
  ++factorizations_;
  return products_.emplace(key, solver_->inverse_products(loads_)).first->second;
}

double ElasticBound::lower_bound(std::span<const double> x, int assigned, const DisplacementsObservation& target) {
  ++calls_;
  const size_t tets = elements_.size();
  // The elements no variable sets, as the tree has them now; the kept
  // products hold only while those stay as they were.
  domain_.materials_at(centroids_, current_);
  bool fixed_changed = false;
  for (size_t t = 0; t < tets; ++t) {
    Element& e = elements_[t];
    if (e.variable >= 0) continue;
    const auto [lambda, mu] = lame_[current_[t]];
    const char active = current_[t] != kVoid;
    if (e.lambda[0] == lambda && e.mu[0] == mu && active_[t] == active) continue;
    fixed_changed = true;
    e.lambda[0] = lambda;
    e.mu[0] = mu;
    active_[t] = active;
  }
  if (fixed_changed) products_.clear();

  // The two matrices, named by what each variable contributes.
  const size_t variables = admissible_.size();
  MatrixKey stiff_key(variables), soft_key(variables);
  for (size_t v = 0; v < variables; ++v) {
    if (static_cast<int>(v) < assigned) {
      const std::vector<double>& values = admissible_[v];
      const auto k = static_cast<size_t>(std::find(values.begin(), values.end(), x[v]) - values.begin());
      if (k == values.size()) throw std::logic_error("ElasticBound: a value that is not admissible");
      stiff_key[v] = soft_key[v] = value_code_[v][k];
    } else {
      stiff_key[v] = free_stiffest_[v];
      soft_key[v] = free_softest_[v];
    }
  }
  // For v = loads (f, then each probe component's g): vᵢᵀK⁻¹f and vᵢᵀK⁻¹vᵢ.
  const auto& stiff = products(stiff_key);
  const auto& soft = products(soft_key);
  if (!stiff) {  // even the stiffest completion is singular: nothing to bound
    history_.push_back({assigned, 0.0});
    return 0;
  }
  // fᵀΔf, ≥ 0 up to rounding; infinite when the softest completion is singular.
  const double spread_f =
      soft ? std::max(0.0, soft->diagonal(0) - stiff->diagonal(0)) : std::numeric_limits<double>::infinity();
  const std::span<const double> goal = target.probes();
  double sum = 0;
  for (Eigen::Index j = 1; j < loads_.cols(); ++j) {
    const double at_stiff = stiff->with_first(j);
    double low = at_stiff, high = at_stiff, width = spread_f;
    if (soft) {
      const double at_soft = soft->with_first(j);
      low = std::max(at_stiff, at_soft);
      high = std::min(at_stiff, at_soft);
      width = std::sqrt(spread_f * std::max(0.0, soft->diagonal(j) - stiff->diagonal(j)));
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

#include "tuning/tuner.h"

#include "core/interrupt.h"

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace spec2fab {

void evaluate_subtree(ReducerNode& node) {
  node.evaluate();
  for (size_t i = 0; i < node.child_count(); ++i) evaluate_subtree(node.child(i));
}

namespace {

void collect_free_parameters(ReducerNode& node, const std::string& path, SearchSpace& space) {
  node.visit_parameters([&](const std::string& name, Parameter& parameter) {
    if (parameter.is_free()) space.add(path.empty() ? name : path + "/" + name, &parameter);
  });
  for (size_t i = 0; i < node.child_count(); ++i) {
    const std::string label = node.child_label(i);
    collect_free_parameters(node.child(i), path.empty() ? label : path + "/" + label, space);
  }
}

void visit_subtree_parameters(ReducerNode& node, const std::function<void(Parameter&)>& visit) {
  node.visit_parameters([&](const std::string&, Parameter& parameter) { visit(parameter); });
  for (size_t i = 0; i < node.child_count(); ++i) visit_subtree_parameters(node.child(i), visit);
}

std::string incompatibility(const Simulator& simulator, const ErrorMetric& metric, const Goal& goal) {
  if (metric.compares() != simulator.produces()) {
    return "metric '" + metric.name() + "' compares " + std::string(metric.compares()) +
           " observations, but simulator '" + simulator.name() + "' produces " +
           std::string(simulator.produces());
  }
  if (goal.describes() != simulator.produces()) {
    return "goal '" + goal.name() + "' describes " + std::string(goal.describes()) +
           " observations, but simulator '" + simulator.name() + "' produces " +
           std::string(simulator.produces());
  }
  return {};
}

}  // namespace

class Tuner::TunerProblem final : public Problem {
 public:
  explicit TunerProblem(Tuner& tuner) : tuner_(tuner) {
    for (const SearchSpace::Entry& e : tuner.space_.entries()) {
      domains_.push_back(VariableDomain::of(*e.parameter));
    }
  }
  int dimension() const override { return static_cast<int>(domains_.size()); }
  const VariableDomain& domain(int i) const override { return domains_[static_cast<size_t>(i)]; }
  double error(std::span<const double> x) override { return tuner_.error_at(x); }
  bool has(Capability capability) const override {
    if (capability == Capability::lower_bound) return static_cast<bool>(tuner_.lower_bound_);
    if (capability == Capability::neighbour_moves) return tuner_.moves_.has_value();
    if (capability == Capability::gradient)
      return tuner_.metric_->differentiable() && tuner_.simulator_->differentiable(*tuner_.node_);
    if (capability == Capability::residuals) return residual_count() > 0;
    return Problem::has(capability);
  }
  int residual_count() const override { return tuner_.metric_->residual_count(*tuner_.effective_target_); }
  // The metric's least-squares form. The Jacobian, when asked, row by row
  // through the simulator's pull_back: row k is ∂r_k/∂v_k times ∂v_k/∂x, one
  // reverse pass per residual (cheap where a residual touches few rays or
  // nodes; an optimizer may use finite differences instead, e.g. Ceres
  // "derivatives": "numeric").
  void residuals(std::span<const double> x, std::span<double> out, std::span<double> jacobian) override {
    tuner_.error_at(x);
    tuner_.metric_->residuals(*tuner_.simulated_, *tuner_.effective_target_, out);
    if (jacobian.empty()) return;
    const size_t m = out.size(), n = domains_.size();
    derivatives_.resize(m);
    const bool analytic = tuner_.simulated_->values().size() == m &&
                          tuner_.simulator_->differentiable(*tuner_.node_) &&
                          tuner_.metric_->residual_derivatives(*tuner_.simulated_, *tuner_.effective_target_,
                                                               derivatives_);
    if (!analytic) {
      throw InputError("tuner '" + tuner_.name_ + "': no analytic residual Jacobian (simulator '" +
                       tuner_.simulator_->name() + "' and metric '" + tuner_.metric_->name() +
                       "' would both need derivatives); use \"derivatives\": \"numeric\"");
    }
    sensitivity_.assign(m, 0.0);
    for (size_t k = 0; k < m; ++k) {
      const std::span<double> row = jacobian.subspan(k * n, n);
      std::fill(row.begin(), row.end(), 0.0);
      if (derivatives_[k] == 0) continue;
      sensitivity_[k] = derivatives_[k];
      tuner_.simulator_->pull_back(*tuner_.node_, sensitivity_, tuner_.space_, row);
      sensitivity_[k] = 0;
    }
  }
  double error_and_gradient(std::span<const double> x, std::span<double> gradient) override {
    return tuner_.error_and_gradient_at(x, gradient);
  }
  double lower_bound(std::span<const double> x, int assigned) override {
    if (!tuner_.lower_bound_) return Problem::lower_bound(x, assigned);
    return tuner_.lower_bound_(x, assigned, *tuner_.effective_target_);
  }
  int neighbour_count() const override {
    return tuner_.moves_ ? static_cast<int>(tuner_.moves_->neighbours.size()) : 0;
  }
  double swap_delta(std::span<const double> x, int k) override {
    if (!tuner_.moves_) return Problem::swap_delta(x, k);
    tuner_.set_values(x);  // the energy reads states, not simulations
    return tuner_.moves_->delta(static_cast<size_t>(k));
  }
  std::vector<double> commit_swap(std::span<const double> x, int k) override {
    if (!tuner_.moves_) return Problem::commit_swap(x, k);
    tuner_.set_values(x);
    tuner_.exchange_state(*tuner_.moves_->neighbours[static_cast<size_t>(k)]);
    return tuner_.space_.values();
  }

 private:
  Tuner& tuner_;
  std::vector<VariableDomain> domains_;
  std::vector<double> derivatives_, sensitivity_;  ///< residual Jacobian scratch, reused
};

Tuner::Tuner(std::string name, std::unique_ptr<Simulator> simulator,
             std::unique_ptr<ErrorMetric> metric, std::unique_ptr<Goal> goal,
             std::unique_ptr<Optimizer> optimizer)
    : name_(std::move(name)),
      simulator_(std::move(simulator)),
      metric_(std::move(metric)),
      goal_(std::move(goal)),
      optimizer_(std::move(optimizer)) {
  const std::string problem = incompatibility(*simulator_, *metric_, *goal_);
  if (!problem.empty()) throw InputError("tuner '" + name_ + "': " + problem);
  simulated_ = simulator_->make_observation();
  reset_target();
}

Tuner::~Tuner() = default;

void Tuner::reset_target() { effective_target_ = goal_->target().clone(); }

void Tuner::set_node(ReducerNode& node, const SimulationDomain& domain) {
  node_ = &node;
  collect_search_space();
  try {
    simulator_->setup(node, domain);
  } catch (const InputError&) {
    if (!origin_.empty()) rethrow_located(origin_);
    throw;
  }
}

void Tuner::set_node(ReducerTree& tree, ReducerNode& node) {
  set_node(node, tree.is_bound() ? SimulationDomain(tree, node) : SimulationDomain());
}

void Tuner::collect_search_space() {
  space_ = SearchSpace();
  collect_free_parameters(*node_, "", space_);
  problem_ = std::make_unique<TunerProblem>(*this);
}

double Tuner::error() {
  interrupt::throw_if_stop_requested();  // a relaxed load: nothing beside a simulation
  simulator_->simulate(*node_, *simulated_);
  return metric_->error(*simulated_, *effective_target_);
}

const Observation& Tuner::simulate() {
  simulator_->simulate(*node_, *simulated_);
  return *simulated_;
}

void Tuner::set_values(std::span<const double> x) {
  const auto& entries = space_.entries();
  for (size_t i = 0; i < x.size(); ++i) {
    // Optimizers often move one coordinate; snapping an unchanged one is wasted work.
    if (Parameter& p = *entries[i].parameter; x[i] != p.value()) p.set(x[i]);
  }
  evaluate_subtree(*node_);
}

double Tuner::error_at(std::span<const double> x) {
  set_values(x);
  return error() + (penalty_ ? penalty_(x, {}) : 0.0);
}

void Tuner::adopt(std::span<const double> x) {
  collect_search_space();
  set_values(x);
  error();
}

double Tuner::error_and_gradient_at(std::span<const double> x, std::span<double> gradient) {
  set_values(x);
  double e = error();
  sensitivity_.resize(simulated_->values().size());
  metric_->error_gradient(*simulated_, *effective_target_, sensitivity_);
  std::fill(gradient.begin(), gradient.end(), 0.0);
  simulator_->pull_back(*node_, sensitivity_, space_, gradient);
  if (penalty_) e += penalty_(x, gradient);
  return e;
}

Problem& Tuner::problem() { return *problem_; }

void Tuner::exchange_state(Tuner& other) {
  const auto mine = effective_target_->values(), theirs = other.effective_target_->values();
  if (mine.size() != theirs.size() || space_.dimension() != other.space_.dimension())
    throw std::logic_error("tuners '" + name_ + "' and '" + other.name_ + "' cannot exchange states: different shapes");
  std::swap_ranges(mine.begin(), mine.end(), theirs.begin());
  const std::vector<double> own = space_.values();
  error_at(other.space_.values());
  other.error_at(own);
}

Tuner::State Tuner::state() {
  State state;
  visit_subtree_parameters(*node_, [&](Parameter& p) {
    state.parameters.push_back(p.value());
    state.free.push_back(p.is_free());
  });
  const auto copy = [](std::span<const double> values) { return std::vector<double>(values.begin(), values.end()); };
  state.target = copy(effective_target_->values());
  state.simulated = copy(simulated_->values());
  state.published = published_;
  state.optimizer = optimizer_->saved_state();
  return state;
}

void Tuner::restore(const State& state) {
  size_t count = 0;
  visit_subtree_parameters(*node_, [&](Parameter&) { ++count; });
  const auto refuse = [&](const std::string& what) {
    throw std::invalid_argument("tuner '" + name_ + "': the saved state's " + what + " do not fit its subtree");
  };
  if (count != state.parameters.size() || count != state.free.size()) refuse("parameters");
  if (state.target.size() != effective_target_->values().size()) refuse("target values");
  size_t i = 0;
  // The saved values are admissible already: set() leaves them as they are.
  visit_subtree_parameters(*node_, [&](Parameter& p) {
    p.set_free(state.free[i]);
    p.set(state.parameters[i++]);
  });
  evaluate_subtree(*node_);
  collect_search_space();
  std::copy(state.target.begin(), state.target.end(), effective_target_->values().begin());
  // A simulator shapes its observation on the first simulation.
  if (simulated_->values().size() != state.simulated.size()) simulate();
  if (simulated_->values().size() != state.simulated.size()) refuse("simulated values");
  std::copy(state.simulated.begin(), state.simulated.end(), simulated_->values().begin());
  published_ = state.published;
  optimizer_->restore(state.optimizer);
}

Summary Tuner::tune(const IterationCallback& callback) {
  try {
    return tune_here(callback);
  } catch (const InputError&) {
    // A part's own check (a metric finding the goal's grid unlike the
    // simulator's) names no file: the tuner's JSON says where it was asked for.
    if (!origin_.empty()) rethrow_located(origin_);
    throw;
  }
}

Summary Tuner::tune_here(const IterationCallback& callback) {
  collect_search_space();
  if (space_.dimension() == 0) {
    Summary summary;
    summary.optimizer = optimizer_->name();
    summary.termination = Termination::converged;
    summary.message = "no free parameters";
    summary.initial_error = summary.final_error = error();
    summary.evaluations = 1;
    return summary;
  }
  std::vector<double> x = space_.values();
  Summary summary = optimizer_->minimize(*problem_, x, callback);
  error_at(x);  // leave the best values set and simulated
  return summary;
}

std::unique_ptr<Tuner> build_tuner(const Properties& properties, std::string name,
                                   const PartContext& context) {
  auto simulator =
      SimulatorRegistry::instance().create(properties.object("simulator"), "simulator", context);
  auto metric = MetricRegistry::instance().create(properties.object("metric"), "metric", context);
  auto goal = GoalRegistry::instance().create(properties.object("goal"), "goal", context);
  auto optimizer = build_optimizer(properties.object("optimizer"));
  const std::string problem = incompatibility(*simulator, *metric, *goal);
  if (!problem.empty()) properties.fail(problem);
  auto tuner = std::make_unique<Tuner>(std::move(name), std::move(simulator), std::move(metric), std::move(goal),
                                       std::move(optimizer));
  tuner->set_origin(properties.where());
  return tuner;
}

}  // namespace spec2fab

#include "tuning/tuner.h"

#include "core/interrupt.h"
#include "core/options.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
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

/// What is wrong with a rule, as "key: why" (the JSON keys' names), or "".
std::string rule_problem(const TermRule& rule) {
  if (!(rule.weight >= 0) || !std::isfinite(rule.weight)) return "weight: a finite number ≥ 0";
  if (rule.at_most && (!(*rule.at_most >= 0) || !std::isfinite(*rule.at_most))) return "at_most: a finite number ≥ 0";
  if (!(rule.penalty > 0) || !std::isfinite(rule.penalty)) return "penalty: a finite number > 0";
  return {};
}

void check_rule(const TermRule& rule, const std::string& where) {
  if (const std::string problem = rule_problem(rule); !problem.empty()) throw std::invalid_argument(where + ": " + problem);
}

}  // namespace

/// A further term with its own observations; the target is the goal's (no
/// coupling shifts it).
struct Tuner::Term {
  TunerTerm parts;
  std::unique_ptr<Observation> simulated, target;
  TermLowerBound bound;
  std::vector<double> sensitivity;
  double error = 0;
};

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
    if (capability == Capability::gradient) {
      return tuner_.metric_->differentiable() && tuner_.simulator_->differentiable(*tuner_.node_) &&
             std::all_of(tuner_.terms_.begin(), tuner_.terms_.end(), [&](const auto& term) {
               return term->parts.metric->differentiable() && term->parts.simulator->differentiable(*tuner_.node_);
             });
    }
    // A weighted sum of squares is not one sum of squares once a limit or a
    // second metric joins it: least squares only for a tuner of one term.
    if (capability == Capability::residuals) return tuner_.terms_.empty() && residual_count() > 0;
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
  // The first term's bound, weighted, plus each further term's share of its
  // own (TermRule::contribution is non-decreasing: a bound on the error
  // bounds the share; a limited term past its limit adds its penalty, as
  // the error does). Terms without a bound count 0, which every registered
  // metric's error is at least.
  double lower_bound(std::span<const double> x, int assigned) override {
    if (!tuner_.lower_bound_) return Problem::lower_bound(x, assigned);
    double bound = tuner_.weight_ * tuner_.lower_bound_(x, assigned, *tuner_.effective_target_);
    for (const auto& term : tuner_.terms_) {
      if (term->bound) bound += term->parts.rule.contribution(term->bound(x, assigned));
    }
    return bound;
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

void Tuner::add_term(TunerTerm term) {
  if (node_ != nullptr) throw std::logic_error("tuner '" + name_ + "': terms are added before set_node");
  check_rule(term.rule, "tuner '" + name_ + "', term '" + term.name + "'");
  const std::string problem = incompatibility(*term.simulator, *term.metric, *term.goal);
  if (!problem.empty()) throw InputError("tuner '" + name_ + "', term '" + term.name + "': " + problem);
  auto added = std::make_unique<Term>();
  added->simulated = term.simulator->make_observation();
  added->target = term.goal->target().clone();
  added->parts = std::move(term);
  terms_.push_back(std::move(added));
}

void Tuner::set_weight(double weight) {
  check_rule(TermRule{weight, std::nullopt, 1e3}, "tuner '" + name_ + "'");
  weight_ = weight;
}

void Tuner::set_term_lower_bound(size_t k, TermLowerBound bound) {
  if (k == 0 || k > terms_.size())
    throw std::out_of_range("tuner '" + name_ + "' has no term " + std::to_string(k) + " (the first is set_lower_bound's)");
  terms_[k - 1]->bound = std::move(bound);
}

std::optional<std::string> Tuner::simulator_reading_beyond_its_node() const {
  if (simulator_->reads_beyond_subtree()) return simulator_->name();
  for (const auto& term : terms_) {
    if (term->parts.simulator->reads_beyond_subtree()) return term->parts.simulator->name();
  }
  return std::nullopt;
}

std::optional<std::string> Tuner::simulator_spreading_over_ranks() const {
  if (simulator_->spreads_over_ranks()) return simulator_->name();
  for (const auto& term : terms_) {
    if (term->parts.simulator->spreads_over_ranks()) return term->parts.simulator->name();
  }
  return std::nullopt;
}

std::vector<TermValue> Tuner::term_values() const {
  const double first = metric_->error(*simulated_, goal_->target());
  std::vector<TermValue> values{{"objective", simulator_->name(), metric_->name(), first, weight_ * first, weight_, {}}};
  for (const auto& term : terms_) {
    const TermRule& rule = term->parts.rule;
    values.push_back({term->parts.name, term->parts.simulator->name(), term->parts.metric->name(), term->error,
                      rule.contribution(term->error), rule.at_most ? 0.0 : rule.weight, rule.at_most});
  }
  return values;
}

void Tuner::set_node(ReducerNode& node, const SimulationDomain& domain) {
  node_ = &node;
  collect_search_space();
  try {
    simulator_->setup(node, domain);
    for (const auto& term : terms_) term->parts.simulator->setup(node, domain);
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
  return combined_error();
}

double Tuner::combined_error() {
  double e = weight_ * metric_->error(*simulated_, *effective_target_);  // × 1 is exact: one term's error as it is
  for (const auto& term : terms_) {
    term->parts.simulator->simulate(*node_, *term->simulated);
    term->error = term->parts.metric->error(*term->simulated, *term->target);
    e += term->parts.rule.contribution(term->error);
  }
  return e;
}

const Observation& Tuner::simulate() {
  simulator_->simulate(*node_, *simulated_);
  for (const auto& term : terms_) term->parts.simulator->simulate(*node_, *term->simulated);
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
  // Each term's ∂error/∂(its values), scaled by its rule's slope, pulled back
  // through its simulator into the one gradient. A pull_back follows its own
  // simulate(); the first term's ran before the others', which do not touch
  // its simulator.
  const auto pull_back = [&](Simulator& simulator, const ErrorMetric& metric, const Observation& simulated,
                             const Observation& target, std::vector<double>& sensitivity, double slope) {
    if (slope == 0) return;
    sensitivity.resize(simulated.values().size());
    metric.error_gradient(simulated, target, sensitivity);
    if (slope != 1) {
      for (double& s : sensitivity) s *= slope;
    }
    simulator.pull_back(*node_, sensitivity, space_, gradient);
  };
  std::fill(gradient.begin(), gradient.end(), 0.0);
  pull_back(*simulator_, *metric_, *simulated_, *effective_target_, sensitivity_, weight_);
  for (const auto& term : terms_) {
    const TermRule& rule = term->parts.rule;
    const double slope = rule.at_most ? (term->error > *rule.at_most ? rule.penalty : 0.0) : rule.weight;
    pull_back(*term->parts.simulator, *term->parts.metric, *term->simulated, *term->target, term->sensitivity, slope);
  }
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
  // The further terms' simulations are not saved: the next error() makes
  // them again (a term may read the whole tree, whose other tuners a resumed
  // checkpoint has not restored yet).
  for (const auto& term : terms_) term->error = std::numeric_limits<double>::quiet_NaN();
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

namespace {

/// The tuner's own keys build_tuner reads beside its parts.
struct WeightKeys {
  double weight = 1;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.number(o.weight, "weight", Range::at_least(0),
             "the weight of its own simulator, metric and goal in the sum with its \"terms\"");
  }
};

/// One of a tuner's "terms", beside its simulator, metric and goal.
struct TermKeys {
  std::optional<std::string> name;
  std::optional<double> weight, at_most, penalty;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.name, "name", "how result.json names it", Default{"termN"});
    d.value(o.weight, "weight", "its weight in the sum (≥ 0)", Default{"1"});
    d.value(o.at_most, "at_most",
            "instead of a weight: a limit its error is held under (a constraint; branch and bound prunes on it)",
            Default{"none"});
    d.value(o.penalty, "penalty", "with at_most: added to the error per unit past the limit (> 0)", Default{"1000"});
  }
  bool check(std::string* why) const {
    if (weight && at_most) *why = "at_most: a term held under a limit takes no weight";
    else if (penalty && !at_most) *why = "penalty: only a term held under a limit (at_most) takes a penalty";
    else *why = rule_problem(rule());
    return why->empty();
  }
  TermRule rule() const { return {weight.value_or(1.0), at_most, penalty.value_or(TermRule{}.penalty)}; }
};

/// A simulator, metric and goal that agree, or an InputError at `properties`.
struct Parts {
  std::unique_ptr<Simulator> simulator;
  std::unique_ptr<ErrorMetric> metric;
  std::unique_ptr<Goal> goal;
};
Parts build_parts(const Properties& properties, const PartContext& context) {
  Parts parts{SimulatorRegistry::instance().create(properties.object("simulator"), "simulator", context),
              MetricRegistry::instance().create(properties.object("metric"), "metric", context),
              GoalRegistry::instance().create(properties.object("goal"), "goal", context)};
  const std::string problem = incompatibility(*parts.simulator, *parts.metric, *parts.goal);
  if (!problem.empty()) properties.fail(problem);
  return parts;
}

}  // namespace

std::unique_ptr<Tuner> build_tuner(const Properties& properties, std::string name,
                                   const PartContext& context) {
  Parts own = build_parts(properties, context);
  auto optimizer = build_optimizer(properties.object("optimizer"));
  auto tuner = std::make_unique<Tuner>(std::move(name), std::move(own.simulator), std::move(own.metric),
                                       std::move(own.goal), std::move(optimizer));
  tuner->set_weight(read_options<WeightKeys>(properties).weight);
  const std::vector<Properties> terms = properties.has("terms") ? properties.objects("terms") : std::vector<Properties>{};
  for (size_t k = 0; k < terms.size(); ++k) {
    const TermKeys keys = read_options<TermKeys>(terms[k]);
    Parts parts = build_parts(terms[k], context);
    tuner->add_term({keys.name.value_or("term" + std::to_string(k + 1)), std::move(parts.simulator),
                     std::move(parts.metric), std::move(parts.goal), keys.rule()});
  }
  tuner->set_origin(properties.where());
  return tuner;
}

std::vector<PropertyDoc> tuner_term_docs(const std::string& prefix) {
  std::vector<PropertyDoc> rows = prefixed(option_docs<WeightKeys>(), prefix);
  rows.push_back({prefix + "terms", "array of {simulator, metric, goal, " + join([] {
                    std::vector<std::string> keys;
                    for (const PropertyDoc& row : option_docs<TermKeys>()) keys.push_back(row.name);
                    return keys;
                  }()) + "}",
                  "none",
                  "further terms the tuner weighs on the same node: weighted ones add weight × error, limited ones "
                  "penalty × (error − at_most) where positive; result.json gives each one's value"});
  append(rows, prefixed(option_docs<TermKeys>(), prefix + "terms[]."));
  return rows;
}

}  // namespace spec2fab

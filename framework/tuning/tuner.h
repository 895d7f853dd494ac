#pragma once
/// A tuner (paper §5.2, §6.2–6.3): simulator + error metric + goal +
/// optimizer, bound to one reducer node (`set_node`, the paper's setNode). It
/// exposes getError over the free parameters of that subtree as a Problem and
/// tunes them with its optimizer.
///
/// The goal's target is copied into an *effective target* that tuner-network
/// couplings may shift (error diffusion adds neighbours' residuals to it);
/// `published()` is the state neighbours read.
///
/// Beside its first (simulator, metric, goal) a tuner may weigh further
/// terms (add_term): each its own simulator, metric and goal on the same
/// subtree, either added with a weight or held under a limit ("at most",
/// with a penalty, and a pruning rule for branch and bound). The error the
/// optimizer sees is their combination (see TermRule); couplings, states and
/// the residual form are the first term's.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/search_space.h"
#include "tuning/optimizer.h"
#include "tuning/parts.h"

namespace spec2fab {

/// How a term enters a tuner's error: added with `weight` (weight · error),
/// or, with `at_most`, held under that limit: penalty · max(0, error − limit)
/// is added (an exact penalty: with a penalty above the objective's rate of
/// change a tuned optimum honours the limit). Both are non-decreasing in the
/// error, so a lower bound on a term's error gives one on its share (what
/// branch and bound prunes on). A NaN error (a simulation that failed) stays
/// NaN, the worst, whichever the rule.
struct TermRule {
  double weight = 1;
  std::optional<double> at_most;
  double penalty = 1e3;
  /// This rule's share of the tuner's error for a term's error `e`.
  double contribution(double e) const {
    if (std::isnan(e)) return e;  // std::max(0.0, NaN) would be 0: a failed simulation passing a limit
    return at_most ? penalty * std::max(0.0, e - *at_most) : weight * e;
  }
};

/// A further (simulator, metric, goal) a tuner weighs (Tuner::add_term).
struct TunerTerm {
  std::string name;  ///< how the run report names it
  std::unique_ptr<Simulator> simulator;
  std::unique_ptr<ErrorMetric> metric;
  std::unique_ptr<Goal> goal;
  TermRule rule;
};

/// One term's value at the tuner's current parameters (Tuner::term_values).
struct TermValue {
  std::string name, simulator, metric;
  double error = 0;         ///< the metric's error against the term's goal
  double contribution = 0;  ///< what it adds to the tuner's error
  double weight = 1;
  std::optional<double> at_most;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.name, "name", "the term (the first is the tuner's own simulator, metric and goal)");
    f(s.simulator, "simulator", "its simulator");
    f(s.metric, "metric", "its metric");
    f(s.error, "error", "its metric's error against its goal");
    f(s.weight, "weight", "its weight in the sum (a limited term: 0)");
    f(s.at_most, "at_most", "the limit its error is held under, where it is a constraint");
    f(s.contribution, "contribution", "what it adds to the tuner's error: weight × error, or penalty × excess");
  }
};

class Tuner {
 public:
  /// Throws InputError naming both parts when their observation types differ.
  Tuner(std::string name, std::unique_ptr<Simulator> simulator, std::unique_ptr<ErrorMetric> metric,
        std::unique_ptr<Goal> goal, std::unique_ptr<Optimizer> optimizer);
  ~Tuner();

  const std::string& name() const { return name_; }
  /// Where the tuner was asked for ("exp.json: /goal/tuners/0"; build_tuner
  /// sets it): an InputError of its parts in setup or tuning that names no
  /// file comes out with it in front.
  void set_origin(std::string location) { origin_ = std::move(location); }
  /// Binds the tuner to a subtree (the paper's setNode): collects its free
  /// parameters and runs the simulator's one-time setup. `domain` places the
  /// node in the run's solid and tree (volumetric simulators need it).
  void set_node(ReducerNode& node, const SimulationDomain& domain = SimulationDomain());
  /// set_node for `node` of `tree`, with the tree's domain when the tree is
  /// bound to a solid (how translators and JSON plans attach tuners).
  void set_node(ReducerTree& tree, ReducerNode& node);
  bool is_bound() const { return node_ != nullptr; }

  /// Adds a term (before set_node). Throws InputError naming the term when
  /// its simulator, metric and goal disagree on their observation type, and
  /// std::invalid_argument for a negative weight, limit or penalty.
  void add_term(TunerTerm term);
  /// The first term's weight (1 unless set).
  void set_weight(double weight);
  size_t term_count() const { return terms_.size() + 1; }
  /// A lower bound on term k's error (k ≥ 1) over every completion of a
  /// partial assignment, like set_lower_bound's. The tuner's bound (what
  /// branch and bound prunes on; it needs the first term's, set_lower_bound)
  /// adds each term's share of its bound (TermRule::contribution). A term
  /// without one counts 0: valid for metrics whose errors are ≥ 0, as every
  /// registered one's are (a metric written in Python may not be).
  using TermLowerBound = std::function<double(std::span<const double> x, int assigned)>;
  void set_term_lower_bound(size_t k, TermLowerBound bound);
  /// Every term's error and contribution at the last simulation (the first
  /// term against the goal's own target, not a diffused one).
  std::vector<TermValue> term_values() const;
  ReducerNode& node() { return *node_; }
  SearchSpace& search_space() { return space_; }

  /// getError: simulates the subtree at its current parameters and compares
  /// with the effective target; with several terms, their combination.
  double error();
  /// Simulates the subtree at its current parameters and compares it with
  /// nothing: how a goal is made from a reference assignment (bench problems).
  const Observation& simulate();
  /// The same at parameter values x (leaves them set).
  double error_at(std::span<const double> x);
  /// Sets the free parameters to x and refreshes the subtree, simulating
  /// nothing (simulated() is then stale until the next error()).
  void set_values(std::span<const double> x);
  /// Takes up a tuning made elsewhere (another rank of an MPI run): sets the
  /// free parameters to x and simulates them, leaving the tuner as tune()
  /// would have left it had it found x.
  void adopt(std::span<const double> x);
  /// The same with ∂error/∂x (simulator and metric both differentiable;
  /// problem() then has Capability::gradient).
  double error_and_gradient_at(std::span<const double> x, std::span<double> gradient);
  /// The Problem optimizers see: error over the free parameters.
  Problem& problem();
  /// The bound callback branch and bound needs (paper §6.2): a lower bound on
  /// the error of every completion of a partial assignment — variables
  /// 0..assigned-1 of the search space take x[0..assigned) — against the
  /// effective target. Problem-specific, so a translator supplies it; with
  /// one set, problem() has Capability::lower_bound.
  using LowerBound =
      std::function<double(std::span<const double> x, int assigned, const Observation& target)>;
  void set_lower_bound(LowerBound bound) { lower_bound_ = std::move(bound); }

  /// A term added to the error optimizers see at x (error_at,
  /// error_and_gradient_at; not error(), which compares the simulation
  /// alone): a translator's soft limit on the parameters, such as a surface's
  /// slope. It returns its value and adds its gradient into `gradient`
  /// when that is not empty.
  using Penalty = std::function<double(std::span<const double> x, std::span<double> gradient)>;
  void set_penalty(Penalty penalty) { penalty_ = std::move(penalty); }

  /// Exchanges of state with network neighbours (paper §7.3, facet caustics:
  /// tuners swap their micro-lenses' kernels): with moves set, problem() has
  /// Capability::neighbour_moves. A NeighbourSwaps coupling (schedule.h)
  /// installs them for the phase it couples.
  struct NeighbourMoves {
    std::vector<Tuner*> neighbours;
    /// Change of the network's energy if this tuner and neighbours[k]
    /// exchanged states; accepted or not by the optimizer.
    std::function<double(size_t k)> delta;
  };
  void set_neighbour_moves(std::optional<NeighbourMoves> moves) { moves_ = std::move(moves); }
  /// Exchanges state with `other`: effective targets and the values of the
  /// free parameters (both tuners' subtrees must have the same shape).
  void exchange_state(Tuner& other);

  /// Runs the optimizer from the current values and leaves the best ones set.
  /// Parameters fixed since set_node (by an earlier schedule phase) are left
  /// alone; with nothing free the summary says so and nothing runs.
  Summary tune(const IterationCallback& callback = {});

  const Observation& simulated() const { return *simulated_; }
  Observation& effective_target() { return *effective_target_; }
  const Goal& goal() const { return *goal_; }
  /// Hands the simulator one of its inputs by name (Simulator::inputs): state
  /// an earlier phase leaves for it, such as the texture a first phase printed
  /// over a caustic slab's exit face.
  void set_simulator_input(std::string_view name, GridField value) { simulator_->set_input(name, std::move(value)); }
  /// The simulator's inputs, for couplings that check what they hand over.
  std::vector<SimulatorInput> simulator_inputs() const { return simulator_->inputs(); }
  /// Whether a simulator of its terms reads the tree beyond this tuner's
  /// node (Simulator::reads_beyond_subtree).
  bool reads_beyond_its_node() const { return simulator_reading_beyond_its_node().has_value(); }
  /// The name of the first such simulator, for the message that refuses it.
  std::optional<std::string> simulator_reading_beyond_its_node() const;
  /// The name of the first simulator of its terms whose solves are spread
  /// over the MPI ranks (Simulator::spreads_over_ranks): every rank must run
  /// this tuner, so it may not run in a parallel phase.
  std::optional<std::string> simulator_spreading_over_ranks() const;
  std::string simulator_name() const { return simulator_->name(); }
  std::string metric_name() const { return metric_->name(); }
  /// The simulator's files for the last simulation (Simulator::write_report)
  /// into `folder`, its sections into `record`: what `spec2fab simulate`
  /// writes, for a run that keeps its solved state (the FEM's fem.vtu).
  SimulatorFiles write_simulation_files(const std::filesystem::path& folder, ReportSections& record) const {
    return simulator_->write_report(*simulated_, folder, record);
  }
  Optimizer& optimizer() { return *optimizer_; }
  /// Puts `optimizer` in place of the tuner's own and returns the one it had
  /// (a schedule phase may tune with another optimizer; Phase::optimizer).
  std::unique_ptr<Optimizer> exchange_optimizer(std::unique_ptr<Optimizer> optimizer) {
    std::swap(optimizer, optimizer_);
    return optimizer;
  }
  /// Resets the effective target to the goal's.
  void reset_target();

  /// What a tuner holds between schedule phases: every parameter of its
  /// subtree (free and fixed, in visiting order), its effective target, its
  /// last simulation and what it publishes. A schedule's checkpoint saves it
  /// after each phase; restore() takes it up in a new process, so that a run
  /// resumed after a kill continues bit for bit (spec2fab run --resume).
  struct State {
    std::vector<double> parameters, target, simulated, published;
    std::vector<bool> free;  ///< per parameter: an earlier phase may have fixed it
    nlohmann::json optimizer;  ///< Optimizer::saved_state
  };
  State state();
  /// Throws std::invalid_argument when `state` is of another subtree's shape.
  void restore(const State& state);

  std::vector<double>& published() { return published_; }
  const std::vector<double>& published() const { return published_; }

 private:
  class TunerProblem;
  struct Term;
  void collect_search_space();
  /// The first term's error, the others' simulated, and their combination.
  double combined_error();
  Summary tune_here(const IterationCallback& callback);

  std::string name_;
  std::string origin_;
  std::unique_ptr<Simulator> simulator_;
  std::unique_ptr<ErrorMetric> metric_;
  std::unique_ptr<Goal> goal_;
  std::unique_ptr<Optimizer> optimizer_;
  ReducerNode* node_ = nullptr;
  SearchSpace space_;
  std::unique_ptr<Observation> simulated_, effective_target_;
  std::unique_ptr<TunerProblem> problem_;
  std::vector<double> published_;
  std::vector<double> sensitivity_;  ///< ∂error/∂(simulated values), reused
  LowerBound lower_bound_;
  Penalty penalty_;
  std::optional<NeighbourMoves> moves_;
  double weight_ = 1;  ///< the first term's
  std::vector<std::unique_ptr<Term>> terms_;  ///< the further terms
};

/// Builds a tuner from C++ parts; does not compile when the simulator, metric
/// and goal disagree on their observation type.
template <class S, class M, class G>
  requires CompatibleParts<S, M, G>
std::unique_ptr<Tuner> make_tuner(std::string name, std::unique_ptr<S> simulator,
                                  std::unique_ptr<M> metric, std::unique_ptr<G> goal,
                                  std::unique_ptr<Optimizer> optimizer) {
  return std::make_unique<Tuner>(std::move(name), std::move(simulator), std::move(metric),
                                 std::move(goal), std::move(optimizer));
}

/// Builds a tuner from JSON: {"simulator": {...}, "metric": {...}, "goal":
/// {...}, "optimizer": {...}}, each with a registered "type", and optionally
/// "weight" and "terms": [{"simulator", "metric", "goal", "weight" |
/// "at_most" + "penalty", "name"}]. Incompatible parts are an InputError at
/// `properties` (or the term's) naming both.
std::unique_ptr<Tuner> build_tuner(const Properties& properties, std::string name,
                                   const PartContext& context);
/// The rows of a tuner's "weight" and "terms" for a TypeDoc, under `prefix`.
std::vector<PropertyDoc> tuner_term_docs(const std::string& prefix);

/// Refreshes derived state of every node of a subtree (after its parameters changed).
void evaluate_subtree(ReducerNode& node);

}  // namespace spec2fab

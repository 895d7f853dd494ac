#pragma once
/// A schedule (paper §6.4): phases, each naming which tuners run, how many
/// sweeps, and whether serially (in the listed order) or in parallel. A
/// parallel phase colours the network so that no two neighbours run at once,
/// and every tuner run draws its random seed from (run seed, phase, sweep,
/// tuner): results are identical for any thread count. Under mpirun a
/// parallel phase's colour classes are split over the ranks as well, with
/// results identical for any rank count.
///
/// A Coupling says how tuners of a phase interact with their neighbours
/// around their own tuning (error diffusion, for example); a phase may fix
/// what it tuned so that a later phase tunes something else on top.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/limits.h"
#include "core/registry.h"
#include "core/report.h"
#include "tuning/tuner_network.h"

namespace spec2fab {

class Coupling {
 public:
  virtual ~Coupling() = default;
  virtual std::string name() const = 0;
  /// Whether tuners coupled this way may run in parallel (in colour classes).
  virtual bool allows_parallel() const { return true; }
  /// Called before each sweep over `tuners`.
  virtual void begin_sweep(TunerNetwork& /*network*/, const std::vector<size_t>& /*tuners*/) {}
  /// Called after tuner `t` was tuned in a sweep; `tuned` marks the tuners
  /// already tuned in this sweep (t included).
  virtual void after_tune(TunerNetwork& /*network*/, size_t /*t*/,
                          const std::vector<bool>& /*tuned*/) {}
  /// Called once after the phase's last sweep.
  virtual void end_phase(TunerNetwork& /*network*/, const std::vector<size_t>& /*tuners*/) {}
  /// What the coupling keeps of a finished phase for the run's report (a
  /// checkpoint saves it; restore() takes it up in a resumed run).
  virtual nlohmann::json saved_state() const { return nullptr; }
  virtual void restore(const nlohmann::json& /*state*/) {}
};

/// Where a schedule keeps its state after each phase: every tuner's state,
/// the couplings' and the record so far. A run killed in a later phase goes
/// on from the last phase saved in a new process (spec2fab run --resume), to
/// the results an uninterrupted run gives, bit for bit.
class PhaseCheckpoint {
 public:
  virtual ~PhaseCheckpoint() = default;
  /// What an earlier process saved last, or nothing (start from the first phase).
  virtual std::vector<std::uint8_t> load() = 0;
  /// Replaces what was saved, all or nothing.
  virtual void save(const std::vector<std::uint8_t>& state) = 0;
};

struct Phase;

/// What a coupling named in JSON ("coupling": "name" in a schedule phase)
/// may rely on: the network's shape, the phase's mode and tuners, the phases
/// before it, the run's materials.
struct CouplingContext {
  const NetworkShape& network;
  bool parallel = false;
  TunerNetwork* tuners = nullptr;              ///< every tuner, bound to its node
  std::vector<size_t> members;                 ///< the phase's tuners
  const std::vector<Phase>* earlier = nullptr;  ///< the phases before this one
  const MaterialPalette* palette = nullptr;
};

/// Couplings that an experiment may name, registered like every other part.
/// The factory gets the phase's properties (a coupling's own options sit
/// beside "coupling" in the phase) and refuses a network, mode or tuners it
/// cannot work with. Couplings built on a translator's functions
/// (NeighbourSwaps, whose energy the translator defines) are made in C++ and
/// not listed.
using CouplingRegistry = Registry<Coupling, const CouplingContext&>;

/// Error diffusion over a grid network (tuners row-major, `grid_width` per
/// row), as in Floyd–Steinberg halftoning: after a tuner is tuned, its
/// residual (effective target − simulated) is added to the effective targets
/// of the network neighbours not yet tuned in this sweep, with weights 7/16
/// (right), 3/16 (down-left), 5/16 (down), 1/16 (down-right) renormalised
/// over the neighbours present — on a 4-neighbour network that is 7/12 right
/// and 5/12 down. Serial phases only: the result depends on the order.
///
/// With `clamp`, diffused targets are clamped to [first, second]: a goal
/// outside what the simulator can reach (a colour out of the printer's
/// gamut) otherwise accumulates residuals without bound and smears them
/// across the grid.

class ErrorDiffusion final : public Coupling {
 public:
  explicit ErrorDiffusion(int grid_width,
                          std::optional<std::pair<double, double>> clamp = std::nullopt)
      : grid_width_(grid_width), clamp_(clamp) {}
  /// From a phase: needs a grid network and a serial phase.
  ErrorDiffusion(const Properties& phase, const CouplingContext& context);
  static TypeDoc doc();
  std::string name() const override { return "error_diffusion"; }
  bool allows_parallel() const override { return false; }
  void begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) override;
  void after_tune(TunerNetwork& network, size_t t, const std::vector<bool>& tuned) override;

 private:
  int grid_width_;
  std::optional<std::pair<double, double>> clamp_;
};

/// Lets each tuner of a phase exchange its state (effective target and
/// parameter values, Tuner::exchange_state) with its network neighbours in
/// the phase: their problems gain Capability::neighbour_moves for the phase,
/// and an optimizer that uses them (annealing) accepts an exchange on
/// `delta(network, a, b)`, the change of an energy the translator defines —
/// for facet caustics, the roughness of the surface. Serial only: an
/// exchange changes a neighbour, which a parallel colour class may be
/// running. `energy`, when given, is recorded before every sweep and after
/// the last (energies()).
class NeighbourSwaps final : public Coupling {
 public:
  using Delta = std::function<double(TunerNetwork& network, size_t a, size_t b)>;
  using Energy = std::function<double(TunerNetwork& network)>;
  explicit NeighbourSwaps(Delta delta, Energy energy = {})
      : delta_(std::move(delta)), energy_(std::move(energy)) {}
  std::string name() const override { return "neighbour_swaps"; }
  bool allows_parallel() const override { return false; }
  void begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) override;
  void end_phase(TunerNetwork& network, const std::vector<size_t>& tuners) override;
  const std::vector<double>& energies() const { return energies_; }
  nlohmann::json saved_state() const override { return energies_; }
  void restore(const nlohmann::json& state) override { energies_ = state.get<std::vector<double>>(); }

 private:
  Delta delta_;
  Energy energy_;
  std::vector<double> energies_;
  bool installed_ = false;
};

struct Phase {
  enum class Mode { serial, parallel };
  std::string name = "phase";
  std::vector<size_t> tuners;  ///< in order; empty: every tuner in index order
  int sweeps = 1;
  Mode mode = Mode::serial;
  std::shared_ptr<Coupling> coupling;  ///< none when null
  bool fix_after = false;              ///< fix the parameters this phase tuned
  /// Keep every sweep's tuner runs in the RunRecord; false keeps only the
  /// last sweep's (a phase of thousands of short sweeps — annealing swaps —
  /// would otherwise hold millions of summaries). Evaluations are counted either way.
  bool record_every_sweep = true;
  /// When not null, every tuner of the phase tunes with its own copy of this
  /// optimizer (built once per phase, kept over its sweeps) instead of its
  /// own — annealing swaps first, a local solver after, say.
  nlohmann::json optimizer;

  /// The tuners the phase runs, in order, in a network of `network_size`.
  std::vector<size_t> members(size_t network_size) const;
};

/// One tuner run of a schedule.
struct TunerRun {
  size_t phase = 0;
  int sweep = 0;
  size_t tuner = 0;
  Summary summary;
};

/// One phase's totals in result.json "tuning".
struct PhaseTotals {
  std::string name;
  long long tuner_runs = 0, evaluations = 0;
  double sum_initial_error = 0, sum_final_error = 0;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.name, "name", "the phase");
    f(s.tuner_runs, "tuner_runs", "tuner runs made, recorded or not");
    f(s.evaluations, "evaluations", "error evaluations spent");
    f(s.sum_initial_error, "sum_initial_error", "its recorded runs' errors at their start, summed");
    f(s.sum_final_error, "sum_final_error", "and at their end");
  }
};

/// A tuner's error against its own goal after the whole schedule.
struct TunerFinalError {
  std::string name;
  double final_error = 0;
  std::optional<std::vector<TermValue>> terms;  ///< a tuner of several terms: each one
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.name, "name", "the tuner");
    f(s.final_error, "final_error",
      "its error against its goal (not a diffused target) at the end; with several terms, their weighted sum and "
      "penalties");
    f(s.terms, "terms", "a tuner that weighs several terms: each term's value at the end");
  }
};

/// result.json "tuning" (core/report.h), without wall times.
struct TuningReport {
  std::vector<PhaseTotals> phases;
  /// Per recorded run: the optimizer's summary (its fields are the
  /// optimizer's: Summary::to_json) with phase, sweep and tuner.
  std::vector<nlohmann::json> tuner_runs;
  std::optional<std::vector<TunerFinalError>> tuners;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.phases, "phases", "per phase of the schedule");
    f(s.tuner_runs, "tuner_runs", "per recorded tuner run: the optimizer's summary, phase, sweep and tuner");
    f(s.tuners, "tuners", "each tuner's final error (the tree translator)");
  }
};

struct RunRecord {
  std::vector<std::string> phase_names;
  std::vector<TunerRun> runs;         ///< in schedule order (deterministic)
  std::vector<double> phase_seconds;  ///< wall time per phase (not deterministic)
  /// Per phase: tuner runs made and evaluations spent, recorded or not.
  std::vector<long long> phase_tuner_runs, phase_evaluations;
  /// Of those, the runs this process made: under mpirun a parallel phase's
  /// colour classes are split over the ranks (each tunes its share, then
  /// takes up the others' results), so this is the rank's share. Phases a
  /// resumed run took from its checkpoint count none.
  long long tuner_runs_here = 0;

  /// Per-run summaries and per-phase totals, without wall times.
  TuningReport report(TunerNetwork& network) const;
  /// "phase,sweep,tuner,iteration,evaluations,error,best_error" rows.
  std::string convergence_csv(TunerNetwork& network) const;
};

class Schedule {
 public:
  Schedule& add(Phase phase);
  const std::vector<Phase>& phases() const { return phases_; }
  /// Runs every phase; throws std::invalid_argument for a parallel phase with
  /// a coupling that forbids it or tuners whose subtrees overlap, or a tuner
  /// index out of range. With a checkpoint, saves the state after each phase
  /// and starts after the last phase an earlier process saved (InputError
  /// when that state is not of this schedule and network).
  RunRecord run(TunerNetwork& network, std::uint64_t seed, const Limits& limits,
                PhaseCheckpoint* checkpoint = nullptr) const;
  /// What run() checks before it starts (run() checks it again): InputError
  /// when the phases from `first_phase` on ask for more tuner runs, or plan
  /// more error evaluations (Optimizer::planned_evaluations), than the
  /// limits tuner_runs and evaluations allow. While it runs, run() projects
  /// each phase's time from the pace of its finished tuner runs and stops,
  /// with InputError, when the tuning would take longer than tuning_hours.
  /// What check_plan counted, for `spec2fab validate`: "N tuner runs in P
  /// phase(s), M error evaluations planned".
  std::string check_plan(TunerNetwork& network, const Limits& limits, size_t first_phase = 0) const;

 private:
  std::vector<Phase> phases_;
};

/// Two of `tuners` whose subtrees overlap — the same node, or one's node
/// inside the other's subtree — or nullopt. Tuners that run in parallel
/// must not overlap: both would set the same parameters at once.
std::optional<std::pair<size_t, size_t>> overlapping_tuners(TunerNetwork& network, const std::vector<size_t>& tuners);
/// Within one of `classes` (the tuners a parallel phase runs together), a
/// tuner whose simulator reads the tree beyond its node and another tuner
/// beside it, or nullopt: the first would see the second's trial values,
/// so its result would depend on timing (and differ between threads and
/// ranks).
std::optional<std::pair<size_t, size_t>> tuner_reading_a_neighbour(TunerNetwork& network,
                                                                   const std::vector<std::vector<size_t>>& classes);
/// The sentence that refuses such a pair.
std::string reading_a_neighbour_problem(TunerNetwork& network, std::pair<size_t, size_t> pair);
/// The sentence that refuses the first of `tuners` (a parallel phase's)
/// whose simulator spreads its solves over the MPI ranks, or nullopt: a
/// parallel phase gives each tuner to one rank, and the others would never
/// join its solves.
std::optional<std::string> spreading_tuner_problem(TunerNetwork& network, const std::vector<size_t>& tuners);

/// The seed of one tuner run (SplitMix64 of the inputs).
std::uint64_t tuner_seed(std::uint64_t run_seed, size_t phase, int sweep, size_t tuner);

}  // namespace spec2fab

#include "tuning/schedule.h"

#include <algorithm>
#include <limits>
#include <chrono>
#include <cstring>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <tbb/parallel_for.h>

#include "core/error.h"
#include "core/limits.h"
#include "core/log.h"
#include "core/ranks.h"
#include "core/seed.h"
#include "core/properties.h"
#include "tuning/schedule_state_impl.h"

namespace spec2fab {

// The resource limits this part enforces (core/limits.h).
SPEC2FAB_LIMIT("tuner_runs", 1e8, "tuner runs a schedule asks for (sweeps times tuners, summed over its phases)");
SPEC2FAB_LIMIT("evaluations", 1e12, "error evaluations a schedule plans (each tuner run's optimizer's, summed over its phases)");
SPEC2FAB_LIMIT("tuning_hours", 72, "hours of tuning a schedule may take, projected from the pace of each phase's first runs");

std::uint64_t tuner_seed(std::uint64_t run_seed, size_t phase, int sweep, size_t tuner) {
  return mix_seed(mix_seed(mix_seed(mix_seed(run_seed) ^ phase) ^ static_cast<std::uint64_t>(sweep)) ^ tuner);
}

ErrorDiffusion::ErrorDiffusion(const Properties& phase, const CouplingContext& context)
    : grid_width_(context.network.grid_width()) {
  if (grid_width_ == 0) phase.fail("coupling", "error_diffusion needs a grid4 or grid8 network");
  if (context.parallel) phase.fail("mode", "error_diffusion depends on the order: its phase must be serial");
}

TypeDoc ErrorDiffusion::doc() {
  return {"Error diffusion over a grid network (Floyd-Steinberg weights): after a tuner is tuned, "
          "its residual (target - simulated) goes to the neighbours not yet tuned in the sweep. "
          "Serial phases on grid4 or grid8 networks only.",
          {},
          R"({"coupling": "error_diffusion", "mode": "serial"})"};
}

std::optional<std::pair<size_t, size_t>> overlapping_tuners(TunerNetwork& network, const std::vector<size_t>& tuners) {
  std::unordered_map<const ReducerNode*, size_t> tuner_at;
  for (size_t t : tuners) {
    if (!network.tuner(t).is_bound()) continue;
    const auto [at, fresh] = tuner_at.emplace(&network.tuner(t).node(), t);
    if (!fresh) return std::pair{at->second, t};
  }
  for (size_t t : tuners) {
    if (!network.tuner(t).is_bound()) continue;
    std::vector<const ReducerNode*> pending;  // the subtree below t's node
    const ReducerNode& node = network.tuner(t).node();
    for (size_t c = 0; c < node.child_count(); ++c) pending.push_back(&node.child(c));
    while (!pending.empty()) {
      const ReducerNode* below = pending.back();
      pending.pop_back();
      if (const auto found = tuner_at.find(below); found != tuner_at.end()) return std::pair{t, found->second};
      for (size_t c = 0; c < below->child_count(); ++c) pending.push_back(&below->child(c));
    }
  }
  return std::nullopt;
}

std::optional<std::pair<size_t, size_t>> tuner_reading_a_neighbour(TunerNetwork& network,
                                                                   const std::vector<std::vector<size_t>>& classes) {
  for (const std::vector<size_t>& together : classes) {
    if (together.size() < 2) continue;
    for (size_t t : together) {
      if (!network.tuner(t).reads_beyond_its_node()) continue;
      for (size_t other : together)
        if (other != t) return std::pair{t, other};
    }
  }
  return std::nullopt;
}

std::optional<std::string> spreading_tuner_problem(TunerNetwork& network, const std::vector<size_t>& tuners) {
  for (size_t t : tuners) {
    if (const auto simulator = network.tuner(t).simulator_spreading_over_ranks())
      return "tuner '" + network.tuner(t).name() + "' cannot run in a parallel phase: its " + *simulator +
             " simulator spreads each solve over the MPI ranks (spread_over_ranks), so every rank must run it, "
             "and a parallel phase gives each tuner to one rank; make the phase serial";
  }
  return std::nullopt;
}

std::string reading_a_neighbour_problem(TunerNetwork& network, std::pair<size_t, size_t> pair) {
  const Tuner& reader = network.tuner(pair.first);
  return "tuners '" + reader.name() + "' and '" + network.tuner(pair.second).name() +
         "' cannot run in parallel: the " + reader.simulator_reading_beyond_its_node().value_or("?") +
         " simulator of '" + reader.name() +
         "' reads the whole tree, so it would see the trial values of '" + network.tuner(pair.second).name() +
         "' as they change and its result would depend on timing; make the phase serial";
}

void ErrorDiffusion::begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) {
  for (size_t t : tuners) network.tuner(t).reset_target();
}

void ErrorDiffusion::after_tune(TunerNetwork& network, size_t t, const std::vector<bool>& tuned) {
  struct Offset {
    long dx, dy;
    double weight;
  };
  static constexpr Offset kFloydSteinberg[] = {{1, 0, 7}, {-1, 1, 3}, {0, 1, 5}, {1, 1, 1}};
  const long width = grid_width_;
  const long x = static_cast<long>(t) % width, y = static_cast<long>(t) / width;
  std::vector<std::pair<size_t, double>> targets;
  double total = 0;
  for (const Offset& o : kFloydSteinberg) {
    const long nx = x + o.dx, ny = y + o.dy;
    if (nx < 0 || nx >= width) continue;
    const size_t n = static_cast<size_t>(ny * width + nx);
    if (n >= network.size() || tuned[n] || !network.connected(t, n)) continue;
    targets.emplace_back(n, o.weight);
    total += o.weight;
  }
  if (targets.empty()) return;
  Tuner& self = network.tuner(t);
  const auto target = self.effective_target().values();
  const auto simulated = self.simulated().values();
  for (const auto& [n, weight] : targets) {
    auto neighbour_target = network.tuner(n).effective_target().values();
    for (size_t k = 0; k < neighbour_target.size() && k < target.size(); ++k) {
      neighbour_target[k] += weight / total * (target[k] - simulated[k]);
      if (clamp_) neighbour_target[k] = std::clamp(neighbour_target[k], clamp_->first, clamp_->second);
    }
  }
}

void NeighbourSwaps::begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) {
  if (energy_) energies_.push_back(energy_(network));
  if (installed_) return;  // the moves stay for the whole phase
  installed_ = true;
  std::vector<bool> in_phase(network.size(), false);
  for (size_t t : tuners) in_phase[t] = true;
  for (size_t t : tuners) {
    Tuner::NeighbourMoves moves;
    std::vector<size_t> others;
    for (size_t n : network.neighbours(t)) {
      if (!in_phase[n]) continue;
      moves.neighbours.push_back(&network.tuner(n));
      others.push_back(n);
    }
    moves.delta = [this, &network, t, others](size_t k) { return delta_(network, t, others[k]); };
    network.tuner(t).set_neighbour_moves(std::move(moves));
  }
}

void NeighbourSwaps::end_phase(TunerNetwork& network, const std::vector<size_t>& tuners) {
  if (energy_) energies_.push_back(energy_(network));
  for (size_t t : tuners) network.tuner(t).set_neighbour_moves(std::nullopt);
  installed_ = false;
}

Schedule& Schedule::add(Phase phase) {
  phases_.push_back(std::move(phase));
  return *this;
}

namespace {

// What the phases from `first` on ask for, counted before they start: tuner
// runs (sweeps × tuners) and error evaluations (each run's optimizer plan;
// runs whose optimizer cannot say are left out of that count and named).
std::string check_schedule_plan(const std::vector<Phase>& phases, size_t first, TunerNetwork& network,
                                const Limits& limits) {
  double runs = 0, evaluations = 0, unplanned_runs = 0;
  for (size_t p = first; p < phases.size(); ++p) {
    const Phase& phase = phases[p];
    const std::vector<size_t> members = phase.members(network.size());
    runs += static_cast<double>(phase.sweeps) * static_cast<double>(members.size());
    std::unique_ptr<Optimizer> phase_optimizer;
    if (!phase.optimizer.is_null())
      phase_optimizer = build_optimizer(Properties::wrap(phase.optimizer, "schedule phase '" + phase.name + "' optimizer"));
    for (size_t t : members) {
      if (t >= network.size()) continue;  // refused, naming the tuner, when the phase starts
      Tuner& tuner = network.tuner(t);
      const Optimizer& optimizer = phase_optimizer ? *phase_optimizer : tuner.optimizer();
      if (const std::optional<double> planned = optimizer.planned_evaluations(tuner.problem()))
        evaluations += static_cast<double>(phase.sweeps) * *planned;
      else
        unplanned_runs += phase.sweeps;
    }
  }
  if (const double max_runs = limits.get("tuner_runs"); runs > max_runs)
    throw InputError(fmt::format("schedule: its phases ask for {:.3g} tuner runs (sweeps times tuners), more than the "
                                 "{:.3g} allowed {}",
                                 runs, max_runs, limits.how_to_change("tuner_runs")));
  if (const double max_evaluations = limits.get("evaluations"); evaluations > max_evaluations)
    throw InputError(fmt::format("schedule: its phases plan {:.3g} error evaluations (each tuner run's optimizer "
                                 "evaluations, summed){}, more than the {:.3g} allowed {}",
                                 evaluations,
                                 unplanned_runs > 0 ? fmt::format(" besides {:.3g} runs of optimizers that cannot say "
                                                                  "how many they make", unplanned_runs)
                                                    : std::string(),
                                 max_evaluations, limits.how_to_change("evaluations")));
  const std::string counted = fmt::format("{:.0f} tuner run(s) in {} phase(s), ", runs, phases.size() - first);
  if (unplanned_runs == 0) return counted + fmt::format("{:.3g} error evaluations planned", evaluations);
  if (evaluations == 0) return counted + "by optimizers that cannot say how many evaluations they make";
  return counted + fmt::format("{:.3g} error evaluations planned for all but {:.0f} (by optimizers that cannot say)",
                               evaluations, unplanned_runs);
}

// The time a phase would take at the pace of its tuner runs so far, added to
// the run's time before it, against the tuning_hours limit. Checked as runs
// finish, so that a schedule far beyond the limit stops after its first runs
// rather than after days. Under mpirun the ranks' clocks differ and a refusal
// on one would leave the others waiting: only runs of one process are checked.
void check_phase_pace(const Phase& phase, long long done, long long total, double phase_seconds, double seconds_before,
                      const Limits& limits) {
  if (done <= 0 || done >= total || ranks::size() > 1) return;
  const double projected = seconds_before + phase_seconds / static_cast<double>(done) * static_cast<double>(total);
  const double max_hours = limits.get("tuning_hours");
  if (projected <= max_hours * 3600) return;
  throw InputError(fmt::format("schedule: phase '{}' took {:.3g} s for its first {} of {} tuner runs; at that pace "
                               "the run's tuning would take about {:.3g} h, more than the {:.3g} h allowed {}",
                               phase.name, phase_seconds, done, total, projected / 3600, max_hours,
                               limits.how_to_change("tuning_hours")));
}

std::string progress_detail(int sweep, double error_sum, size_t runs) {
  return fmt::format("sweep {}, mean error {:.4g}", sweep + 1,
                     error_sum / static_cast<double>(std::max<size_t>(runs, 1)));
}

}  // namespace

std::vector<size_t> Phase::members(size_t network_size) const {
  if (!tuners.empty()) return tuners;
  std::vector<size_t> all(network_size);
  std::iota(all.begin(), all.end(), size_t{0});
  return all;
}

std::string Schedule::check_plan(TunerNetwork& network, const Limits& limits, size_t first_phase) const {
  return check_schedule_plan(phases_, first_phase, network, limits);
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Refuses a phase that cannot run as declared — a tuner the network lacks;
/// in a parallel phase, a coupling that must run serially, tuners whose
/// subtrees overlap, or one reading the tree beyond its node beside another
/// of its colour class — and returns its colour classes (none when serial).
std::vector<std::vector<size_t>> runnable_classes(const Phase& phase, const std::vector<size_t>& tuners,
                                                  TunerNetwork& network) {
  for (size_t t : tuners) {
    if (t >= network.size()) throw std::invalid_argument("schedule: no tuner " + std::to_string(t));
  }
  if (phase.mode != Phase::Mode::parallel) return {};
  if (phase.coupling && !phase.coupling->allows_parallel()) {
    throw std::invalid_argument("schedule: phase '" + phase.name + "' couples tuners by " + phase.coupling->name() +
                                ", which must run serially");
  }
  if (const auto overlap = overlapping_tuners(network, tuners)) {
    throw std::invalid_argument("schedule: phase '" + phase.name + "' runs tuners '" +
                                network.tuner(overlap->first).name() + "' and '" +
                                network.tuner(overlap->second).name() + "' in parallel, but their subtrees overlap");
  }
  if (const auto spreading = spreading_tuner_problem(network, tuners))
    throw std::invalid_argument("schedule: phase '" + phase.name + "': " + *spreading);
  auto classes = network.colour_classes(tuners);
  if (const auto reading = tuner_reading_a_neighbour(network, classes))
    throw std::invalid_argument("schedule: phase '" + phase.name + "': " + reading_a_neighbour_problem(network, *reading));
  return classes;
}

/// One phase as it runs: its sweeps over its tuners (serially, or colour
/// class by colour class in parallel, shared over MPI ranks), the coupling
/// between them, progress and pace, and what it adds to the record.
class PhaseRun {
 public:
  PhaseRun(const Phase& phase, size_t index, TunerNetwork& network, std::uint64_t seed, RunRecord& record,
           double seconds_before, const Limits& limits)
      : phase_(phase),
        index_(index),
        network_(network),
        seed_(seed),
        record_(record),
        tuners_(phase.members(network.size())),
        classes_(runnable_classes(phase, tuners_, network)),
        runs_(static_cast<long long>(tuners_.size()) * phase.sweeps),
        progress_(phase.name, runs_),
        seconds_before_(seconds_before),
        limits_(limits) {
    record_.phase_names.push_back(phase.name);
    // A phase's own optimizer (built once per phase, kept over its sweeps).
    if (!phase.optimizer.is_null()) {
      const Properties properties = Properties::wrap(phase.optimizer, "schedule phase '" + phase.name + "' optimizer");
      for (size_t t : tuners_) own_.push_back(network.tuner(t).exchange_optimizer(build_optimizer(properties)));
    }
  }

  void sweep(int sweep) {
    if (phase_.coupling) phase_.coupling->begin_sweep(network_, tuners_);
    tuned_.assign(network_.size(), false);
    summaries_.assign(network_.size(), Summary());
    sweep_error_ = 0;
    swept_ = 0;
    if (phase_.mode == Phase::Mode::parallel) {
      for (const auto& colour : classes_) tune_class(colour, sweep);
    } else {
      for (size_t t : tuners_) {
        tune(t, sweep);
        ++record_.tuner_runs_here;
        after_runs({t}, sweep);
      }
    }
    for (size_t t : tuners_) evaluations_ += summaries_[t].evaluations;
    if (phase_.record_every_sweep || sweep + 1 == phase_.sweeps)
      for (size_t t : tuners_) record_.runs.push_back({index_, sweep, t, std::move(summaries_[t])});
  }

  void finish() {
    if (phase_.coupling) phase_.coupling->end_phase(network_, tuners_);
    for (size_t k = 0; k < own_.size(); ++k) network_.tuner(tuners_[k]).exchange_optimizer(std::move(own_[k]));
    progress_.finish();
    record_.phase_tuner_runs.push_back(done_);
    record_.phase_evaluations.push_back(evaluations_);
    if (phase_.fix_after) {
      for (size_t t : tuners_) {
        for (const auto& e : network_.tuner(t).search_space().entries()) e.parameter->set_free(false);
      }
    }
    record_.phase_seconds.push_back(seconds_since(start_));
  }

 private:
  void tune(size_t t, int sweep) {
    Tuner& tuner = network_.tuner(t);
    tuner.optimizer().set_seed(tuner_seed(seed_, index_, sweep, t));
    summaries_[t] = tuner.tune();
  }

  // Under mpirun each rank tunes its share of the class, then takes up the others'.
  void tune_class(const std::vector<size_t>& colour, int sweep) {
    const auto [begin, end] = ranks::share(static_cast<long long>(colour.size()), ranks::rank(), ranks::size());
    tbb::parallel_for(static_cast<size_t>(begin), static_cast<size_t>(end), [&](size_t i) { tune(colour[i], sweep); });
    record_.tuner_runs_here += end - begin;
    if (ranks::size() > 1)
      schedule_state::share_colour_tunings(network_, colour, static_cast<size_t>(begin), static_cast<size_t>(end),
                                           summaries_);
    after_runs(colour, sweep);
  }

  // The coupling after each run, in order; progress and pace.
  void after_runs(const std::vector<size_t>& tuned, int sweep) {
    for (size_t t : tuned) {
      tuned_[t] = true;
      if (phase_.coupling) phase_.coupling->after_tune(network_, t, tuned_);
    }
    done_ += static_cast<long long>(tuned.size());
    for (size_t t : tuned) sweep_error_ += summaries_[t].final_error;
    swept_ += tuned.size();
    progress_.update(done_, progress_detail(sweep, sweep_error_, swept_));
    check_phase_pace(phase_, done_, runs_, seconds_since(start_), seconds_before_, limits_);
  }

  const Phase& phase_;
  const size_t index_;
  TunerNetwork& network_;
  const std::uint64_t seed_;
  RunRecord& record_;
  const std::vector<size_t> tuners_;
  const std::vector<std::vector<size_t>> classes_;
  const long long runs_;
  Progress progress_;
  const double seconds_before_;
  const Limits& limits_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<Optimizer>> own_;  ///< the tuners' optimizers while the phase's own tune
  long long done_ = 0, evaluations_ = 0;
  // This sweep's.
  std::vector<bool> tuned_;
  std::vector<Summary> summaries_;
  double sweep_error_ = 0;  ///< sum of the final errors of this sweep's runs so far
  size_t swept_ = 0;
};

}  // namespace

RunRecord Schedule::run(TunerNetwork& network, std::uint64_t seed, const Limits& limits,
                        PhaseCheckpoint* checkpoint) const {
  RunRecord record;
  size_t first = 0;
  if (checkpoint) {
    if (const std::vector<std::uint8_t> saved = checkpoint->load(); !saved.empty()) {
      first = schedule_state::restore_checkpoint(saved, phases_, record, network);
      if (first > 0)
        spdlog::info("resuming after phase '{}' ({} of {}), which the killed run had finished", phases_[first - 1].name,
                     first, phases_.size());
    }
  }
  check_plan(network, limits, first);  // the loops below, bounded before they start
  const auto schedule_start = std::chrono::steady_clock::now();
  for (size_t p = first; p < phases_.size(); ++p) {
    PhaseRun phase(phases_[p], p, network, seed, record, seconds_since(schedule_start), limits);
    for (int sweep = 0; sweep < phases_[p].sweeps; ++sweep) phase.sweep(sweep);
    phase.finish();
    if (checkpoint) checkpoint->save(schedule_state::checkpoint_state(phases_, p + 1, record, network));
  }
  return record;
}

TuningReport RunRecord::report(TunerNetwork& network) const {
  TuningReport report;
  for (size_t p = 0; p < phase_names.size(); ++p) {
    PhaseTotals totals{phase_names[p], 0, 0, 0, 0};
    for (const TunerRun& run : runs) {
      if (run.phase != p) continue;
      totals.sum_initial_error += run.summary.initial_error;
      totals.sum_final_error += run.summary.final_error;
      totals.evaluations += run.summary.evaluations;
      ++totals.tuner_runs;
    }
    // Phases that keep only their last sweep count every run and evaluation.
    if (p < phase_tuner_runs.size()) {
      totals.tuner_runs = phase_tuner_runs[p];
      totals.evaluations = phase_evaluations[p];
    }
    report.phases.push_back(std::move(totals));
  }
  for (const TunerRun& run : runs) {
    nlohmann::json entry = run.summary.to_json();
    entry["phase"] = phase_names[run.phase];
    entry["sweep"] = run.sweep;
    entry["tuner"] = network.tuner(run.tuner).name();
    report.tuner_runs.push_back(std::move(entry));
  }
  return report;
}

std::string RunRecord::convergence_csv(TunerNetwork& network) const {
  std::ostringstream out;
  out.precision(10);
  out << "phase,sweep,tuner,iteration,evaluations,error,best_error\n";
  for (const TunerRun& run : runs) {
    const std::string prefix = phase_names[run.phase] + "," + std::to_string(run.sweep) + "," +
                               network.tuner(run.tuner).name() + ",";
    if (run.summary.trace.empty()) {
      out << prefix << run.summary.iterations << "," << run.summary.evaluations << ","
          << run.summary.final_error << "," << run.summary.final_error << "\n";
    }
    for (const IterationRecord& r : run.summary.trace) {
      out << prefix << r.iteration << "," << r.evaluations << "," << r.error << "," << r.best_error
          << "\n";
    }
  }
  return out.str();
}

}  // namespace spec2fab

namespace spec2fab {
namespace {

class NoCoupling final : public Coupling {
 public:
  NoCoupling(const Properties& /*phase*/, const CouplingContext& /*context*/) {}
  std::string name() const override { return "none"; }
  static TypeDoc doc() { return {"Tuners of the phase do not interact (the default).", {}, R"({"coupling": "none"})"}; }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::CouplingRegistry, spec2fab::NoCoupling, "none")
SPEC2FAB_REGISTER(spec2fab::CouplingRegistry, spec2fab::ErrorDiffusion, "error_diffusion")
SPEC2FAB_LIST_REGISTRY(spec2fab::CouplingRegistry, 70, "coupling", "couplings")

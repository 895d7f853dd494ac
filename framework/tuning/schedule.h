#pragma once
/// A schedule (paper §6.4): phases, each naming which tuners run, how many
/// sweeps, and whether serially (in the listed order) or in parallel. A
/// parallel phase colours the network so that no two neighbours run at once,
/// and every tuner run draws its random seed from (run seed, phase, sweep,
/// tuner): results are identical for any thread count.
///
/// A Coupling says how tuners of a phase interact with their neighbours
/// around their own tuning (error diffusion, for example); a phase may fix
/// what it tuned so that a later phase tunes something else on top.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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
};

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
  std::string name() const override { return "error_diffusion"; }
  bool allows_parallel() const override { return false; }
  void begin_sweep(TunerNetwork& network, const std::vector<size_t>& tuners) override;
  void after_tune(TunerNetwork& network, size_t t, const std::vector<bool>& tuned) override;

 private:
  int grid_width_;
  std::optional<std::pair<double, double>> clamp_;
};

struct Phase {
  enum class Mode { serial, parallel };
  std::string name = "phase";
  std::vector<size_t> tuners;  ///< in order; empty: every tuner in index order
  int sweeps = 1;
  Mode mode = Mode::serial;
  std::shared_ptr<Coupling> coupling;  ///< none when null
  bool fix_after = false;              ///< fix the parameters this phase tuned
};

/// One tuner run of a schedule.
struct TunerRun {
  size_t phase = 0;
  int sweep = 0;
  size_t tuner = 0;
  Summary summary;
};

struct RunRecord {
  std::vector<std::string> phase_names;
  std::vector<TunerRun> runs;         ///< in schedule order (deterministic)
  std::vector<double> phase_seconds;  ///< wall time per phase (not deterministic)

  /// Per-run summaries and per-phase totals, without wall times.
  nlohmann::json to_json(TunerNetwork& network) const;
  /// "phase,sweep,tuner,iteration,evaluations,error,best_error" rows.
  std::string convergence_csv(TunerNetwork& network) const;
};

class Schedule {
 public:
  Schedule& add(Phase phase);
  const std::vector<Phase>& phases() const { return phases_; }
  /// Runs every phase; throws std::invalid_argument for a parallel phase with
  /// a coupling that forbids it or a tuner index out of range.
  RunRecord run(TunerNetwork& network, std::uint64_t seed) const;

 private:
  std::vector<Phase> phases_;
};

/// The seed of one tuner run (SplitMix64 of the inputs).
std::uint64_t tuner_seed(std::uint64_t run_seed, size_t phase, int sweep, size_t tuner);

}  // namespace spec2fab

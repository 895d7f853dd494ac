#pragma once
/// The three typed parts of a tuner besides its optimizer (paper §6.2):
/// a Simulator produces an observation of a reducer subtree, a Goal holds the
/// target observation, an ErrorMetric compares the two.
///
/// Write parts against a concrete observation type by deriving from
/// SimulatorFor<O>, MetricFor<O>, GoalFor<O>; `make_tuner` (tuner.h) then
/// refuses to compile when the types differ, and the JSON path checks the
/// same at load time. Parts register by name like every other type:
/// `SPEC2FAB_REGISTER(SimulatorRegistry, MySimulator, "my_simulator")`, with
/// a constructor from (const Properties&, const PartContext&).

#include <array>
#include <concepts>
#include <filesystem>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/report.h"

#include "core/limits.h"
#include "core/registry.h"
#include "core/run_cache.h"
#include "core/search_space.h"
#include "materials/palette.h"
#include "reducer/node.h"
#include "tuning/observation.h"
#include "tuning/simulation_domain.h"

namespace spec2fab {

struct PrinterProfile;

/// Values over a grid of cells covering a simulator's footprint, row by row
/// from the lowest (a, b): what one part of a print hands the simulator of
/// another (the transmittance of a texture over a caustic slab's exit face).
struct GridField {
  std::array<int, 2> cells{0, 0};
  std::vector<double> values;  ///< cells[0] · cells[1]
};

/// One input a simulator takes from outside its subtree (Simulator::inputs).
struct SimulatorInput {
  std::string name;
  std::string meaning;
};

/// What Simulator::write_report wrote.
struct SimulatorFiles {
  std::vector<std::string> files;
  /// Where the values are better read than from simulation.json's list of
  /// them ("displacements.csv (nodes) and probes"); empty: listed there.
  std::string values_in;
};

class Simulator {
 public:
  virtual ~Simulator() = default;
  virtual std::string name() const = 0;
  virtual std::string_view produces() const = 0;
  virtual std::unique_ptr<Observation> make_observation() const = 0;
  /// One-time work for a subtree (meshes, factorisations, lookup tables).
  /// `domain` places the subtree in the run's solid and whole tree; it is
  /// empty where there is none (a column simulated on its own), and
  /// simulators that need it call domain.require_solid().
  virtual void setup(const ReducerNode& /*subtree*/, const SimulationDomain& /*domain*/) {}
  /// Simulates the subtree at its current parameters into `out` (made by
  /// make_observation); called thousands of times, so it must not allocate.
  virtual void simulate(const ReducerNode& subtree, Observation& out) = 0;
  /// Why the last simulate() left non-finite values (an optimizer takes them
  /// as the worst error; the simulate command names the reason), or nothing.
  virtual std::string failure() const { return {}; }

  /// After simulate(subtree, out): writes what a person would look at into
  /// `folder` and returns the files written; by default the observation in
  /// its own form (Observation::write_files). A simulator with better outputs
  /// (meshes, pictures, tables) overrides it, adds its figures to `record`
  /// (simulation.json) as typed sections (core/report.h) and, where its
  /// values are better read from its files, says where.
  virtual SimulatorFiles write_report(const Observation& out, const std::filesystem::path& folder,
                                      ReportSections& /*record*/) const {
    return {out.write_files(folder), {}};
  }

  /// After setup: about how many bytes write_report will write, so that
  /// `spec2fab simulate` refuses before simulating when the disk has less
  /// free (require_free_space: exit 2 with the figures). 0: no estimate, for
  /// simulators whose files are small (a refused write is still exit 3).
  virtual long long estimated_report_bytes() const { return 0; }

  /// Whether simulate() reads the tree beyond `subtree`: a volumetric
  /// simulator asks the whole tree which material is where, so it sees
  /// whatever the other tuners hold at that moment. Such a tuner may not
  /// share a parallel phase's colour class with another (its result would
  /// depend on their timing, and differ between threads and ranks): the
  /// schedule refuses it.
  virtual bool reads_beyond_subtree() const { return false; }
  /// Whether its solves are spread over the MPI ranks of a run, so that
  /// every rank must make the same calls: a tuner using it may not run in a
  /// parallel phase (which gives each tuner to one rank).
  virtual bool spreads_over_ranks() const { return false; }

  /// Inputs that come from outside the subtree — state an earlier schedule
  /// phase hands over by name through Tuner::set_simulator_input (a coupling
  /// does it; see TextureShadow). None by default.
  virtual std::vector<SimulatorInput> inputs() const { return {}; }
  /// Sets input `name`, replacing what it held; the next simulate() sees it.
  /// Throws InputError for a malformed field; the default (no inputs) throws
  /// std::invalid_argument naming the inputs there are.
  virtual void set_input(std::string_view name, GridField /*value*/);

  /// Reverse-mode derivative, for simulators that have one for this subtree
  /// (gradient-based optimizers need it; see Capability::gradient).
  virtual bool differentiable(const ReducerNode& /*subtree*/) const { return false; }
  /// Right after simulate(subtree, out): given `sensitivity`, ∂E/∂v for every
  /// value v of out (Observation::values order), adds ∂E/∂p to gradient[i]
  /// for the parameter of `space` entry i.
  virtual void pull_back(const ReducerNode& /*subtree*/, std::span<const double> /*sensitivity*/,
                         const SearchSpace& /*space*/, std::span<double> /*gradient*/) {
    throw std::logic_error("simulator '" + name() + "' has no derivative");
  }
};

class ErrorMetric {
 public:
  virtual ~ErrorMetric() = default;
  virtual std::string name() const = 0;
  virtual std::string_view compares() const = 0;
  virtual double error(const Observation& simulated, const Observation& target) const = 0;

  /// Metrics with a derivative say so and write ∂error/∂v for every value v
  /// of `simulated` (Observation::values order) into `sensitivity`.
  virtual bool differentiable() const { return false; }

  /// Least-squares form, for metrics that have one: error = ½‖r‖² with
  /// residual_count(target) residuals r written by residuals().
  virtual int residual_count(const Observation& /*target*/) const { return 0; }
  virtual void residuals(const Observation& /*simulated*/, const Observation& /*target*/,
                         std::span<double> /*out*/) const {
    throw std::logic_error("metric '" + name() + "' has no residual form");
  }

  /// The residual form's derivative, for metrics whose residual k depends
  /// on value k alone (every sum of squares here: r_k = w_k (s_k − t_k)):
  /// ∂r_k/∂v_k into `out`, one per residual. With the simulator's pull_back
  /// it gives the tuner's residual Jacobian (Levenberg–Marquardt with
  /// "derivatives": "analytic"). False: the metric has none.
  virtual bool residual_derivatives(const Observation& /*simulated*/, const Observation& /*target*/,
                                    std::span<double> /*out*/) const {
    return false;
  }

  virtual void error_gradient(const Observation& /*simulated*/, const Observation& /*target*/,
                              std::span<double> /*sensitivity*/) const {
    throw std::logic_error("metric '" + name() + "' has no derivative");
  }
};

class Goal {
 public:
  virtual ~Goal() = default;
  virtual std::string name() const = 0;
  virtual std::string_view describes() const = 0;
  virtual const Observation& target() const = 0;
};

template <class O>
class SimulatorFor : public Simulator {
 public:
  using ObservationType = O;
  std::string_view produces() const final { return O::kType; }
  std::unique_ptr<Observation> make_observation() const override { return std::make_unique<O>(); }
  void simulate(const ReducerNode& subtree, Observation& out) final {
    simulate(subtree, static_cast<O&>(out));
  }
  virtual void simulate(const ReducerNode& subtree, O& out) = 0;
};

template <class O>
class MetricFor : public ErrorMetric {
 public:
  using ObservationType = O;
  std::string_view compares() const final { return O::kType; }
  double error(const Observation& simulated, const Observation& target) const final {
    return error(static_cast<const O&>(simulated), static_cast<const O&>(target));
  }
  virtual double error(const O& simulated, const O& target) const = 0;
};

template <class O>
class GoalFor : public Goal {
 public:
  using ObservationType = O;
  std::string_view describes() const final { return O::kType; }
  const Observation& target() const final { return typed_target(); }
  virtual const O& typed_target() const = 0;
};

/// Simulator, metric and goal that agree on their observation type.
template <class S, class M, class G>
concept CompatibleParts =
    std::derived_from<S, Simulator> && std::derived_from<M, ErrorMetric> &&
    std::derived_from<G, Goal> &&
    std::same_as<typename S::ObservationType, typename M::ObservationType> &&
    std::same_as<typename S::ObservationType, typename G::ObservationType>;

/// What a part reads while it is built from JSON besides its properties:
/// the run's materials, whose optical and mechanical data simulators need.
/// (Relative file names in properties resolve with Properties::existing_file.)
struct PartContext {
  const MaterialPalette& palette;
  /// What the run's parts share (tables, spectra, meshes); null outside a
  /// run, when each part makes its own.
  RunCache* cache = nullptr;
  /// Every MPI rank of this process's run builds the same part and makes
  /// the same calls (`mpirun … spec2fab simulate`): a simulator that can
  /// spread one solve over the ranks does (the FEM's gamg solver); the
  /// others compute the same answer on each rank.
  bool solve_across_ranks = false;
  /// The run's limits (core/limits.h); null: the declared defaults.
  const Limits* run_limits = nullptr;
  const Limits& limits() const { return run_limits != nullptr ? *run_limits : default_limits(); }
  /// The run's printer (its print-time model); null outside a run.
  const PrinterProfile* printer = nullptr;
  /// Every MPI rank builds this part, and makes the same calls where its
  /// tuner runs in a serial phase (`mpirun … spec2fab run`; a parallel
  /// phase gives each tuner to one rank): a simulator may spread its solves
  /// over the ranks where told to (Simulator::spreads_over_ranks), which
  /// keeps its tuner out of parallel phases.
  bool every_rank_builds = false;
};

using SimulatorRegistry = Registry<Simulator, const PartContext&>;
using MetricRegistry = Registry<ErrorMetric, const PartContext&>;
using GoalRegistry = Registry<Goal, const PartContext&>;

}  // namespace spec2fab

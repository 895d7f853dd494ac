#pragma once
/// Tuners, their network and schedule as an experiment writes them, beside
/// the reducer tree they tune:
///
///   "tuners": [{"name": "patch", "node": "shell",            // node path; "" = root
///               "simulator": {...}, "metric": {...}, "goal": {...}, "optimizer": {...}}],
///   "network": {"type": "none" | "grid4" | "grid8", "width": W},   // grid: tuners row-major
///   "schedule": [{"name": "tune", "tuners": ["patch"], "sweeps": 1,
///                 "mode": "serial" | "parallel", "coupling": "none" | "error_diffusion",
///                 "fix_after": false}]
///
/// Everything is checked while building (incompatible parts, unknown node
/// paths and tuner names, a grid that does not match the tuner count, a
/// coupling that forbids parallel sweeps), so `spec2fab validate` reports it.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/options.h"
#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"

namespace spec2fab {

/// A tuner's own keys; its parts (simulator, metric, goal, optimizer) are
/// registered types with their own options.
struct TunerKeys {
  std::optional<std::string> name;
  std::string node;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.name, "name", "its name in result.json and convergence.csv", Default{"tunerN"});
    d.value(o.node, "node", "path of child labels of the subtree it tunes; \"\" = the root");
  }
};

/// A phase of the schedule; its coupling reads its own keys beside these.
struct PhaseKeys {
  std::optional<std::string> name;
  std::vector<std::string> tuners;
  int sweeps = 1;
  std::string mode = "serial";
  std::string coupling = "none";
  bool fix_after = false;
  template <class Declare, class Self>
  static void declare(Declare& d, Self& o) {
    d.value(o.name, "name", "its name in result.json", Default{"phaseN"});
    d.value(o.tuners, "tuners", "names, in the order a serial phase runs them", Default{"all"});
    d.number(o.sweeps, "sweeps", Range::closed(1, 1e6), "passes over the phase's tuners");
    d.choice(o.mode, "mode", {"serial", "parallel"},
             "parallel: the network's colour classes run together, results identical for any thread count");
    d.value(o.coupling, "coupling", "a registered coupling (`spec2fab list coupling`), with its options");
    d.value(o.fix_after, "fix_after", "fix what the phase tuned, so that a later phase tunes on top");
  }
};

/// The rows of "tuners", "network" and "schedule" for a TypeDoc, under `prefix`.
std::vector<PropertyDoc> tuning_plan_docs(const std::string& prefix);

struct TuningPlan {
  TunerNetwork network;
  Schedule schedule;
};

/// Reads "tuners", "network" and "schedule" from `goal` and binds each tuner
/// to its node of `tree` (which must outlive the plan).
std::unique_ptr<TuningPlan> build_tuning_plan(const Properties& goal, ReducerTree& tree,
                                              const PartContext& context);

}  // namespace spec2fab

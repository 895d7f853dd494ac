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

#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"

namespace spec2fab {

struct TuningPlan {
  TunerNetwork network;
  Schedule schedule;
};

/// Reads "tuners", "network" and "schedule" from `goal` and binds each tuner
/// to its node of `tree` (which must outlive the plan).
std::unique_ptr<TuningPlan> build_tuning_plan(const Properties& goal, ReducerTree& tree,
                                              const PartContext& context);

}  // namespace spec2fab

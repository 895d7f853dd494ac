// The registries of tuner parts, in `spec2fab list`.

#include "tuning/parts.h"

SPEC2FAB_LIST_REGISTRY(spec2fab::SimulatorRegistry, 30, "simulator", "simulators")
SPEC2FAB_LIST_REGISTRY(spec2fab::MetricRegistry, 40, "metric", "metrics")
SPEC2FAB_LIST_REGISTRY(spec2fab::GoalRegistry, 50, "goal", "goals")

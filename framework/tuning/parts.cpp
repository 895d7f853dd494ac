// The registries of tuner parts, in `spec2fab list`, and what every
// simulator shares.

#include "tuning/parts.h"

#include "core/strings.h"

namespace spec2fab {

void Simulator::set_input(std::string_view name, GridField /*value*/) {
  std::vector<std::string> names;
  for (const SimulatorInput& input : inputs()) names.push_back(input.name);
  throw std::invalid_argument("simulator '" + this->name() + "' has no input '" + std::string(name) + "'" +
                              (names.empty() ? std::string(" (it takes none)") : " (inputs: " + join(names) + ")"));
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::SimulatorRegistry, 30, "simulator", "simulators")
SPEC2FAB_LIST_REGISTRY(spec2fab::MetricRegistry, 40, "metric", "metrics")
SPEC2FAB_LIST_REGISTRY(spec2fab::GoalRegistry, 50, "goal", "goals")

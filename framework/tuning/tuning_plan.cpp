#include "tuning/tuning_plan.h"

#include <map>
#include <stdexcept>

#include "core/strings.h"

namespace spec2fab {

std::unique_ptr<TuningPlan> build_tuning_plan(const Properties& goal, ReducerTree& tree,
                                              const PartContext& context) {
  auto plan = std::make_unique<TuningPlan>();
  std::map<std::string, size_t> index_of;
  std::vector<std::string> names;
  const std::vector<Properties> tuners = goal.objects("tuners");
  if (tuners.empty()) goal.fail("tuners", "needs at least one tuner");
  for (size_t i = 0; i < tuners.size(); ++i) {
    const Properties& t = tuners[i];
    const std::string name = t.get<std::string>("name", "tuner" + std::to_string(i));
    if (index_of.count(name)) t.fail("name", "a second tuner named '" + name + "'");
    const std::string path = t.get<std::string>("node", "");
    ReducerNode* node = nullptr;
    try {
      node = &tree.node(path);
    } catch (const std::out_of_range& e) {
      t.fail("node", e.what());
    }
    auto tuner = build_tuner(t, name, context);
    tuner->set_node(*node, tree.is_bound() ? SimulationDomain(tree, *node) : SimulationDomain());
    index_of[name] = plan->network.add(std::move(tuner));
    names.push_back(name);
  }

  int grid_width = 0;
  if (const auto network = goal.optional_object("network")) {
    const std::string type = network->get<std::string>("type");
    if (type == "grid4" || type == "grid8") {
      grid_width = static_cast<int>(network->get_in_range("width", 1, 1, 1e9));
      const auto count = static_cast<int>(tuners.size());
      if (count % grid_width != 0) {
        network->fail("width", std::to_string(count) + " tuners do not fill rows of " +
                                   std::to_string(grid_width));
      }
      plan->network.connect_grid(grid_width, count / grid_width, type == "grid4" ? 4 : 8);
    } else if (type != "none") {
      network->fail("type", "unknown network '" + type + "'" +
                                did_you_mean(type, {"none", "grid4", "grid8"}) +
                                " (known: none, grid4, grid8)");
    }
  }

  const std::vector<Properties> phases =
      goal.has("schedule") ? goal.objects("schedule") : std::vector<Properties>{};
  if (phases.empty()) {
    Phase all;
    all.name = "tune";
    plan->schedule.add(std::move(all));
  }
  for (size_t p = 0; p < phases.size(); ++p) {
    const Properties& spec = phases[p];
    Phase phase;
    phase.name = spec.get<std::string>("name", "phase" + std::to_string(p));
    for (const std::string& name : spec.get<std::vector<std::string>>("tuners", {})) {
      const auto found = index_of.find(name);
      if (found == index_of.end()) {
        spec.fail("tuners", "no tuner '" + name + "'" + did_you_mean(name, names) +
                                " (tuners: " + join(names) + ")");
      }
      phase.tuners.push_back(found->second);
    }
    phase.sweeps = static_cast<int>(spec.get_in_range("sweeps", 1, 1, 1e6));
    const std::string mode = spec.get<std::string>("mode", "serial");
    if (mode != "serial" && mode != "parallel") spec.fail("mode", "must be serial or parallel");
    phase.mode = mode == "parallel" ? Phase::Mode::parallel : Phase::Mode::serial;
    const std::string coupling = spec.get<std::string>("coupling", "none");
    if (coupling == "error_diffusion") {
      if (grid_width == 0) spec.fail("coupling", "error_diffusion needs a grid4 or grid8 network");
      phase.coupling = std::make_shared<ErrorDiffusion>(grid_width);
      if (phase.mode == Phase::Mode::parallel) {
        spec.fail("mode", "error_diffusion depends on the order: its phase must be serial");
      }
    } else if (coupling != "none") {
      spec.fail("coupling", "unknown coupling '" + coupling + "' (known: none, error_diffusion)");
    }
    phase.fix_after = spec.get<bool>("fix_after", false);
    plan->schedule.add(std::move(phase));
  }
  return plan;
}

}  // namespace spec2fab

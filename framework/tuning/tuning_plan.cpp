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
    tuner->set_node(tree, *node);
    index_of[name] = plan->network.add(std::move(tuner));
    names.push_back(name);
  }

  const auto count = tuners.size();
  std::unique_ptr<NetworkShape> shape;
  if (const auto network = goal.optional_object("network")) {
    shape = NetworkRegistry::instance().create(*network, "network", count);
  } else {
    shape = NetworkRegistry::instance().create_named("none", goal, "network", count);
  }
  shape->connect(plan->network);

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
    const CouplingContext coupling_context{*shape, phase.mode == Phase::Mode::parallel, &plan->network,
                                           phase.members(plan->network.size()), &plan->schedule.phases(),
                                           &context.palette};
    phase.coupling = CouplingRegistry::instance().create_named(coupling, spec, "coupling", coupling_context, "coupling");
    if (phase.mode == Phase::Mode::parallel) {
      if (const auto overlap = overlapping_tuners(plan->network, phase.members(plan->network.size()))) {
        spec.fail("mode", "tuners '" + names[overlap->first] + "' and '" + names[overlap->second] +
                              "' cannot run in parallel: their subtrees overlap (they would set the same "
                              "parameters at once); make the phase serial");
      }
    }
    phase.fix_after = spec.get<bool>("fix_after", false);
    plan->schedule.add(std::move(phase));
  }
  return plan;
}

}  // namespace spec2fab

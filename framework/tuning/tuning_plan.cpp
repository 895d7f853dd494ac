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
    const TunerKeys keys = read_options<TunerKeys>(t);
    const std::string name = keys.name.value_or("tuner" + std::to_string(i));
    if (index_of.count(name)) t.fail("name", "a second tuner named '" + name + "'");
    const std::string& path = keys.node;
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
    const PhaseKeys keys = read_options<PhaseKeys>(spec);
    Phase phase;
    phase.name = keys.name.value_or("phase" + std::to_string(p));
    for (const std::string& name : keys.tuners) {
      const auto found = index_of.find(name);
      if (found == index_of.end()) {
        spec.fail("tuners", "no tuner '" + name + "'" + did_you_mean(name, names) +
                                " (tuners: " + join(names) + ")");
      }
      phase.tuners.push_back(found->second);
    }
    phase.sweeps = keys.sweeps;
    phase.mode = keys.mode == "parallel" ? Phase::Mode::parallel : Phase::Mode::serial;
    const std::string& coupling = keys.coupling;
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
      const std::vector<size_t> members = phase.members(plan->network.size());
      if (const auto spreading = spreading_tuner_problem(plan->network, members)) spec.fail("mode", *spreading);
      if (const auto reading = tuner_reading_a_neighbour(plan->network, plan->network.colour_classes(members)))
        spec.fail("mode", reading_a_neighbour_problem(plan->network, *reading));
    }
    phase.fix_after = keys.fix_after;
    plan->schedule.add(std::move(phase));
  }
  return plan;
}

std::vector<PropertyDoc> tuning_plan_docs(const std::string& prefix) {
  std::vector<PropertyDoc> rows = {
      {prefix + "tuners", "array of {" + join([] {
                            std::vector<std::string> keys;
                            for (const PropertyDoc& row : option_docs<TunerKeys>()) keys.push_back(row.name);
                            for (const char* part : {"simulator", "metric", "goal", "optimizer", "weight", "terms"})
                              keys.push_back(part);
                            return keys;
                          }()) + "}",
       "none", "the tuners; each part a registered type with its options (`spec2fab list simulator` ...)"}};
  append(rows, prefixed(option_docs<TunerKeys>(), prefix + "tuners[]."));
  append(rows, tuner_term_docs(prefix + "tuners[]."));
  rows.push_back({prefix + "network", "object", "none",
                  "{type, ...}: a registered network shape (`spec2fab list network`), tuners row-major"});
  rows.push_back({prefix + "schedule", "array of phases", "one serial phase of all tuners", "the phases, in order"});
  append(rows, prefixed(option_docs<PhaseKeys>(), prefix + "schedule[]."));
  return rows;
}

}  // namespace spec2fab

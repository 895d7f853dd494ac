// The "tree" translator: a reducer tree written in the experiment file,
// either fully specified (direct specification) or with free parameters that
// tuners assembled from JSON tune first (tuning/tuning_plan.h: any registered
// simulator, metric, goal and optimizer, a network and a schedule). It binds
// the tree to the shape, tunes, writes what the tree assigns (tree.json, a
// material census, cross-section pictures, the tuning record and
// convergence.csv), then fabricates it at the printer's resolution (print/ and
// preview/render.png; see fabrication/fabricate.h).

#include <cmath>

#include <spdlog/spdlog.h>

#include "reducer/reducer_tree.h"
#include "spec/tuning_translator.h"
#include "tuning/tuning_plan.h"

namespace spec2fab {
namespace {

class TreeTranslator final : public TuningTranslator {
 public:
  TreeTranslator(const Properties& /*root*/, const Experiment& experiment) {
    const Properties goal = experiment.goal();
    set_tree(std::make_unique<ReducerTree>(goal.object("tree"), experiment.palette(), experiment.limits()), goal, experiment);
    report_final_errors_ = true;  // its only figures: each tuner's error against its goal at the end
    if (goal.has("tuners")) {
      const auto plan = build_tuning_plan(goal, *tree_, experiment.part_context());
      network_ = std::move(plan->network);
      schedule_ = std::move(plan->schedule);
    } else if (const SearchSpace free = tree_->search_space(); free.dimension() > 0) {
      // Without tuners nothing is tuned; a free parameter is likely a mistake.
      spdlog::warn(
          "{} free parameter(s) (e.g. {}) stay at their values: no \"tuners\" tune them",
          free.dimension(), free.entries().front().name);
    }
  }

  std::string summary() const override {
    std::string text = "tree: a reducer tree (" + std::to_string(tree_->node_count()) +
                       " nodes) bound to the shape";
    if (network_.size() > 0) {
      text += ", tuned by " + std::to_string(network_.size()) + " tuner(s) in " +
              std::to_string(schedule_.phases().size()) + " phase(s)";
    }
    return text + "; writes tree.json, a material census on " +
           std::to_string(outputs_.census_voxel_mm) + " mm voxels and cross-section previews";
  }

  static TypeDoc doc() {
    TypeDoc doc{
        "A reducer tree, directly specified or tuned by tuners assembled from JSON. Binds it "
        "to the shape, tunes its free parameters, reports what it assigns and fabricates it.",
        {{"goal.tree", "node", "required", "the reducer tree (see `spec2fab list node`)"}},
        R"({"translator": "tree", "goal": {"tree": {"type": "layered", "material": )"
        R"("VeroWhitePlus"}}})"};
    append(doc.properties, tuning_plan_docs("goal."));
    append(doc.properties, TreeOutputOptions::docs());
    return doc;
  }

 private:
  /// The tuning record (with each tuner's final error) says it all; the log
  /// has each run.
  void report(const RunRecord& record, RunContext& /*context*/) override {
    for (const TunerRun& run : record.runs) {
      spdlog::debug("{} ({}, sweep {}): {}", network_.tuner(run.tuner).name(), record.phase_names[run.phase],
                    run.sweep + 1, run.summary.brief_report());
    }
  }
};

}  // namespace
}  // namespace spec2fab

SPEC2FAB_REGISTER(spec2fab::TranslatorRegistry, spec2fab::TreeTranslator, "tree")

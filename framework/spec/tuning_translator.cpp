#include "spec/tuning_translator.h"

#include "core/interrupt.h"

#include "reducer/reducer_tree.h"
#include "spec/tuning_outputs.h"

namespace spec2fab {

void TuningTranslator::set_tree(std::unique_ptr<ReducerTree> tree, const Properties& goal,
                                const Experiment& experiment) {
  tree_ = std::move(tree);
  limits_ = &experiment.limits();
  try {
    tree_->bind(experiment.solid(), experiment.geometry_spec().field_voxel_mm);
  } catch (const FieldBeyondLimit& e) {
    experiment.root().object("geometry").fail("field_voxel_mm", e.what());
  }
  outputs_ = TreeOutputOptions::read(goal, experiment, *tree_);
}

void TuningTranslator::set_tree(NodePtr root, const Properties& goal, const Experiment& experiment) {
  set_tree(std::make_unique<ReducerTree>(std::move(root), experiment.palette(), experiment.limits()), goal, experiment);
}

std::string TuningTranslator::check_limits() {
  return network_.size() > 0 ? schedule_.check_plan(network_, *limits_) : std::string();
}

void TuningTranslator::run(RunContext& context) {
  if (tunes()) {
    prepare(context);
    RunRecord record;
    if (network_.size() > 0) {
      record = schedule_.run(network_, context.seed, *limits_, context.checkpoint);
      context.tuner_runs_here += record.tuner_runs_here;
      tree_->evaluate();
      write_tuning_outputs(record, network_, context, report_final_errors_);
    }
    report(record, context);
  }
  interrupt::throw_if_stop_requested();  // before the print, often most of a run's time
  write_tree_outputs(*tree_, outputs_, context, print_surfaces_);
  after_print(context);
}

}  // namespace spec2fab

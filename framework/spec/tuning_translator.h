#pragma once
/// The skeleton of every translator that tunes a reducer tree: it owns the
/// tree, the tree outputs, the tuner network and the schedule, and runs
///
///   prepare → schedule → tree evaluated → tuning record → report → tree outputs → after_print
///
/// A translator derived from it builds the tree (`set_tree`), adds tuners to
/// `network_` and phases to `schedule_` in its constructor — from pieces such
/// as the texture (translators/pieces) — and writes only what is its own in
/// `report`. A translator with no tuners writes the tree outputs alone
/// unless it overrides tunes().

#include <memory>

#include "reducer/node.h"
#include "spec/translator.h"
#include "spec/tree_outputs.h"
#include "tuning/schedule.h"

namespace spec2fab {

class TuningTranslator : public Translator {
 public:
  const ReducerTree& tree() const final { return *tree_; }
  void run(RunContext& context) final;
  std::string check_limits() final;
  long long estimated_output_bytes() const final { return outputs_.estimated_bytes; }
  /// The tuners as the constructor built and bound them, before the
  /// schedule's first phase: what the Python module's tuner_problem hands
  /// to outside optimizers.
  TunerNetwork& tuners() { return network_; }

 protected:
  /// Takes the tree, binds it to the experiment's solid and reads the
  /// outputs' options (refusing an oversized print now).
  void set_tree(std::unique_ptr<ReducerTree> tree, const Properties& goal, const Experiment& experiment);
  /// set_tree for a tree the translator composed (reducer/nodes/nodes.h).
  void set_tree(NodePtr root, const Properties& goal, const Experiment& experiment);

  /// Before the schedule runs: what the report compares with (the start).
  virtual void prepare(RunContext& /*context*/) {}
  /// Whether prepare and report run: with tuners, or for a translator that
  /// chooses its parameters without them (the albedo lookup) and says so.
  virtual bool tunes() const { return network_.size() > 0; }
  /// After the schedule ran, the tree was evaluated and the tuning record
  /// written: the translator's figures (its section of the RunReport),
  /// previews, and the surfaces it wants printed (print_surfaces_).
  virtual void report(const RunRecord& record, RunContext& context) = 0;
  /// After the print was written: what checks the print's files (a
  /// surface read back and traced).
  virtual void after_print(RunContext& /*context*/) {}

  std::unique_ptr<ReducerTree> tree_;
  TreeOutputOptions outputs_;
  TunerNetwork network_;
  Schedule schedule_;
  /// Surfaces the translator defines exactly, printed beside the materials'
  /// (fabrication/print_writer.h); set in report().
  std::vector<PrintSurface> print_surfaces_;
  /// The tuning record lists each tuner's final error against its own goal.
  bool report_final_errors_ = false;

 private:
  const Limits* limits_ = nullptr;  ///< the experiment's (set_tree)
};

}  // namespace spec2fab

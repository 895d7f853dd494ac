#pragma once
/// Translators (paper §4, §7): given an experiment's inputs, decide which
/// material goes where. A translator is one folder under translators/ ending
/// in `SPEC2FAB_REGISTER(TranslatorRegistry, MyTranslator, "name")`.
///
/// Its constructor reads its sections of the experiment (goal, simulation,
/// optimizer) and builds everything it will need — reducer tree, tuners — so
/// that `spec2fab validate` catches every input problem before any work;
/// `run` then does the work and writes into the run folder.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "core/registry.h"
#include "core/run_folder.h"
#include "spec/experiment.h"
#include "spec/run_report.h"

namespace spec2fab {

class ReducerTree;
class PhaseCheckpoint;

struct RunContext {
  const Experiment& experiment;
  RunFolder& folder;
  int threads = 1;
  std::uint64_t seed = 1;
  RunReport& report;  ///< result.json: each part adds its own section, once
  /// timing.json (wall-clock figures, which would break result.json's
  /// byte-identity); null when nobody records timings.
  nlohmann::json* timing = nullptr;
  /// Where a tuning schedule saves its state after each phase and finds what
  /// a killed run saved (Schedule::run); null: no checkpoints.
  PhaseCheckpoint* checkpoint = nullptr;
  /// Tuner runs this process made in the run's schedules (RunRecord::
  /// tuner_runs_here, added up by whoever runs one): timing.json's split
  /// over the ranks.
  long long tuner_runs_here = 0;
};

class Translator {
 public:
  virtual ~Translator() = default;
  /// One paragraph for `spec2fab validate`: what will run.
  virtual std::string summary() const = 0;
  virtual void run(RunContext& context) = 0;
  /// The tuned tree (after run), written to tree.json.
  virtual const ReducerTree& tree() const = 0;
  /// Refuses (InputError) work past the resource limits that only the built
  /// translator can count, such as its schedule's tuner runs and planned
  /// evaluations: `validate` then refuses it too. Returns what it counted,
  /// for validate to show (empty: nothing).
  virtual std::string check_limits() { return {}; }
  /// What its files will take on disk, as far as it can tell before the
  /// work (the print's estimate); `run` refuses a destination with less
  /// free space before any work. 0: nothing worth checking.
  virtual long long estimated_output_bytes() const { return 0; }
};

using TranslatorRegistry = Registry<Translator, const Experiment&>;

/// An experiment loaded, its translator built, every key checked.
struct PreparedExperiment {
  std::unique_ptr<Experiment> experiment;  // stable address: the translator refers to it
  std::unique_ptr<Translator> translator;
  std::string plan;  ///< Translator::check_limits' count
};

/// Throws InputError for any problem in the file or the inputs it names.
/// `limits`: the command line's (which win over the experiment's "limits").
/// `session`: a cache kept across preparations by a process that prepares
/// many and runs none (Experiment::load); none: the experiment's own.
PreparedExperiment prepare_experiment(const std::filesystem::path& file, const Limits& limits,
                                      std::shared_ptr<RunCache> session = nullptr);
PreparedExperiment prepare_experiment(ExperimentSource source, const Limits& limits,
                                      std::shared_ptr<RunCache> session = nullptr);

struct RunOptions {
  std::filesystem::path out;  ///< empty: out/<experiment name>
  int threads = 0;            ///< 0: all cores
  std::optional<std::uint64_t> seed;  ///< overrides the experiment's seed
  /// Go on from the last phase a killed run of the same experiment, seed and
  /// output folder finished (its checkpoint), to the files an uninterrupted
  /// run writes; with none, start from the beginning.
  bool resume = false;
  Limits limits;  ///< the command line's, over the experiment's "limits"
  /// Write report.html (report/html_report.h) beside result.json; `run
  /// --no-report` turns it off (a batch of runs, one page written later
  /// with `spec2fab report`).
  bool report_html = true;
};

/// Prepares and runs an experiment, writing the run folder all-or-nothing.
/// Returns the folder written.
std::filesystem::path run_experiment(const std::filesystem::path& file, const RunOptions& options);
std::filesystem::path run_experiment(ExperimentSource source, const RunOptions& options);

}  // namespace spec2fab

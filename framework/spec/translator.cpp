#include "spec/translator.h"
#include "core/file_write.h"

#include <chrono>
#include <thread>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/ranks.h"
#include "core/version.h"
#include "reducer/reducer_tree.h"
#include "report/html_report.h"
#include "spec/report_fields.h"
#include "tuning/schedule.h"

namespace spec2fab {

PreparedExperiment prepare_experiment(const std::filesystem::path& file, const Limits& limits,
                                      std::shared_ptr<RunCache> session) {
  return prepare_experiment(ExperimentSource::read(file), limits, std::move(session));
}

PreparedExperiment prepare_experiment(ExperimentSource source, const Limits& limits, std::shared_ptr<RunCache> session) {
  PreparedExperiment prepared;
  prepared.experiment =
      std::make_unique<Experiment>(Experiment::load(std::move(source), limits, std::move(session)));
  const Experiment& experiment = *prepared.experiment;
  prepared.translator = TranslatorRegistry::instance().create(experiment.root(), "translator",
                                                              experiment, "translator");
  experiment.root().check_all_read();
  prepared.plan = prepared.translator->check_limits();
  return prepared;
}

namespace {

/// A schedule's checkpoint in the run folder (checkpoint/schedule.cbor).
class FolderCheckpoint final : public PhaseCheckpoint {
 public:
  explicit FolderCheckpoint(const RunFolder& folder) : folder_(folder) {}
  std::vector<std::uint8_t> load() override { return folder_.read_checkpoint("schedule.cbor"); }
  void save(const std::vector<std::uint8_t>& state) override { folder_.write_checkpoint("schedule.cbor", state); }

 private:
  const RunFolder& folder_;
};

/// What a checkpoint was made from: a resumed run must have the same.
nlohmann::json run_identity(const Experiment& experiment, const RunHeader& header) {
  const nlohmann::json written = write_section(header);
  return {{"spec2fab_version", written["spec2fab_version"]},
          {"seed", written["seed"]},
          {"inputs", written["inputs"]},
          // The experiment as parsed: a file or a dict, whitespace aside.
          {"experiment_text", experiment.root().value().dump()}};
}

/// Refuses to resume a run of other inputs; records this run's for a later resume.
void check_run_identity(RunFolder& folder, const nlohmann::json& identity) {
  const std::vector<std::uint8_t> saved = folder.read_checkpoint("run.json");
  if (folder.resumed() && !saved.empty()) {
    const nlohmann::json before = nlohmann::json::parse(saved.begin(), saved.end(), nullptr, false);
    if (before != identity) {
      std::string what;
      for (const char* key : {"experiment_text", "inputs", "seed", "spec2fab_version"})
        if (before.is_discarded() || before.value(key, nlohmann::json()) != identity[key]) {
          what = key == std::string("experiment_text") ? "experiment file" : key;
          break;
        }
      folder.give_back_resumed();
      throw InputError(folder.destination().string() + ": --resume: the killed run had another " + what +
                       "; run without --resume to start afresh");
    }
  }
  const std::string text = identity.dump();
  folder.write_checkpoint("run.json", std::vector<std::uint8_t>(text.begin(), text.end()));
}

}  // namespace

std::filesystem::path run_experiment(const std::filesystem::path& file, const RunOptions& options) {
  return run_experiment(ExperimentSource::read(file), options);
}

std::filesystem::path run_experiment(ExperimentSource source, const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const WarningRecorder warnings;  // for timing.json and the page: what this execution warned of
  PreparedExperiment prepared = prepare_experiment(std::move(source), options.limits);
  const Experiment& experiment = *prepared.experiment;

  const int threads = options.threads > 0
                          ? options.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<size_t>(threads));
  const std::filesystem::path out =
      options.out.empty() ? std::filesystem::path("out") / experiment.name() : options.out;
  if (options.resume && ranks::size() > 1)
    throw InputError("--resume: a run under mpirun cannot be resumed; run it in one process");
  require_free_space(out, prepared.translator->estimated_output_bytes(), "the run's files");
  RunFolder folder(out, options.resume);

  // result.json holds only what the inputs determine, so that a rerun with any
  // thread count is byte-identical; wall-clock times go to timing.json.
  RunReport report(RunHeader{version(), experiment.name(), experiment.translator(),
                             options.seed.value_or(experiment.seed()), InputsRecord::of(experiment)});
  nlohmann::json timing = {{"threads", threads}};
  check_run_identity(folder, run_identity(experiment, report.header()));
  FolderCheckpoint checkpoint(folder);
  // Only rank 0's folder keeps a checkpoint: the other ranks need not build one.
  RunContext context{experiment, folder, threads, report.header().seed, report, &timing,
                     ranks::root() ? &checkpoint : nullptr};
  spdlog::info("running '{}' ({}) on {} thread(s)", experiment.name(), experiment.translator(), threads);
  folder.writing([&] {
    prepared.translator->run(context);
    interrupt::throw_if_stop_requested();  // a stop during the print: nothing committed
    folder.write_json("tree.json", prepared.translator->tree().to_json());
    folder.write_json("result.json", report.to_json());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    timing["wall_seconds"] = seconds;
    if (ranks::size() > 1) {
      // Which rank tuned how much: the parallel phases' split.
      std::vector<long long> runs(static_cast<size_t>(ranks::size()), 0);
      runs[static_cast<size_t>(ranks::rank())] = context.tuner_runs_here;
      ranks::sum(runs);
      timing["ranks"] = ranks::size();
      timing["tuner_runs_per_rank"] = runs;
    }
    if (const auto messages = warnings.messages(); !messages.empty()) timing["warnings"] = messages;
    folder.write_json("timing.json", timing);
    // The page people open first, built from the files above (as `spec2fab report` builds it again).
    if (ranks::root() && options.report_html) {
      interrupt::throw_if_stop_requested();
      try {
        write_run_report_html(folder.path("."), TranslatorRegistry::instance().doc(experiment.translator()).summary,
                              report_meanings(experiment.translator()));
      } catch (const WriteError&) {
        throw;  // a full disk fails the run, as any of its writes does
      } catch (const interrupt::Stopped&) {
        throw;
      } catch (const std::exception& e) {
        // A finished run is not thrown away for its page; the command writes it later.
        spdlog::warn("report.html not written ({}); `spec2fab report {}` writes it", folder.as_destination(e.what()),
                     out.string());
      }
    }
  });
  folder.commit();
  return out;
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::TranslatorRegistry, 20, "translator", "translators")

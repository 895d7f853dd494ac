#include "spec/tuning_outputs.h"

#include "core/run_folder.h"
#include "tuning/convergence_plot.h"

namespace spec2fab {

void write_tuning_outputs(const RunRecord& record, TunerNetwork& network, RunContext& context,
                          bool final_errors) {
  TuningReport report = record.report(network);
  if (final_errors) {
    std::vector<TunerFinalError>& tuners = report.tuners.emplace();
    for (size_t t = 0; t < network.size(); ++t) {
      Tuner& tuner = network.tuner(t);
      tuner.reset_target();
      const double error = tuner.error();
      tuners.push_back({tuner.name(), error, {}});
      if (tuner.term_count() > 1) tuners.back().terms = tuner.term_values();
    }
  }
  context.report.add("tuning", report);
  context.folder.write_text("convergence.csv", record.convergence_csv(network));
  write_convergence_plot(record, network.size(), context.folder.path("preview/convergence.png"));
  if (context.timing) (*context.timing)["tuning_phase_seconds"] = record.phase_seconds;
}

}  // namespace spec2fab

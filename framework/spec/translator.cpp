#include "spec/translator.h"

#include <chrono>
#include <thread>

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include "core/ranks.h"
#include "core/version.h"
#include "reducer/reducer_tree.h"
#include "tuning/schedule.h"

namespace spec2fab {

PreparedExperiment prepare_experiment(const std::filesystem::path& file) {
  PreparedExperiment prepared;
  prepared.experiment = std::make_unique<Experiment>(Experiment::load(file));
  const Experiment& experiment = *prepared.experiment;
  prepared.translator = TranslatorRegistry::instance().create(experiment.root(), "translator",
                                                              experiment, "translator");
  experiment.root().check_all_read();
  return prepared;
}

namespace {

nlohmann::json describe_inputs(const Experiment& experiment) {
  const Solid& solid = experiment.solid();
  const Bounds& b = solid.bounds();
  const PrinterProfile& printer = experiment.printer();
  return {
      {"experiment", experiment.file().string()},
      {"geometry",
       {{"mesh", experiment.geometry_spec().mesh.string()},
        {"vertices", solid.mesh().vertices.size()},
        {"triangles", solid.mesh().triangles.size()},
        {"volume_mm3", solid.volume()},
        {"surface_area_mm2", solid.mesh().surface_area()},
        {"bounds_mm", {{b.lower.x(), b.lower.y(), b.lower.z()}, {b.upper.x(), b.upper.y(), b.upper.z()}}},
        {"uv", to_string(solid.uv_source())},
        // What `spec2fab export` needs to rebuild the same Solid.
        {"scale_to_mm", experiment.geometry_spec().scale_to_mm},
        {"uv_axis", experiment.geometry_spec().uv_axis},
        {"field_voxel_mm", experiment.geometry_spec().field_voxel_mm}}},
      {"materials", experiment.library().origin()},
      {"printer",
       {{"name", printer.name},
        {"file", printer.origin},
        {"resolution_dpi", printer.dpi},
        {"layer_mm", printer.layer_mm},
        {"model_materials", printer.model_materials}}},
  };
}

}  // namespace

std::filesystem::path run_experiment(const std::filesystem::path& file, const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PreparedExperiment prepared = prepare_experiment(file);
  const Experiment& experiment = *prepared.experiment;

  const int threads = options.threads > 0
                          ? options.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<size_t>(threads));
  const std::filesystem::path out =
      options.out.empty() ? std::filesystem::path("out") / experiment.name() : options.out;
  RunFolder folder(out);

  // result.json holds only what the inputs determine, so that a rerun with any
  // thread count is byte-identical; wall-clock times go to timing.json.
  nlohmann::json result = {{"spec2fab_version", version()},
                           {"experiment", experiment.name()},
                           {"translator", experiment.translator()},
                           {"seed", options.seed.value_or(experiment.seed())},
                           {"inputs", describe_inputs(experiment)}};
  nlohmann::json timing = {{"threads", threads}};
  RunContext context{experiment, folder, threads, options.seed.value_or(experiment.seed()), result, &timing};
  spdlog::info("running '{}' ({}) on {} thread(s)", experiment.name(), experiment.translator(), threads);
  prepared.translator->run(context);

  folder.write_json("tree.json", prepared.translator->tree().to_json());
  folder.write_json("result.json", result);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  timing["wall_seconds"] = seconds;
  if (ranks::size() > 1) {
    // Which rank tuned how much: the parallel phases' split.
    std::vector<long long> runs(static_cast<size_t>(ranks::size()), 0);
    runs[static_cast<size_t>(ranks::rank())] = tuner_runs_in_this_process();
    ranks::sum(runs);
    timing["ranks"] = ranks::size();
    timing["tuner_runs_per_rank"] = runs;
  }
  folder.write_json("timing.json", timing);
  folder.commit();
  return out;
}

}  // namespace spec2fab

SPEC2FAB_LIST_REGISTRY(spec2fab::TranslatorRegistry, 20, "translator", "translators")

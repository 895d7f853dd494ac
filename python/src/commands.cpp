// run, validate, simulate, list, bench: the commands, called as functions.
#include <pybind11/stl.h>

#include <algorithm>

#include "bindings.h"
#include "bench/harness.h"
#include "commands.h"
#include "core/interrupt.h"
#include "core/registry.h"
#include "core/run_folder.h"
#include "core/strings.h"
#include "spec/translator.h"

namespace spec2fab::python {
namespace {

std::string run(py::handle experiment, std::optional<std::string> out, std::optional<int> threads,
                std::optional<std::uint64_t> seed, std::optional<std::string> origin, bool resume, bool report) {
  ExperimentSource source = experiment_source(experiment, origin);
  RunOptions options;
  if (out) options.out = *out;
  if (threads) {
    if (*threads < 1 || *threads > 1024) throw InputError("threads: " + std::to_string(*threads) + " is not in [1, 1024]");
    options.threads = *threads;
  }
  options.seed = seed;
  options.resume = resume;
  options.report_html = report;
  // A Ctrl-C after the folder was committed leaves a complete run: it is returned.
  return long_call([&] { return run_experiment(std::move(source), options).string(); }, true);
}

py::dict validate(py::handle experiment, std::optional<std::string> origin) {
  ExperimentSource source = experiment_source(experiment, origin);
  // Loading a mesh and building its field takes a while.
  const PreparedExperiment prepared = long_call([&] { return prepare_experiment(std::move(source), Limits()); });
  const Experiment& e = *prepared.experiment;
  py::dict summary;
  summary["name"] = e.name();
  summary["translator"] = e.translator();
  summary["summary"] = prepared.translator->summary();
  summary["mesh"] = e.geometry_spec().mesh.string();
  summary["triangles"] = e.solid().mesh().triangles.size();
  summary["volume_mm3"] = e.solid().volume();
  summary["uv"] = to_string(e.solid().uv_source());
  summary["printer"] = e.printer().name;
  summary["materials"] = e.palette().names();
  summary["tuning"] = prepared.plan;
  return summary;
}

py::array_t<double> simulate(const std::string& simulator, py::handle config, std::optional<std::string> origin) {
  const Properties properties = properties_of(config, origin);
  const std::unique_ptr<Observation> observation = long_call([&] {
    cli::PreparedSimulation prepared = cli::prepare_simulation(properties, simulator, Limits());
    std::unique_ptr<Observation> out = prepared.simulator->make_observation();
    cli::set_up(prepared);
    cli::simulate_checked(prepared, *out);
    return out;
  });
  return to_array(*observation);
}

/// Every listed registry: kind → [(name, summary)], in `spec2fab list` order.
py::list registries() {
  std::vector<ListedRegistry> listed = listed_registries();
  std::stable_sort(listed.begin(), listed.end(), [](const auto& a, const auto& b) { return a.rank < b.rank; });
  py::list out;
  for (const ListedRegistry& registry : listed) {
    py::list entries;
    for (const auto& [name, doc] : registry.entries()) entries.append(py::make_tuple(name, doc.summary));
    out.append(py::make_tuple(registry.kind, registry.heading, entries));
  }
  return out;
}

/// bench's matrix: `problems` names registered problems (empty: all), those
/// registered from Python included; `optimizers` are entrant labels.
std::string bench(std::vector<std::string> problems, std::vector<std::string> optimizers, int seeds,
                  const std::string& budget, const std::string& out, std::optional<int> threads, bool quick,
                  std::optional<std::string> entrants) {
  cli::BenchArguments arguments;
  arguments.problems = std::move(problems);
  arguments.optimizers = std::move(optimizers);
  arguments.seeds = seeds;
  arguments.budget = budget;
  arguments.out = out;
  arguments.threads = threads.value_or(0);
  arguments.quick = quick;
  arguments.datasets = datasets_folder();
  if (entrants) arguments.entrants = *entrants;
  long_call([&] { cli::bench_command(arguments); });
  return out;
}

}  // namespace

void bind_commands(py::module_& m) {
  m.def("_run", &run, py::arg("experiment"), py::arg("out"), py::arg("threads"), py::arg("seed"), py::arg("origin"),
        py::arg("resume"), py::arg("report"));
  m.def("_validate", &validate, py::arg("experiment"), py::arg("origin"));
  m.def("_simulate", &simulate, py::arg("simulator"), py::arg("config"), py::arg("origin"));
  m.def("_registries", &registries);
  m.def("_bench", &bench, py::arg("problems"), py::arg("optimizers"), py::arg("seeds"), py::arg("budget"),
        py::arg("out"), py::arg("threads"), py::arg("quick"), py::arg("entrants"));
  m.def("_datasets", [] { return datasets_folder().string(); });
  m.def("_report", [](const std::string& folder) { return long_call([&] { return cli::write_report(folder).string(); }); },
        py::arg("folder"));
}

}  // namespace spec2fab::python

#include "commands.h"
#include "core/file_read.h"
#include "core/file_write.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

#include <unistd.h>

#include <tbb/global_control.h>

#include "bench/harness.h"
#include "core/error.h"
#include "core/strings.h"
#include "fabrication/fabricate.h"
#include "core/ranks.h"
#include "geometry/mesh_io.h"
#include "materials/material_library.h"
#include "materials/palette_files.h"
#include "materials/printer_profile.h"
#include "reducer/node.h"
#include "reducer/reducer_tree.h"
#include "report/html_report.h"
#include "spec/report_fields.h"
#include "spec/experiment.h"
#include "spec/run_report.h"
#include "core/run_folder.h"
#include "spec/translator.h"
#include "spec/tree_outputs.h"
#include "tuning/optimizer.h"
#include "tuning/parts.h"

namespace spec2fab::cli {

namespace fs = std::filesystem;

int run_command(const RunArguments& arguments) {
  RunOptions options;
  options.out = arguments.out;
  options.threads = arguments.threads;
  options.seed = arguments.seed;
  options.resume = arguments.resume;
  options.limits = arguments.limits;
  options.report_html = arguments.report_html;
  const fs::path folder = run_experiment(arguments.experiment, options);
  if (ranks::root())
    std::cout << "wrote " << folder.string() << "/ (" << (options.report_html ? "report.html, " : "")
              << "result.json, tree.json, preview/, print/)\n";
  return 0;
}

fs::path write_report(const fs::path& folder) {
  if (report_folder_kind(folder) == ReportFolderKind::bench) {
    write_bench_report_html(folder);
  } else {
    // What the run was for: its translator's summary, where this build has the translator.
    std::ifstream file(folder / "result.json");
    const nlohmann::json result = nlohmann::json::parse(file, nullptr, false);
    std::string purpose;
    std::map<std::string, std::string> meanings;
    if (result.is_object() && result.contains("translator") && result["translator"].is_string() &&
        TranslatorRegistry::instance().contains(result["translator"].get<std::string>())) {
      const std::string translator = result["translator"].get<std::string>();
      purpose = TranslatorRegistry::instance().doc(translator).summary;
      meanings = report_meanings(translator);
    }
    write_run_report_html(folder, purpose, meanings);
  }
  return folder / "report.html";
}

int report_command(const fs::path& folder) {
  const fs::path page = write_report(folder);
  std::cout << "wrote " << page.string() << " ("
            << fmt::format("{:.1f}", static_cast<double>(fs::file_size(page)) / (1 << 20)) << " MB)\n";
  return 0;
}

int bench_command(BenchArguments arguments) {
  if (arguments.quick) {
    // A smoke test of every problem and entrant: a short budget, few seeds.
    arguments.seeds = std::min(arguments.seeds, 3);
    arguments.budget = "12d";
  }
  const fs::path entrants_file =
      arguments.entrants.empty() ? arguments.datasets / "bench" / "entrants.json" : arguments.entrants;
  std::vector<Entrant> entrants = read_entrants(entrants_file);
  if (!arguments.optimizers.empty()) {
    std::vector<Entrant> chosen;
    std::vector<std::string> labels;
    for (const Entrant& e : entrants) labels.push_back(e.label);
    for (const std::string& label : arguments.optimizers) {
      const auto found = std::find_if(entrants.begin(), entrants.end(), [&](const Entrant& e) { return e.label == label; });
      if (found == entrants.end()) {
        throw InputError("--optimizers: unknown entrant '" + label + "'" + did_you_mean(label, labels) +
                         " (known: " + join(labels) + "; entrants come from " + entrants_file.string() +
                         " and every registered optimizer)");
      }
      chosen.push_back(*found);
    }
    entrants = std::move(chosen);
  }
  BenchOptions options;
  options.problems = arguments.problems;
  options.entrants = std::move(entrants);
  options.seeds = arguments.seeds;
  options.budget = Budget::parse(arguments.budget);
  options.threads = arguments.threads;
  const auto start = std::chrono::steady_clock::now();
  if (arguments.progress) {
    // On a terminal one line rewritten at most 4 times a second; into a
    // file or pipe, a line every 10 s.
    const bool terminal = isatty(STDERR_FILENO) != 0;
    options.progress = [start, terminal, shown = -1.0](const BenchProgress& p) mutable {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const bool last = p.runs_done == p.runs;
      if (!last && elapsed - shown < (terminal ? 0.25 : 10.0)) return;
      shown = elapsed;
      const double left = p.runs_done > 0 ? elapsed * static_cast<double>(p.runs - p.runs_done) / p.runs_done : 0;
      std::cerr << (terminal ? "\r" : "") << "bench: pairs " << p.pairs_done << "/" << p.pairs << " done, runs "
                << p.runs_done << "/" << p.runs << ", " << format_seconds(elapsed) << " elapsed"
                << (last ? "" : ", ETA " + format_seconds(left)) << (terminal && !last ? "   " : "\n") << std::flush;
    };
  }
  require_free_space(arguments.out, estimated_bench_report_bytes(options), "the benchmark's files");
  RunCache cache;
  const BenchResult result = run_bench(options, BenchmarkContext{arguments.datasets, &cache});
  RunFolder folder(arguments.out);
  folder.writing([&] { write_bench_report(result, folder.path(".")); });
  folder.commit();
  size_t ran = 0, incompatible = 0;
  for (const BenchPair& pair : result.pairs) (pair.missing.empty() ? ran : incompatible) += 1;
  std::cout << "wrote " << arguments.out.string() << "/ (report.html, report.md, report.json, ioh/, plots/, timing/): "
            << result.runs.size() << " runs of " << ran << " pairs (" << incompatible
            << " incompatible pairs listed) in " << format_seconds(result.wall_seconds) << "\n";
  for (const BenchProblem& problem : result.problems) {
    if (!problem.unavailable.empty()) std::cout << "  not run: " << problem.name << ": " << problem.unavailable << "\n";
  }
  return 0;
}

namespace {

// A path recorded in result.json: absolute, or relative to the folder the run
// was started in (tried from here); a problem is named at `key` of `record`.
fs::path recorded_file(const Properties& record, const std::string& key, const std::string& path) {
  const fs::path file = path;
  if (const std::string why = unreadable_file_reason(file); !why.empty())
    record.fail(key, why + ": " + file.string() + " (relative paths are read from the folder the run was started in)");
  return file;
}

}  // namespace

int export_command(const ExportArguments& arguments) {
  const auto start = std::chrono::steady_clock::now();
  // tree.json holds the tree; its run folder's result.json says which
  // geometry (and material library) it was tuned on.
  const fs::path run_folder =
      fs::is_directory(arguments.source) ? arguments.source : arguments.source.parent_path();
  const fs::path tree_file =
      fs::is_directory(arguments.source) ? run_folder / "tree.json" : arguments.source;
  const fs::path result_file = run_folder / "result.json";
  if (!fs::is_regular_file(tree_file)) throw InputError(tree_file.string() + ": file not found");
  if (!fs::is_regular_file(result_file)) {
    throw InputError(
        result_file.string() +
        ": file not found; export reads the geometry from the run folder tree.json came from");
  }
  // The run's manifest, read through the declaration that wrote it
  // (spec/run_report.h): a missing or mistyped field is named by its path.
  const Properties result = Properties::load(result_file);
  const Properties inputs_where = result.object("inputs");
  const InputsRecord inputs = read_section<InputsRecord>(inputs_where);
  const GeometryRecord& geometry = inputs.geometry;
  const Properties geometry_where = inputs_where.object("geometry");
  const fs::path mesh_file = recorded_file(geometry_where, "mesh", geometry.mesh);
  const fs::path materials_file =
      arguments.materials.empty() ? recorded_file(inputs_where, "materials", inputs.materials) : arguments.materials;

  const PrinterProfile printer = PrinterProfile::load(arguments.printer);
  const MaterialLibrary library = MaterialLibrary::load(materials_file);
  const MaterialPalette palette(library, printer);
  UvSource uv = UvSource::mesh;
  try {
    uv = parse_uv_source(geometry.uv);
  } catch (const std::invalid_argument&) {
    geometry_where.fail("uv", "unknown uv source");
  }
  Solid solid(load_mesh(mesh_file, geometry.scale_to_mm, arguments.limits), uv, geometry.uv_axis);
  // Materials the tree names must be loaded in the new printer: the palette
  // says which one is missing, where, and what the printer holds.
  ReducerTree tree(Properties::load(tree_file), palette, arguments.limits);

  const int threads = arguments.threads > 0
                          ? arguments.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<size_t>(threads));
  tree.bind(solid, geometry.field_voxel_mm);
  FabricationOptions options;
  if (arguments.max_voxels > 0) options.max_voxels = static_cast<long long>(arguments.max_voxels);
  options.mesh_voxel_mm = arguments.mesh_voxel_mm;
  require_free_space(arguments.out, check_fabrication(tree, printer, options), "the print's files");

  RunFolder folder(arguments.out);
  const FabricationReport report = folder.writing([&] { return fabricate(tree, printer, options, folder); });
  if (!ranks::root()) {  // its slices are in; rank 0 writes the record
    folder.commit();
    return 0;
  }
  folder.write_json("export.json", {{"tree", tree_file.string()},
                                    {"geometry", mesh_file.string()},
                                    {"materials", materials_file.string()},
                                    {"printer", {{"name", printer.name}, {"file", printer.origin}}},
                                    {"fabrication", write_section(report.record)}});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  folder.write_json("timing.json", {{"threads", threads},
                                    {"ranks", ranks::size()},
                                    {"wall_seconds", seconds},
                                    {"fabrication_seconds", report.seconds}});
  folder.commit();
  std::cout << "wrote " << arguments.out.string()
            << "/ (export.json, print/, preview/render.png)\n";
  return 0;
}

int validate_command(const fs::path& experiment, const Limits& limits) {
  const PreparedExperiment prepared = prepare_experiment(experiment, limits);
  const Experiment& e = *prepared.experiment;
  std::cout << experiment.string() << ": ok\n"
            << "  name:       " << e.name() << "\n"
            << "  geometry:   " << e.geometry_spec().mesh.string() << " ("
            << e.solid().mesh().triangles.size() << " triangles, " << e.solid().volume()
            << " mm^3, uv " << to_string(e.solid().uv_source()) << ")\n"
            << "  printer:    " << e.printer().name << " (" << join(e.palette().names()) << ")\n"
            << "  translator: " << prepared.translator->summary() << "\n";
  if (!prepared.plan.empty()) std::cout << "  tuning:     " << prepared.plan << "\n";
  return 0;
}

namespace {

/// simulation.json's own fields; the simulator adds its sections beside them.
struct SimulationHeader {
  std::string simulator, produces, config, printer;
  nlohmann::json subtree;  ///< the subtree simulated, in the tree format
  double setup_seconds = 0, simulate_seconds = 0;
  int evaluations = 0;
  nlohmann::json values;  ///< the observation's values, or where to read them (SimulatorFiles::values_in)
  std::vector<std::string> files;
  template <class Fields, class Self>
  static void fields(Fields& f, Self& s) {
    f(s.simulator, "simulator", "the simulator");
    f(s.produces, "produces", "the observation it produces");
    f(s.config, "config", "the configuration file");
    f(s.printer, "printer", "the printer whose materials it used");
    f(s.subtree, "subtree", "the subtree simulated");
    f(s.setup_seconds, "setup_seconds", "its setup");
    f(s.simulate_seconds, "simulate_seconds", "one simulation, the mean of the evaluations");
    f(s.evaluations, "evaluations", "simulations timed");
    f(s.values, "values", "the observation's values, or the files that hold them");
    f(s.files, "files", "what the simulator wrote");
  }
};

}  // namespace

PreparedSimulation prepare_simulation(const fs::path& config_file, const std::string& simulator,
                                      const Limits& limits, const std::shared_ptr<RunCache>& session) {
  return prepare_simulation(Properties::load(config_file), simulator, limits, session);
}

PreparedSimulation prepare_simulation(const Properties& config, const std::string& simulator, const Limits& limits,
                                      const std::shared_ptr<RunCache>& session) {
  PreparedSimulation prepared;
  prepared.cache = session ? session : std::make_shared<RunCache>();
  RunCache& cache = *prepared.cache;
  const fs::path materials_file = config.existing_file("materials"), printer_file = config.existing_file("printer");
  PaletteFiles palette_files = load_palette_files(materials_file, printer_file, cache);
  prepared.library = std::move(palette_files.library);
  prepared.printer = std::move(palette_files.printer);
  prepared.palette = std::move(palette_files.palette);
  // Under mpirun every rank prepares and runs the same simulation.
  const PartContext context{*prepared.palette, prepared.cache.get(), ranks::size() > 1, &limits, prepared.printer.get()};
  const auto& simulators = SimulatorRegistry::instance();
  if (!simulators.contains(simulator)) {
    throw InputError("simulate: unknown simulator '" + simulator + "'" + did_you_mean(simulator, simulators.names()) +
                     " (known: " + join(simulators.names()) + ")");
  }
  // With a "mesh", the subtree becomes the root of a tree bound to that solid
  // (volumetric simulators need one); without, it is simulated on its own.
  if (config.has("mesh")) {
    const fs::path mesh_file = config.existing_file("mesh");
    // A session shares the solid, field and all (Experiment::load keeps only
    // the mesh): the fuzz harness prepares each input once per simulator, and
    // building a box's field each time ran its corpus at under 1 input a
    // second. A field another input asked for first may be finer or deeper
    // than this one's request; preparing only checks the band, so nothing
    // it answers depends on that.
    prepared.solid = cache.get<const Solid>(
        file_identity(mesh_file), [&] { return std::make_shared<const Solid>(load_mesh(mesh_file, 1.0, limits), UvSource::planar); });
  }
  prepared.tree = std::make_unique<ReducerTree>(config.object("subtree"), *prepared.palette, limits);
  prepared.subtree_location = config.where("subtree");
  if (prepared.solid) prepared.tree->bind(*prepared.solid);
  const auto options = config.optional_object("simulator");
  const Properties no_options = Properties::wrap(nlohmann::json::object(), config.origin() + " (simulator)");
  prepared.simulator = simulators.create_named(simulator, options ? *options : no_options, "simulator", context);
  config.check_all_read();
  return prepared;
}

double set_up(PreparedSimulation& prepared) {
  const auto start = std::chrono::steady_clock::now();
  const ReducerNode& subtree = prepared.tree->root();
  prepared.simulator->setup(subtree, prepared.solid ? SimulationDomain(*prepared.tree, subtree) : SimulationDomain());
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void simulate_checked(PreparedSimulation& prepared, Observation& out) {
  Simulator& simulator = *prepared.simulator;
  simulator.simulate(prepared.tree->root(), out);
  // The config is all the simulator was given: an answer it cannot give is the config's problem.
  for (double v : out.values()) {
    if (!std::isfinite(v)) {
      const std::string why = simulator.failure();
      throw InputError(prepared.subtree_location + ": the " + simulator.name() + " simulator gives no finite answer for it" +
                       (why.empty() ? std::string() : ": " + why));
    }
  }
}

int simulate_command(const SimulateArguments& arguments) {
  PreparedSimulation prepared = prepare_simulation(arguments.config, arguments.simulator, arguments.limits);
  const MaterialPalette& palette = *prepared.palette;
  const PrinterProfile& printer = *prepared.printer;
  const ReducerNode& subtree = prepared.tree->root();
  Simulator* simulator = prepared.simulator.get();

  using Clock = std::chrono::steady_clock;
  const double setup_seconds = set_up(prepared);
  // After setup (the FEM's mesh is made), before the simulation: a disk
  // that cannot take the files is refused with the figures.
  require_free_space(arguments.out, simulator->estimated_report_bytes(), "the simulation's files");
  auto observation = simulator->make_observation();
  const auto simulate_start = Clock::now();
  int evaluations = 0;
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - simulate_start).count(); };
  // Under mpirun the ranks' solves are collective: rank 0's clock decides
  // for all of them when to stop repeating.
  const auto again = [&] {
    if (arguments.repeat > 0) return evaluations < arguments.repeat;
    const bool mine = evaluations < 100 && elapsed() < 2.0;
    return ranks::size() > 1 ? ranks::broadcast(mine ? "1" : "0") == "1" : mine;
  };
  do {
    simulate_checked(prepared, *observation);
    ++evaluations;
  } while (again());
  const double simulate_seconds = elapsed() / evaluations;

  // Under mpirun every rank holds the same answer; rank 0's folder is the
  // one kept (RunFolder).
  RunFolder folder(arguments.out);
  SimulationHeader header{simulator->name(), std::string(simulator->produces()), arguments.config.string(),
                          printer.name, subtree.to_json(palette), setup_seconds, simulate_seconds, evaluations,
                          {}, {}};
  ReportSections sections(section_keys(header));
  const std::vector<std::string> files = folder.writing([&] {
    const SimulatorFiles written = simulator->write_report(*observation, folder.path("."), sections);
    header.values = written.values_in.empty()
                        ? nlohmann::json(std::vector<double>(observation->values().begin(), observation->values().end()))
                        : nlohmann::json(written.values_in);
    header.files = written.files;
    nlohmann::json record = write_section(header);
    sections.write_into(record);
    folder.write_json("simulation.json", record);
    return written.files;
  });
  folder.commit();
  if (!ranks::root()) return 0;
  std::cout << "wrote " << arguments.out.string() << "/ (simulation.json, " << join(files)
            << "); setup " << format_seconds(setup_seconds) << ", simulate "
            << format_seconds(simulate_seconds) << " per evaluation (mean of " << evaluations
            << ")\n";
  return 0;
}

}  // namespace spec2fab::cli

// spec2fab: run, validate and inspect Spec2Fab experiments.
// Exit codes: 0 success, 2 bad input (one line saying what and where), 3 a write the system
// refused (full disk, quota, file-size limit: core/file_write.h), 1 internal error,
// 130 / 143 stopped by SIGINT / SIGTERM (core/interrupt.h).

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "commands.h"
#include "core/build_options.h"
#include "core/error.h"
#include "core/file_write.h"
#include "core/interrupt.h"
#include "core/limits.h"
#include "core/log.h"
#include "core/ranks.h"
#include "core/strings.h"
#include "core/version.h"

namespace {

using namespace spec2fab;

std::filesystem::path default_datasets() {
  if (const char* env = std::getenv("SPEC2FAB_DATASETS")) return env;
  return SPEC2FAB_DATASETS_DIR;
}

/// The command line: each command's options and help, declared in a
/// function of its own; what was given lands in the arguments structs.
struct CommandLine {
  CLI::App app{
      "spec2fab: turns a functional specification into a multi-material 3D print.\n"
      "An experiment file (JSON) names a translator and its five inputs: geometry, goal,\n"
      "simulation, materials, printer. See README.md and docs/experiment-format.md."};
  bool quiet = false, verbose = false;
  cli::RunArguments run;
  std::uint64_t seed = 0;
  CLI::Option* seed_option = nullptr;
  cli::ExportArguments export_arguments;
  cli::SimulateArguments simulate;
  cli::BenchArguments bench;
  std::filesystem::path validate_file, report_folder;
  std::vector<std::string> limit_assignments;
  std::string kind;
  bool list_verbose = false, list_markdown = false;
  std::filesystem::path datasets = default_datasets(), update_doc;
  CLI::App *run_cmd = nullptr, *export_cmd = nullptr, *simulate_cmd = nullptr, *bench_cmd = nullptr,
           *validate_cmd = nullptr, *list_cmd = nullptr, *report_cmd = nullptr;

  CommandLine() {
    app.require_subcommand(1);
    app.set_version_flag("--version",
                         std::string("spec2fab ") + version() + " (" + build_summary() + ")");
    app.add_flag("-q,--quiet", quiet, "only warnings and errors");
    app.add_flag("-v,--verbose", verbose, "debug messages");
    bench.datasets = default_datasets();
    add_run();
    add_export();
    add_simulate();
    add_bench();
    add_validate();
    add_report();
    add_limits();
    add_list();
  }

  void add_run() {
    run_cmd = app.add_subcommand("run", "run an experiment and write its run folder");
    run_cmd->add_option("experiment", run.experiment, "experiment file (JSON)")->required();
    run_cmd->add_option("--out", run.out, "output folder (default out/<experiment name>)");
    run_cmd->add_option("--threads", run.threads, "worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    seed_option = run_cmd->add_option("--seed", seed, "random seed (overrides the experiment's)");
    run_cmd->add_flag("--resume", run.resume,
                      "go on from the last tuning phase a killed run (SIGKILL, power cut) of the "
                      "same experiment, "
                      "seed and --out finished; without one, start afresh");
    run_cmd->add_flag("-q,--quiet", quiet, "only warnings and errors");
    run_cmd->add_flag("!--no-report", run.report_html,
                      "leave out report.html (write it later with `spec2fab report FOLDER`)");
    run_cmd->footer(
        "Writes <out>/report.html (open it in a browser: goal beside achieved, figures, a 3D view of the\n"
        "print), result.json (inputs, goal metrics), tree.json (the tuned tree; `export` "
        "reads it),\ntiming.json (wall time, threads), preview/*.png and print/ (slices/, "
        "<material>.stl, model.3mf).\nThe folder appears only when the run completes. The same "
        "experiment and seed give\n"
        "byte-identical files for any thread count, except timing.json (and report.html's copy of it).\n"
        "Stopped by Ctrl-C or SIGTERM, a run removes its partial folder and exits with 130 or "
        "143;\n"
        "what a killed run (SIGKILL) left is removed by the next run into the same parent folder,\n"
        "unless that run is `spec2fab run --resume` into the same --out: it continues from the "
        "killed\n"
        "run's checkpoint (saved after each tuning phase) to the files an uninterrupted run "
        "writes.");
  }

  void add_export() {
    export_cmd = app.add_subcommand("export",
                                    "re-fabricate a run's tuned tree for another printer "
                                    "(same tree, its resolution and materials)");
    export_cmd->add_option("tree", export_arguments.source, "a run folder, or the tree.json in one")
        ->required();
    export_cmd->add_option("--printer", export_arguments.printer, "printer profile (JSON)")
        ->required();
    export_cmd->add_option("--materials", export_arguments.materials,
                           "material library (default: the run's, from its result.json)");
    export_cmd->add_option("--out", export_arguments.out, "output folder")->required();
    export_cmd
        ->add_option("--threads", export_arguments.threads, "worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    export_cmd
        ->add_option("--max-voxels", export_arguments.max_voxels,
                     "refuse above this many print voxels (default 5e9)")
        ->check(CLI::PositiveNumber);
    export_cmd
        ->add_option("--mesh-voxel-mm", export_arguments.mesh_voxel_mm,
                     "cell of the STL/3MF surfaces (default: <= 128 cells along the longest side)")
        ->check(CLI::NonNegativeNumber);
    export_cmd->add_flag("-q,--quiet", quiet, "only warnings and errors");
    export_cmd->footer(
        "Reads <run>/tree.json and the geometry named in <run>/result.json; writes <out>/print/ "
        "(slices/,\n"
        "<material>.stl, model.3mf), preview/render.png and export.json. Every material the tree "
        "names\n"
        "must be loaded in the new printer.");
  }

  void add_simulate() {
    simulate_cmd = app.add_subcommand(
        "simulate", "run one simulator standalone on a subtree and write its observation");
    simulate_cmd
        ->add_option("simulator", simulate.simulator,
                     "a registered simulator (spec2fab list simulator)")
        ->required();
    simulate_cmd->add_option("config", simulate.config, "input description (JSON)")->required();
    simulate_cmd->add_option("--out", simulate.out, "output folder")->required();
    simulate_cmd
        ->add_option("--repeat", simulate.repeat,
                     "evaluations to time (default: up to 100, stopping after 2 s)")
        ->check(CLI::Range(1, 100000000));
    simulate_cmd->add_flag("-q,--quiet", quiet, "only warnings and errors");
    simulate_cmd->footer(
        "CONFIG names the run's materials and printer (the palette), the subtree to simulate and\n"
        "the simulator's options, e.g.\n"
        "  {\"materials\": \"../materials/polyjet.json\", \"printer\": \"../printers/j750.json\",\n"
        "   \"subtree\": {\"type\": \"layered\", \"layers\": [{\"material\": \"VeroCyan\", "
        "\"thickness_mm\": 0.1},\n"
        "                                       {\"material\": \"VeroWhitePlus\"}]},\n"
        "   \"simulator\": {\"depth_mm\": 2}}\n"
        "With \"mesh\": a closed surface (mm), the subtree is bound to that solid, as volumetric\n"
        "simulators need (fem: datasets/simulations/fem_cantilever.json; docs/fem.md).\n"
        "Paths are relative to CONFIG. Writes simulation.json (inputs and values) and the\n"
        "observation: PNG for images, CSV for profiles and displacements, CSV + swatch PNG for\n"
        "albedo; fem adds displacements.csv, deformed.stl and deformation.png. Prints setup and\n"
        "per-evaluation times (mean of --repeat runs).");
  }

  void add_bench() {
    bench_cmd = app.add_subcommand(
        "bench", "run every compatible optimizer on every benchmark problem and report the matrix");
    bench_cmd->add_option("--out", bench.out, "output folder")->required();
    bench_cmd
        ->add_option("--problems", bench.problems,
                     "problems to run, comma-separated (default: all; "
                     "spec2fab list bench)")
        ->delimiter(',');
    bench_cmd
        ->add_option("--optimizers", bench.optimizers,
                     "entrants to run, by label, comma-separated (default: all)")
        ->delimiter(',');
    bench_cmd->add_option(
        "--entrants", bench.entrants,
        "entrant list (JSON; default datasets/bench/entrants.json); registered optimizers it "
        "does not name join at their defaults");
    bench_cmd
        ->add_option("--seeds", bench.seeds,
                     "runs of each stochastic entrant per problem (default 15)")
        ->check(CLI::Range(1, 10000));
    bench_cmd->add_option(
        "--budget", bench.budget,
        "per run: 100d (evaluations per variable), 5000 (evaluations), 30s (seconds; makes "
        "results machine-dependent), or several joined by commas (default 100d)");
    bench_cmd->add_option("--threads", bench.threads, "worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
    bench_cmd->add_flag("--quick", bench.quick, "a smoke test: budget 12d, at most 3 seeds");
    bench_cmd->add_flag("--progress", bench.progress,
                        "show pairs and runs done and an ETA on stderr");
    bench_cmd->add_option("--datasets", bench.datasets,
                          "datasets folder (default $SPEC2FAB_DATASETS or the source tree's)");
    bench_cmd->add_flag("-q,--quiet", quiet, "only warnings and errors");
    bench_cmd->footer(
        "Writes <out>/report.md (the matrix: median final error with quartiles, success rate, ERT "
        "to a\n"
        "ladder of targets; incompatible pairs with the capability missing; the fight matrix),\n"
        "report.json, plots/ (convergence with quartile bands, runtime ECDFs, fight matrix),\n"
        "ioh/ (IOHprofiler's format: IOHanalyzer reads the folder as it is) and timing/ (wall and\n"
        "simulator seconds). Everything but timing/ is byte-identical for any --threads.\n"
        "Add a problem or optimizer: docs/benchmarking.md.");
  }

  void add_validate() {
    validate_cmd =
        app.add_subcommand("validate", "check an experiment and everything it names, run nothing");
    validate_cmd->add_option("experiment", validate_file, "experiment file (JSON)")->required();
  }

  void add_report() {
    report_cmd = app.add_subcommand("report", "write report.html again for a run folder or a bench folder");
    report_cmd->add_option("folder", report_folder, "a folder `spec2fab run` or `spec2fab bench` wrote")->required();
    report_cmd->footer(
        "report.html is one self-contained page (no network needed): what the run was for, goal beside\n"
        "achieved at full resolution, the figures with their meaning, convergence, material census,\n"
        "timings, inputs, and a 3D view of the print (material regions, the FEM's deformed shape, a\n"
        "caustic slab). Runs write it themselves unless `run --no-report`; this command rebuilds it\n"
        "from the folder's files (after `--no-report`, or for a folder an older version wrote).");
  }

  void add_limits() {
    // Resource limits (core/limits.h): the same option on every command that reads user input.
    std::string limit_help =
        "set a resource limit for this command, e.g. --limit tets=2e7 (repeatable; wins over an "
        "experiment's \"limits\"). Limits and defaults:";
    for (const LimitDoc& doc : limits::docs())
      limit_help +=
          "\n  " + doc.name + " (" + fmt::format("{:g}", doc.default_value) + "): " + doc.meaning;
    for (CLI::App* command : {run_cmd, validate_cmd, simulate_cmd, export_cmd})
      command->add_option("--limit", limit_assignments, limit_help)->type_name("NAME=VALUE");
  }

  void add_list() {
    list_cmd = app.add_subcommand(
        "list",
        "list every registered kind of part (nodes, translators, simulators, metrics, goals, "
        "optimizers, couplings, networks...) and the shipped materials and printers");
    list_cmd->add_option("kind", kind,
                         spec2fab::join(spec2fab::cli::list_kinds(), " | ") + " (default: all)");
    list_cmd->add_flag("--verbose", list_verbose, "properties, defaults and an example of each");
    list_cmd->add_flag(
        "--markdown", list_markdown,
        "every registered part with its options as Markdown (what docs/parts.md holds)");
    list_cmd->add_option(
        "--update-doc", update_doc,
        "rewrite the option tables of a Markdown file (between '<!-- options: KIND NAME -->' and "
        "'<!-- end options -->') from the code, e.g. docs/experiment-format.md");
    list_cmd->add_option("--datasets", datasets,
                         "datasets folder (default $SPEC2FAB_DATASETS or the source tree's)");
  }

  /// A first word that is no command, after any global flags (which take no
  /// value): CLI11 would only say that a command is required. Exit code 2
  /// when there is one, else 0.
  int refuse_unknown_command(int argc, char** argv) {
    int first_word = 1;
    while (first_word < argc && argv[first_word][0] == '-' &&
           app.get_option_no_throw(argv[first_word]) != nullptr &&
           argv[first_word] != std::string("--"))
      ++first_word;
    if (first_word < argc && argv[first_word][0] != '-') {
      const std::string word = argv[first_word];
      std::vector<std::string> commands;
      for (const CLI::App* command : app.get_subcommands({}))
        commands.push_back(command->get_name());
      if (std::find(commands.begin(), commands.end(), word) == commands.end()) {
        std::cerr << "error: unknown command '" << word << "'" << did_you_mean(word, commands)
                  << " (commands: " << join(commands) << "; see spec2fab --help)\n";
        return 2;
      }
    }
    return 0;
  }

  /// Runs the chosen command; its errors are main's to report.
  int dispatch() {
    if (*seed_option) run.seed = seed;
    Limits limits;
    for (const std::string& assignment : limit_assignments) limits.set_from_command_line(assignment);
    run.limits = simulate.limits = export_arguments.limits = limits;
    if (*run_cmd) return cli::run_command(run);
    if (*validate_cmd) return cli::validate_command(validate_file, limits);
    if (*report_cmd) return cli::report_command(report_folder);
    if (*bench_cmd) return cli::bench_command(bench);
    if (*simulate_cmd) return cli::simulate_command(simulate);
    if (*export_cmd) return cli::export_command(export_arguments);
    if (*list_cmd && !update_doc.empty()) {
      std::cout << update_doc.string()
                << (cli::update_option_tables(update_doc) ? ": updated\n" : ": current\n");
      return 0;
    }
    if (*list_cmd && list_markdown) {
      std::cout << cli::parts_reference();
      return 0;
    }
    if (*list_cmd) return cli::list_command(kind, list_verbose, datasets);
    return 1;
  }
};

}  // namespace

int main(int argc, char** argv) {
  interrupt::exit_cleanly_on_signals();  // before any thread starts: they inherit the blocked
                                         // signals
  // Past a file-size limit (ulimit -f) a write fails with EFBIG, which is
  // reported (exit code 3) and cleaned up, instead of the signal's core dump.
  std::signal(SIGXFSZ, SIG_IGN);
  CommandLine line;
  if (const int refused = line.refuse_unknown_command(argc, argv)) return refused;
  try {
    line.app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return line.app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return line.app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return line.app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "error: " << e.what() << " (see spec2fab --help)\n";
    return 2;
  }
  // Under mpirun only rank 0 speaks (the ranks do the same work on the same
  // inputs, so they fail alike), and only run, export and simulate split
  // their work (simulate: the FEM's gamg solves).
  ranks::start();
  const struct StopRanks {
    ~StopRanks() { ranks::stop(); }
  } stop_ranks;
  configure_logging(line.quiet || !ranks::root() ? Verbosity::quiet
                    : line.verbose               ? Verbosity::verbose
                                                 : Verbosity::normal);
  if (ranks::size() > 1 && !*line.export_cmd && !*line.run_cmd && !*line.simulate_cmd) {
    if (ranks::root())
      std::cerr << "error: under mpirun only 'spec2fab run', 'export' and 'simulate' split their "
                   "work over ranks ("
                << ranks::size() << " here); run the others as one process\n";
    return 2;
  }
  try {
    return line.dispatch();
  } catch (const InputError& e) {
    // Every rank read the same inputs and stopped at the same point.
    if (ranks::root()) std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const WriteError& e) {
    // The system refused a write (a full disk, a quota, a file-size limit):
    // the rank that met it says so; the run folder is already removed.
    std::cerr << "error: " << e.what() << "\n";
    ranks::abort_all(3);
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\n";
    ranks::abort_all(1);
    return 1;
  }
}

#pragma once
// The spec2fab subcommands; main.cpp parses arguments and maps errors to exit codes.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/limits.h"
#include "core/run_cache.h"
#include "geometry/solid.h"
#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "reducer/reducer_tree.h"
#include "tuning/parts.h"

namespace spec2fab::cli {

struct RunArguments {
  std::filesystem::path experiment, out;
  int threads = 0;
  std::optional<std::uint64_t> seed;
  bool resume = false;
  bool report_html = true;  ///< false: --no-report
  Limits limits;  ///< --limit's
};

struct ExportArguments {
  std::filesystem::path source;     ///< a run folder, or the tree.json inside one
  std::filesystem::path printer;    ///< the printer to fabricate for
  std::filesystem::path materials;  ///< material library; empty: the run's
  std::filesystem::path out;
  int threads = 0;
  double max_voxels = 0;     ///< 0: the default limit
  double mesh_voxel_mm = 0;  ///< 0: automatic
  Limits limits;             ///< --limit's
};

struct SimulateArguments {
  std::string simulator;         ///< a registered simulator
  std::filesystem::path config;  ///< materials, printer, subtree, simulator options
  std::filesystem::path out;
  int repeat = 0;  ///< evaluations timed; 0: up to 100, stopping once 2 s have passed
  Limits limits;   ///< --limit's
};

struct BenchArguments {
  std::vector<std::string> problems;    ///< empty: every registered problem
  std::vector<std::string> optimizers;  ///< entrant labels; empty: every entrant
  std::filesystem::path entrants;       ///< entrant list (JSON); empty: the shipped one
  std::filesystem::path datasets;
  std::filesystem::path out;
  int seeds = 15;
  std::string budget = "100d";
  int threads = 0;
  bool quick = false;
  bool progress = false;
};

/// What `simulate` reads from its config before any work: every part built,
/// every key checked (InputError otherwise). Members refer to each other:
/// held by pointer so that their addresses stay put.
struct PreparedSimulation {
  std::shared_ptr<const MaterialLibrary> library;
  std::shared_ptr<const PrinterProfile> printer;
  std::shared_ptr<const MaterialPalette> palette;
  std::shared_ptr<RunCache> cache;
  std::shared_ptr<const Solid> solid;  ///< null without a "mesh"
  std::unique_ptr<ReducerTree> tree;
  std::unique_ptr<Simulator> simulator;
  std::string subtree_location;  ///< "config.json: /subtree", for what the simulator makes of it
};
/// `session`: a cache kept across preparations by a process that prepares
/// many (the fuzz harness; later the Python module). It keeps the library,
/// printer, palette and solid made from each file as the file is now (its
/// path, size and modification time) and the parts' shared tables; without
/// one, everything is made afresh and lives as long as the simulation.
PreparedSimulation prepare_simulation(const std::filesystem::path& config, const std::string& simulator,
                                      const Limits& limits, const std::shared_ptr<RunCache>& session = nullptr);
/// The same for a config already parsed (a dict from the Python module).
PreparedSimulation prepare_simulation(const Properties& config, const std::string& simulator, const Limits& limits,
                                      const std::shared_ptr<RunCache>& session = nullptr);
/// The simulator's one-time setup on the prepared subtree; returns its seconds.
double set_up(PreparedSimulation& prepared);
/// One simulation of the prepared subtree into `out`; an answer that is not
/// finite is the config's problem (InputError naming its subtree).
void simulate_checked(PreparedSimulation& prepared, Observation& out);

int run_command(const RunArguments& arguments);
/// Runs the optimizer x problem matrix and writes its report (docs/benchmarking.md).
int bench_command(BenchArguments arguments);
/// Re-fabricates a run's tuned tree for another printer (device independence).
int export_command(const ExportArguments& arguments);
/// Runs one simulator standalone on a subtree and writes its observation.
int simulate_command(const SimulateArguments& arguments);
/// Writes report.html again for a run or bench folder; returns its path.
std::filesystem::path write_report(const std::filesystem::path& folder);
/// `spec2fab report FOLDER`: write_report, and a line saying so.
int report_command(const std::filesystem::path& folder);
int validate_command(const std::filesystem::path& experiment, const Limits& limits);
int list_command(const std::string& kind, bool verbose, const std::filesystem::path& datasets);
/// docs/parts.md: every registered part, its options and an example, as
/// Markdown (`list --markdown`; a test keeps the committed file current).
std::string parts_reference();
/// Rewrites, in a Markdown file, every block between
///   <!-- options: KIND NAME … -->  and  <!-- end options -->
/// with that part's option table ("experiment file" and "experiment
/// geometry" are the file's own keys) (`list --update-doc`; a test keeps
/// docs/experiment-format.md current); "KIND NAME own" leaves out the tree
/// outputs' rows that every tree-making translator shares. Returns whether
/// the file changed.
bool update_option_tables(const std::filesystem::path& file);
/// What `list` can show: every listed registry's kind, then material and printer.
std::vector<std::string> list_kinds();

}  // namespace spec2fab::cli

// mpirun -np N spec2fab run|export: each rank fabricates its share of whole
// mesh layers and writes its slices, rank 0 meshes every rank's layer counts
// in order; a run's parallel tuner phases split their colour classes over the
// ranks. The files must be those of one process, byte for byte.

#include "cli_support.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/build_options.h"

namespace spec2fab_cli_test {
namespace {

std::string mpirun(int ranks) {
  // As root in a container: Open MPI needs to be told that is fine; shared
  // memory between the ranks of this machine, no network. In the sanitizer
  // build, LeakSanitizer would report what Open MPI's plugins keep (from
  // their own threads, in modules unloaded by exit, so no suppression can
  // name them): leak checking is off for the ranks only — the same export
  // in one process, just before, is checked.
  const char* asan = std::getenv("ASAN_OPTIONS");
  const std::string options = std::string(asan ? asan : "") + (asan && *asan ? ":" : "") + "detect_leaks=0";
  return "ASAN_OPTIONS=" + options + " mpirun --allow-run-as-root --oversubscribe --mca btl self,vader -x ASAN_OPTIONS -np " +
         std::to_string(ranks) + " ";
}

TEST_F(Cli, MpiExportIsByteIdenticalToOneProcess) {
  if (!SPEC2FAB_WITH_MPI) GTEST_SKIP() << "built without MPI (SPEC2FAB_WITH_MPI=OFF)";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  // Columns of cyan layers of different depths over white: thin layers and
  // material changes in every slab.
  const std::string tree =
      R"({"type": "stratum", "depth_mm": 2, "shell": {"type": "column", "count": [3, 1], "children": [)"
      R"({"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": 0.3}], "fill": "VeroWhitePlus"},)"
      R"({"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": 1.1}], "fill": "VeroWhitePlus"},)"
      R"({"type": "layered", "material": "VeroWhitePlus"}]}, "core": {"type": "layered", "material": "VeroWhitePlus"}})";
  const fs::path file = experiment("src", valid_body(tree, R"(, "output": {"slices": false, "stl": false,
                                                                         "3mf": false, "render": false})"));
  ASSERT_EQ(run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string()).code, 0);
  std::ofstream(dir_ / "fine.json")
      << R"({"name": "fine", "technology": "fdm", "resolution_dpi": [127, 127], "layer_mm": 0.2, "nozzle_mm": 0.2,
             "build_volume_mm": [200, 200, 200], "model_materials": ["VeroCyan", "VeroWhitePlus"],
             "print_time": {"source": "test: the extrusion model's defaults"}, "source": "test"})";
  // 250 layers in mesh layers of 4 (0.8 mm): 63, split 32 + 31 and 21 x 3.
  // An extruding printer: the print estimate's raster census is merged
  // across the ranks (export.json's fabrication.print must match too).
  const std::string arguments = "export -q " + (dir_ / "run").string() + " --printer " + (dir_ / "fine.json").string() +
                                " --mesh-voxel-mm 0.8 --out ";
  const Result one = run_spec2fab(arguments + (dir_ / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const std::map<std::string, std::string> expected = files_of(dir_ / "one");
  ASSERT_GT(expected.size(), 250u);  // the slices, manifest, STLs, render, export.json
  for (int ranks : {2, 3}) {
    const fs::path out = dir_ / ("ranks" + std::to_string(ranks));
    const Result r = run_command(mpirun(ranks) + SPEC2FAB_CLI_PATH + " " + arguments + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    expect_same_files(expected, out, "with " + std::to_string(ranks) + " ranks");
    EXPECT_THAT(read(out / "timing.json"), HasSubstr("\"ranks\": " + std::to_string(ranks)));
    // Nothing left beside the folder: no rank's staging folder.
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr("partial")));
  }
}

TEST_F(Cli, MpiRunSplitsTunersAndSlicesAndIsByteIdenticalToOneProcess) {
  if (!SPEC2FAB_WITH_MPI) GTEST_SKIP() << "built without MPI (SPEC2FAB_WITH_MPI=OFF)";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  // The subsurface chessboard: one parallel phase of 3 x 2 independent
  // column tuners (branch and bound), then fabrication with slices and STLs.
  const std::string body =
      R"({"name": "board", "translator": "subsurface",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"media": ["marble", "skimmilk"], "columns": [3, 2], "layers": 2,
                   "materials": ["VeroWhitePlus", "VeroCyan"], "thickness_steps": [1, 2],
                   "radius_mm": 8, "samples": 64},
          "output": {"3mf": false, "render": false},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "coarse_printer.json").string() + R"("})";
  const std::string arguments = "run -q " + experiment("board", body).string() + " --out ";
  const Result one = run_spec2fab(arguments + (dir_ / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const std::map<std::string, std::string> expected = files_of(dir_ / "one");
  ASSERT_GT(expected.size(), 20u);  // result, tree, previews, slices, manifest, STLs
  for (int ranks : {2, 3}) {
    const fs::path out = dir_ / ("ranks" + std::to_string(ranks));
    const Result r = run_command(mpirun(ranks) + SPEC2FAB_CLI_PATH + " " + arguments + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    expect_same_files(expected, out, "with " + std::to_string(ranks) + " ranks");
    // Every rank tuned its share of the six columns.
    const auto timing = nlohmann::json::parse(read(out / "timing.json"));
    EXPECT_EQ(timing["ranks"], ranks);
    const auto per_rank = timing["tuner_runs_per_rank"].get<std::vector<long long>>();
    ASSERT_EQ(per_rank.size(), static_cast<size_t>(ranks));
    long long total = 0;
    for (long long runs : per_rank) {
      EXPECT_GT(runs, 0) << timing.dump();
      total += runs;
    }
    EXPECT_EQ(total, 6);
    for (const auto& entry : fs::directory_iterator(dir_))
      EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr("partial")));
  }
}

// Node displacements of a simulate folder's displacements.csv, by node.
std::vector<double> node_displacements(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<double> u;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string field;
    for (int column = 0; std::getline(fields, field, ','); ++column)
      if (column >= 4) u.push_back(std::stod(field));
  }
  return u;
}

double largest_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return worst;
}

double largest(const std::vector<double>& a) {
  double worst = 0;
  for (double v : a) worst = std::max(worst, std::abs(v));
  return worst;
}

// mpirun -np N spec2fab simulate fem with the gamg solver: the mesh is split
// along its nodes' Morton curve and PETSc's CG + GAMG solve across the
// ranks; the displacements are one process's within 1e-8 of the largest
// (and CHOLMOD's within 1e-7: the CG stops at a relative residual of 1e-10).
TEST_F(Cli, MpiSimulateFemSpreadsItsSolveOverTheRanks) {
  if (!SPEC2FAB_WITH_MPI || !SPEC2FAB_WITH_PETSC || !SPEC2FAB_WITH_TETGEN)
    GTEST_SKIP() << "needs MPI, PETSc and TetGen in the build";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  // A rigid beam with a rubber-like piece from x = 40 to 70 mm (E 2500 :
  // 3.6 MPa, VeroWhitePlus : DM9860), clamped at one end, pulled down and
  // sideways at the other.
  auto config = [&](const std::string& solver) {
    return R"({"materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
      "printer": ")" + (kDatasets / "printers/objet500_connex_flex.json").string() + R"(",
      "mesh": ")" + (kDatasets / "meshes/beam_100x10x10.stl").string() + R"(",
      "subtree": {"type": "plane", "axis": "x", "offset_mm": 40,
        "below": {"type": "layered", "material": "VeroWhitePlus"},
        "above": {"type": "plane", "axis": "x", "offset_mm": 70,
          "below": {"type": "layered", "material": "DM9860"},
          "above": {"type": "layered", "material": "VeroWhitePlus"}}},
      "simulator": {"max_tet_volume_mm3": 2, "nonlinear": false, "linear_solver": ")" + solver + R"(",
        "fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}],
        "loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 1, -5]}],
        "probes": [[100, 5, 5]]}})";
  };
  const fs::path direct = experiment("direct", config("cholesky")), gamg = experiment("gamg", config("gamg"));
  ASSERT_EQ(run_spec2fab("simulate fem -q " + direct.string() + " --repeat 1 --out " + (dir_ / "direct").string()).code, 0);
  const Result one = run_spec2fab("simulate fem -q " + gamg.string() + " --repeat 1 --out " + (dir_ / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const std::vector<double> exact = node_displacements(dir_ / "direct" / "displacements.csv");
  const std::vector<double> serial = node_displacements(dir_ / "one" / "displacements.csv");
  ASSERT_GT(exact.size(), 3000u);
  ASSERT_EQ(serial.size(), exact.size());
  EXPECT_LT(largest_difference(serial, exact), 1e-7 * largest(exact));
  for (int ranks : {2, 3}) {
    const fs::path out = dir_ / ("ranks" + std::to_string(ranks));
    // (timeout: a collective call that one rank skips would hang its ranks)
    const Result r = run_command(mpirun(ranks) + "timeout 300 " + SPEC2FAB_CLI_PATH + " simulate fem -q " + gamg.string() +
                                 " --repeat 1 --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.out;
    const std::vector<double> spread = node_displacements(out / "displacements.csv");
    ASSERT_EQ(spread.size(), serial.size());
    const double difference = largest_difference(spread, serial) / largest(serial);
    std::printf("%d ranks: largest difference from one process %.2e of the largest displacement\n", ranks, difference);
    EXPECT_LT(difference, 1e-8) << ranks << " ranks";
    const auto record = nlohmann::json::parse(read(out / "simulation.json"));
    EXPECT_EQ(record["solve"]["ranks"], ranks);
    EXPECT_EQ(record["solve"]["linear_solver"], "gamg");
    // Each rank assembles its own rows: rank 0 about 1/ranks of the tets
    // (those touching its nodes) and of the stiffness's entries.
    const auto whole = nlohmann::json::parse(read(dir_ / "one" / "simulation.json"));
    const double tets = whole["mesh"]["tets"], entries = whole["solve"]["stiffness_entries"];
    EXPECT_EQ(whole["solve"]["assembled_tets"], whole["mesh"]["tets"]);
    EXPECT_LT(record["solve"]["assembled_tets"].get<double>(), tets * (1.3 / ranks)) << ranks << " ranks";
    EXPECT_LT(record["solve"]["stiffness_entries"].get<double>(), entries * (1.3 / ranks)) << ranks << " ranks";
    EXPECT_GT(record["solve"]["assembled_tets"].get<double>(), tets * (0.7 / ranks)) << ranks << " ranks";
  }
}

// mpirun -np 3 spec2fab run with two FEM tuners on the gamg solver. PETSc
// lives on each rank alone (its initialisation is collective on its world);
// the files are one process's, byte for byte. The phase is serial: an FEM
// tuner reads the whole tree, so two may not share a parallel phase
// (Cli.FemTunersMayNotRunInParallel), and every rank runs both.
TEST_F(Cli, MpiRunWithGamgTunersIsByteIdenticalToOneProcess) {
  if (!SPEC2FAB_WITH_MPI || !SPEC2FAB_WITH_PETSC || !SPEC2FAB_WITH_TETGEN)
    GTEST_SKIP() << "needs MPI, PETSc and TetGen in the build";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  const std::string body =
      two_fem_tuners_body("serial", "gamg", R"({"slices": false, "stl": false, "3mf": false, "render": false})");
  const std::string arguments = "run -q --threads 1 " + experiment("two_fem_tuners", body).string() + " --out ";
  const Result one = run_spec2fab(arguments + (dir_ / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const std::map<std::string, std::string> expected = files_of(dir_ / "one");
  const fs::path out = dir_ / "ranks3";
  const Result r = run_command(mpirun(3) + "timeout 300 " + SPEC2FAB_CLI_PATH + " " + arguments + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  expect_same_files(expected, out, "with 3 ranks");
  const auto timing = nlohmann::json::parse(read(out / "timing.json"));
  // FEM tuners read the whole tree, so they may not share a parallel phase
  // (Cli.FemTunersMayNotRunInParallel): every rank runs the serial phase.
  EXPECT_EQ(timing["tuner_runs_per_rank"], nlohmann::json::array({2, 2, 2})) << timing.dump();
}

// With "spread_over_ranks": true an FEM tuner of a run spreads each solve
// over the ranks, as `simulate` does: every rank runs the serial phase, and
// each assembles its own rows. The outputs then match one process to
// rounding, not byte for byte (the ground rule holds where the experiment
// does not ask for this); the tuned tree is the same. A parallel phase, which
// gives each tuner to one rank, is refused for such a tuner, and so is the
// option with a solver that cannot spread.
TEST_F(Cli, MpiRunSpreadsFemSolvesOverTheRanksWhereTold) {
  if (!SPEC2FAB_WITH_MPI || !SPEC2FAB_WITH_PETSC || !SPEC2FAB_WITH_TETGEN)
    GTEST_SKIP() << "needs MPI, PETSc and TetGen in the build";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  auto spread = [](std::string body) {
    const std::string solver = R"("linear_solver": "gamg",)";
    for (size_t at = body.find(solver); at != std::string::npos; at = body.find(solver, at + 1))
      body.insert(at + solver.size(), R"( "spread_over_ranks": true,)");
    return body;
  };
  const std::string output = R"({"slices": false, "stl": false, "3mf": false, "render": false})";
  const fs::path file = experiment("spread", spread(two_fem_tuners_body("serial", "gamg", output)));
  const Result one = run_spec2fab("run -q --threads 1 " + file.string() + " --out " + (dir_ / "one").string());
  ASSERT_EQ(one.code, 0) << one.out;
  const fs::path out = dir_ / "ranks2";
  const Result r = run_command(mpirun(2) + "timeout 300 " + SPEC2FAB_CLI_PATH + " run --threads 1 " + file.string() +
                               " --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.out;
  // Rank 0 says it assembles part of each tuner's mesh.
  EXPECT_THAT(r.out, HasSubstr("/goal/tuners/0/simulator: each solve spread over 2 ranks, this one assembling"));
  EXPECT_THAT(r.out, HasSubstr("/goal/tuners/1/simulator: each solve spread over 2 ranks, this one assembling"));
  EXPECT_EQ(read(out / "tree.json"), read(dir_ / "one" / "tree.json"));
  const auto alone = nlohmann::json::parse(read(dir_ / "one" / "result.json"));
  const auto spread_out = nlohmann::json::parse(read(out / "result.json"));
  const auto& runs = alone["tuning"]["tuner_runs"];
  ASSERT_EQ(runs.size(), 2u);
  for (size_t k = 0; k < runs.size(); ++k) {
    const double expected = runs[k]["final_error"], got = spread_out["tuning"]["tuner_runs"][k]["final_error"];
    EXPECT_NEAR(got, expected, 1e-8 * expected) << "tuner run " << k;
  }

  // A gamg tuner that does not spread, set up first, starts PETSc on each
  // rank alone: the one after it cannot spread, and the log says why.
  std::string mixed = two_fem_tuners_body("serial", "gamg", output);
  const std::string far = R"("name": "far")";
  mixed = mixed.substr(0, mixed.find(far)) + spread(mixed.substr(mixed.find(far)));
  const Result alone_first = run_command(mpirun(2) + "timeout 300 " + SPEC2FAB_CLI_PATH + " run --threads 1 " +
                                         experiment("mixed", mixed).string() + " --out " + (dir_ / "mixed").string());
  ASSERT_EQ(alone_first.code, 0) << alone_first.out;
  EXPECT_THAT(alone_first.out, HasSubstr("/goal/tuners/1/simulator: spread_over_ranks, but each rank solves alone"));

  const fs::path parallel = experiment("spread_parallel", spread(two_fem_tuners_body("parallel", "gamg", output)));
  const Result refused = run_spec2fab("-q validate " + parallel.string());
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_THAT(single_line(refused.out),
              HasSubstr("/goal/schedule/0/mode: tuner 'near' cannot run in a parallel phase: its fem simulator "
                        "spreads each solve over the MPI ranks (spread_over_ranks)"));
  std::string cholesky = spread(two_fem_tuners_body("serial", "gamg", output));
  for (size_t at = cholesky.find("\"gamg\""); at != std::string::npos; at = cholesky.find("\"gamg\"", at))
    cholesky.replace(at, 6, "\"cholesky\"");
  const Result wrong_solver = run_spec2fab("-q validate " + experiment("spread_cholesky", cholesky).string());
  EXPECT_EQ(wrong_solver.code, 2) << wrong_solver.out;
  EXPECT_THAT(single_line(wrong_solver.out),
              HasSubstr("/goal/tuners/0/simulator/spread_over_ranks: only the linear solver \"gamg\" spreads"));
}

TEST_F(Cli, UnderMpirunOnlyRunExportAndSimulateSplitTheirWork) {
  if (!SPEC2FAB_WITH_MPI) GTEST_SKIP() << "built without MPI (SPEC2FAB_WITH_MPI=OFF)";
  if (run_command("command -v mpirun").code != 0) GTEST_SKIP() << "mpirun not installed";
  const fs::path file = experiment("src", valid_body(R"({"type": "layered", "material": "VeroCyan"})"));
  const Result r = run_command(mpirun(2) + SPEC2FAB_CLI_PATH + " validate " + file.string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("only 'spec2fab run', 'export' and 'simulate' split their work over ranks"));
}

}  // namespace
}  // namespace spec2fab_cli_test

// The spec2fab command as users run it: exit codes, one-line errors, no
// partial output, byte-identical results for any thread count.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/sanitizer.h"
#include "build_gates.h"
#include "cli_support.h"

namespace {

using namespace spec2fab_cli_test;

const char* kTree =
    R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}})";

TEST_F(Cli, HelpAnswersForEveryCommand) {
  for (const char* command :
       {"--help", "run --help", "validate --help", "list --help", "export --help",
        "simulate --help"}) {
    const Result r = run_spec2fab(command);
    EXPECT_EQ(r.code, 0) << command;
    EXPECT_THAT(r.out, HasSubstr("Usage")) << command;
  }
}

// Every shipped experiment validates; in a build without a part one of them
// names, it is refused in one line saying which build option left it out.
// Under ASan the four photo-scale albedo experiments (one translator, two
// meshes, two images) take 30-76 s each to validate, most of the build's
// test time: there the smallest of them stands for all four.
#if SPEC2FAB_ASAN
const std::set<std::string> kLeftToReleaseBuild = {"earth_sphere.json", "earth_torus.json", "photo_sphere.json"};
#else
const std::set<std::string> kLeftToReleaseBuild;
#endif

TEST_F(Cli, ValidateAcceptsShippedExperiments) {
  int accepted = 0, left = 0;
  for (const auto& entry : fs::directory_iterator(kDatasets / "experiments")) {
    if (kLeftToReleaseBuild.count(entry.path().filename().string())) {
      ++left;
      continue;
    }
    const Result r = run_spec2fab("validate " + entry.path().string());
    if (r.code == 2 && r.out.find("is left out of this build: configure with -DSPEC2FAB_WITH_") != std::string::npos)
      continue;
    EXPECT_EQ(r.code, 0) << entry.path() << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr(": ok"));
    ++accepted;
  }
  if (SPEC2FAB_WITH_CERES && SPEC2FAB_WITH_NLOPT && SPEC2FAB_WITH_LIB3MF && SPEC2FAB_WITH_TETGEN && SPEC2FAB_WITH_HYPRE && SPEC2FAB_WITH_PETSC) {
    EXPECT_EQ(accepted + left, std::distance(fs::directory_iterator(kDatasets / "experiments"), fs::directory_iterator()));
    EXPECT_EQ(left, static_cast<int>(kLeftToReleaseBuild.size()));
  } else {
    EXPECT_GE(accepted, 1);
  }
}

// The version is written once, in CMakeLists.txt's project(); the optional
// modules this build has follow it.
TEST_F(Cli, VersionIsTheProjectsVersion) {
  const Result r = run_spec2fab("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(single_line(r.out), "spec2fab " SPEC2FAB_PROJECT_VERSION " (" + ::spec2fab::build_summary() + ")\n");
  EXPECT_THAT(r.out, HasSubstr(SPEC2FAB_WITH_NLOPT ? "NLopt," : "NLopt (SPEC2FAB_WITH_NLOPT=OFF)"));
}

TEST_F(Cli, ListShowsNodesTranslatorsMaterialsAndPrinters) {
  const Result r = run_spec2fab("list");
  EXPECT_EQ(r.code, 0);
  for (const char* name : {"stratum", "column", "voxel", "bspline", "plane", "layered", "tree",
                           "albedo", "ciede2000", "rgb_mse", "annealing", "branch_and_bound",
                           "VeroCyan", "objet500_connex.json", "j750.json"}) {
    EXPECT_THAT(r.out, HasSubstr(name));
  }
  EXPECT_EQ(r.out.find("  nlopt ") != std::string::npos, SPEC2FAB_WITH_NLOPT);
  // One line per type: the name, then the summary's whole first sentence,
  // in one column per section however long the names.
  std::istringstream lines(r.out);
  std::string line, section;
  std::map<std::string, size_t> summary_column;
  std::map<std::string, std::string> first;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == ':' && line[0] != ' ') section = line;
    if (line.rfind("  ", 0) != 0 || line.rfind("   ", 0) == 0 || section.rfind("materials", 0) == 0) continue;
    const size_t name_end = line.find(' ', 2);
    const size_t summary = line.find_first_not_of(' ', name_end);
    ASSERT_NE(summary, std::string::npos) << line;
    EXPECT_GE(summary - name_end, 2u) << "a name runs into its summary: " << line;
    const auto [at, fresh] = summary_column.emplace(section, summary);
    EXPECT_EQ(at->second, summary) << "misaligned in " << section << ": " << line;
    first[section + line.substr(2, name_end - 2)] = line.substr(summary);
  }
  EXPECT_EQ(first["translators:albedo"].substr(0, 39), "Spatially varying albedo (paper Fig. 7)");
  EXPECT_EQ(first["translators:caustics_texture"].back(), '.');
  EXPECT_THAT(first["translators:caustics_texture"], HasSubstr("(paper Fig. 1 right, Fig. 11)"));
  EXPECT_THAT(first["goals:radial_profile"], HasSubstr("(Jensen et al. 2001's dipole)."));
  for (const char* name : {"optimizers:annealing", "optimizers:spsa", "metrics:image_mse",
                           "goals:caustic_image", "goals:values"}) {
    EXPECT_GT(first[name].size(), 20u) << name << " has no summary";
  }
  if (SPEC2FAB_WITH_CERES) {
    EXPECT_GT(first["optimizers:ceres"].size(), 20u);
  }
  if (SPEC2FAB_WITH_NLOPT) {
    EXPECT_GT(first["optimizers:nlopt"].size(), 20u);
  }
  const Result verbose = run_spec2fab("list node --verbose");
  EXPECT_THAT(verbose.out, HasSubstr("depth_mm"));
  const Result optimizers = run_spec2fab("list optimizer --verbose");
  EXPECT_THAT(optimizers.out, HasSubstr("max_candidates"));
  // Each type's properties in columns, however long a name (schedule_iterations).
  std::istringstream rows(optimizers.out);
  std::string row;
  size_t default_column = 0;
  int property_rows = 0;
  while (std::getline(rows, row)) {
    if (row.rfind("  ", 0) == 0 && row.size() > 2 && row[2] != ' ') default_column = 0;  // the next type
    if (row.rfind("      ", 0) != 0) continue;
    const size_t at = row.find("  default ");
    ASSERT_NE(at, std::string::npos) << row;
    if (default_column == 0) default_column = at;
    EXPECT_EQ(at, default_column) << "misaligned: " << row;
    ++property_rows;
  }
  EXPECT_GE(property_rows, 10);
  EXPECT_THAT(verbose.out, HasSubstr("example:"));
  EXPECT_EQ(run_spec2fab("list nodez").code, 2);
  const Result bad_flag = run_spec2fab("run --threads 0 x.json");
  EXPECT_EQ(bad_flag.code, 2);
  EXPECT_THAT(single_line(bad_flag.out), StartsWith("error: "));
}

TEST_F(Cli, BadInputIsOneLineAndExitCodeTwo) {
  struct Case {
    std::string body, expected;
  };
  const std::vector<Case> cases = {
      {"{\"translator\": \"tree\",", "malformed JSON"},
      {valid_body(kTree, R"(, "sede": 3)"), "/sede: unknown key; did you mean 'seed'?"},
      {valid_body(R"({"type": "stratm", "shell": {}, "core": {}})"),
       "/goal/tree/type: unknown node 'stratm'; did you mean 'stratum'?"},
      {valid_body(kTree).replace(valid_body(kTree).find("sphere_r25.obj"), 14, "missing.obj"),
       "/geometry/mesh: file not found"},
      {valid_body(R"({"type": "layered", "material": "VeroMagenta"})"),
       "/goal/tree/material: material 'VeroMagenta' is not loaded in printer"},
      {valid_body(kTree, "", "albedoo"),
       "/translator: unknown translator 'albedoo'; did you mean 'albedo'?"},
      {valid_body(kTree, R"(, "seed": 1e999)"), "malformed JSON: number overflow parsing '1e999'"},
      {valid_body(R"({"type": "column", "count": [4294967297, 1], "child": {"type": "layered", "material": "VeroCyan"}})"),
       "/goal/tree/count: expected an array of 2 integers, got [4294967297,1] (beyond ±2147483647)"},
  };
  for (const Case& c : cases) {
    const fs::path file = experiment("bad", c.body);
    for (const std::string& command :
         {"validate " + file.string(),
          "run " + file.string() + " --out " + (dir_ / "out").string()}) {
      const Result r = run_spec2fab(command);
      EXPECT_EQ(r.code, 2) << r.out;
      EXPECT_THAT(single_line(r.out), StartsWith("error: " + file.string()));
      EXPECT_THAT(r.out, HasSubstr(c.expected));
    }
    EXPECT_FALSE(fs::exists(dir_ / "out"));
  }
}

TEST_F(Cli, OpenMeshIsRejectedWithItsDefect) {
  const fs::path mesh = dir_ / "open.obj";
  // A tetrahedron with one face missing: 3 boundary edges.
  std::ofstream(mesh) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n";
  std::string body = valid_body(kTree);
  body.replace(body.find((kDatasets / "meshes/sphere_r25.obj").string()),
               (kDatasets / "meshes/sphere_r25.obj").string().size(), mesh.string());
  const Result r = run_spec2fab("validate " + experiment("open", body).string());
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(single_line(r.out), HasSubstr("open.obj: not closed: 3 boundary edges"));
}

// Assimp runs in spec2fab-read-mesh, a program of its own (not a fork of a
// process with threads, which hung once in CI). Stand-ins for it, named by
// SPEC2FAB_MESH_READER, show that a reader that dies or hangs is a refusal
// naming the file, and that a variable naming no program is said so.
TEST_F(Cli, TheMeshReaderIsAProgramWhoseCrashOrHangIsARefusal) {
  const fs::path sphere = kDatasets / "meshes/sphere_r25.obj";
  const std::string validate = " " + std::string(SPEC2FAB_CLI_PATH) + " validate " +
                               experiment("e", valid_body(kTree)).string();
  // The program itself, named: the mesh is read (without the variable a
  // missing program would fall back to a fork and pass unseen).
  const fs::path reader = fs::path(SPEC2FAB_CLI_PATH).parent_path() / "spec2fab-read-mesh";
  const Result fine = run_command("SPEC2FAB_MESH_READER=" + reader.string() + validate);
  EXPECT_EQ(fine.code, 0) << fine.out;

  std::ofstream(dir_ / "crash.sh") << "#!/bin/sh\nkill -SEGV $$\n";
  std::ofstream(dir_ / "hang.sh") << "#!/bin/sh\nexec sleep 30\n";
  std::ofstream(dir_ / "broken.sh") << "#!/bin/sh\nexit 127\n";  // what ld.so says of a missing library
  for (const char* script : {"crash.sh", "hang.sh", "broken.sh"})
    fs::permissions(dir_ / script, fs::perms::owner_all);
  const Result broken = run_command("SPEC2FAB_MESH_READER=" + (dir_ / "broken.sh").string() + validate);
  EXPECT_EQ(broken.code, 2);
  EXPECT_THAT(single_line(broken.out), HasSubstr(": cannot read mesh: the mesh reader " + (dir_ / "broken.sh").string() +
                                                 " exited with status 127 (a broken install?"));
  const Result crashed = run_command("SPEC2FAB_MESH_READER=" + (dir_ / "crash.sh").string() + validate);
  EXPECT_EQ(crashed.code, 2);
  EXPECT_THAT(single_line(crashed.out),
              HasSubstr(sphere.string() + ": cannot read mesh: the mesh reader (Assimp) crashed on it (Segmentation fault)"));
  const Result hung =
      run_command("SPEC2FAB_MESH_READER=" + (dir_ / "hang.sh").string() + validate + " --limit mesh_read_seconds=0.5");
  EXPECT_EQ(hung.code, 2);
  EXPECT_THAT(single_line(hung.out), HasSubstr(sphere.string() + ": cannot read mesh: the mesh reader (Assimp) did not finish in 0.5 s"));
  const Result missing = run_command("SPEC2FAB_MESH_READER=" + (dir_ / "none").string() + validate);
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(single_line(missing.out), HasSubstr("SPEC2FAB_MESH_READER=" + (dir_ / "none").string() + ": not an executable file"));
}

// docs/parts.md is what the registries declare, regenerated, byte for byte.
TEST_F(Cli, PartsReferenceInDocsIsCurrent) {
  // docs/parts.md documents the full build.
  if (!(SPEC2FAB_WITH_CERES && SPEC2FAB_WITH_NLOPT && SPEC2FAB_WITH_LIB3MF && SPEC2FAB_WITH_TETGEN && SPEC2FAB_WITH_HYPRE && SPEC2FAB_WITH_PETSC))
    GTEST_SKIP() << "an optional module is off in this build";
  const Result r = run_spec2fab("list --markdown");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("\n### texture_shadow\n"));
  EXPECT_THAT(r.out, HasSubstr("| `output.png_compression` | integer in [0, 9] | 1 |"));
  EXPECT_TRUE(r.out == read(kDatasets / "../docs/parts.md"))
      << "docs/parts.md is stale: regenerate it with `build/spec2fab list --markdown > docs/parts.md`";
}

// docs/run-report.md's table of result.json's shared sections is the
// declarations', regenerated on a copy.
TEST_F(Cli, RunReportTableIsCurrent) {
  const fs::path original = kDatasets / "../docs/run-report.md";
  const fs::path copy = dir_ / "run-report.md";
  fs::copy_file(original, copy);
  const Result r = run_spec2fab("list --update-doc " + copy.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr(": current"))
      << "docs/run-report.md is stale: `build/spec2fab list --update-doc docs/run-report.md`";
  EXPECT_THAT(read(copy), HasSubstr("| `inputs.geometry.scale_to_mm` | number |"));
}

// The option tables of docs/experiment-format.md are the code's, regenerated
// on a copy: nothing changes.
TEST_F(Cli, OptionTablesInExperimentFormatAreCurrent) {
  if (!(SPEC2FAB_WITH_CERES && SPEC2FAB_WITH_NLOPT && SPEC2FAB_WITH_LIB3MF && SPEC2FAB_WITH_TETGEN && SPEC2FAB_WITH_HYPRE && SPEC2FAB_WITH_PETSC))
    GTEST_SKIP() << "an optional module is off in this build";
  const fs::path original = kDatasets / "../docs/experiment-format.md";
  const fs::path copy = dir_ / "experiment-format.md";
  fs::copy_file(original, copy);
  const Result r = run_spec2fab("list --update-doc " + copy.string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr(": current"))
      << "docs/experiment-format.md is stale: `build/spec2fab list --update-doc docs/experiment-format.md`";
  EXPECT_EQ(read(copy), read(original));

  // A changed table is put back, between its markers only.
  std::string text = read(copy);
  const size_t row = text.find("| `goal.facets` |");
  ASSERT_NE(row, std::string::npos);
  text.insert(row, "| `goal.stale` | number | 1 | gone |\n");
  std::ofstream(copy) << text;
  EXPECT_THAT(run_spec2fab("list --update-doc " + copy.string()).out, HasSubstr(": updated"));
  EXPECT_EQ(read(copy), read(original));

  // A marker naming no part is an input error.
  std::ofstream(copy) << "<!-- options: translator nonesuch -->\n<!-- end options -->\n";
  const Result bad = run_spec2fab("list --update-doc " + copy.string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.out, HasSubstr("no translator 'nonesuch' in this build"));
}

TEST_F(Cli, RunWritesFolderIdenticalForAnyThreadCount) {
  const fs::path file = experiment("det", valid_body(kTree));
  const Result one =
      run_spec2fab("run -q " + file.string() + " --threads 1 --out " + (dir_ / "t1").string());
  const Result two =
      run_spec2fab("run -q " + file.string() + " --threads 2 --out " + (dir_ / "t2").string());
  ASSERT_EQ(one.code, 0) << one.out;
  ASSERT_EQ(two.code, 0) << two.out;
  int compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "t1")) {
    if (!entry.is_regular_file() || entry.path().filename() == "timing.json") continue;
    const fs::path other = dir_ / "t2" / fs::relative(entry.path(), dir_ / "t1");
    if (entry.path().filename() == "report.html") {
      EXPECT_EQ(without_timing_block(read(entry.path())), without_timing_block(read(other)));
    } else {
      EXPECT_EQ(read(entry.path()), read(other)) << entry.path();
    }
    ++compared;
  }
  EXPECT_GE(compared, 6);  // report.html, result.json, tree.json, three previews
  // ... and the print: slices, manifest, one STL per material, the 3MF, the render.
  for (const char* file :
       {"print/slices/manifest.json", "print/slices/slice_00000.png", "print/VeroCyan.stl",
        "print/VeroWhitePlus.stl", "preview/render.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ / "t1" / file)) << file;
  }
  EXPECT_EQ(fs::is_regular_file(dir_ / "t1" / "print/model.3mf"), SPEC2FAB_WITH_LIB3MF);
  // No staging folder is left behind.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr("partial")));
  }
}

TEST_F(Cli, SeedsAreExactWholeNumbersUpTo2To64) {
  // 2^53 + 1 and 2^64 - 1: a seed read as a double (as it was) rounds both.
  for (const char* seed : {"9007199254740993", "18446744073709551615"}) {
    const fs::path file = experiment("seed", valid_body(kTree, std::string(R"(, "seed": )") + seed));
    const fs::path out = dir_ / (std::string("seed_") + seed);
    const Result run = run_spec2fab("run -q " + file.string() + " --out " + out.string());
    ASSERT_EQ(run.code, 0) << run.out;
    EXPECT_THAT(read(out / "result.json"), HasSubstr(std::string("\"seed\": ") + seed));
  }
  const fs::path rounded = experiment("rounded", valid_body(kTree, R"(, "seed": 1e19)"));
  EXPECT_THAT(single_line(run_spec2fab("validate " + rounded.string()).out),
              HasSubstr("/seed: expected a whole number from 0 to 18446744073709551615, got 1e+19"));
}

TEST_F(Cli, TreeJsonRunsAgainAsAGoal) {
  // tree.json is a tree in the experiment format: feeding it back gives the same tree.
  const fs::path first = experiment("first", valid_body(kTree));
  ASSERT_EQ(run_spec2fab("run -q " + first.string() + " --out " + (dir_ / "a").string()).code, 0);
  const std::string tree = read(dir_ / "a" / "tree.json");
  const fs::path second = experiment("second", valid_body(tree));
  ASSERT_EQ(run_spec2fab("run -q " + second.string() + " --out " + (dir_ / "b").string()).code, 0);
  EXPECT_EQ(read(dir_ / "b" / "tree.json"), tree);
}

TEST_F(Cli, OversizedPrintIsRefusedBeforeAnyWork) {
  const fs::path file = experiment("big", valid_body(kTree, R"(, "output": {"max_voxels": 1000})"));
  for (const std::string& command :
       {"validate " + file.string(),
        "run " + file.string() + " --out " + (dir_ / "out").string()}) {
    const Result r = run_spec2fab(command);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_THAT(single_line(r.out), HasSubstr("raise output.max_voxels"));
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  // Without print files there is nothing to refuse.
  const fs::path off = experiment(
      "off",
      valid_body(kTree,
                 R"(, "output": {"max_voxels": 1000, "slices": false, "stl": false, "3mf": false,
                                               "render": false})"));
  const Result r = run_spec2fab("run -q " + off.string() + " --out " + (dir_ / "off").string());
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "off" / "print"));
}

TEST_F(Cli, ExportRefabricatesATreeForAnotherPrinter) {
  const fs::path file = experiment("src", valid_body(kTree));
  ASSERT_EQ(run_spec2fab("run -q " + file.string() + " --out " + (dir_ / "run").string()).code, 0);
  // Another printer: finer voxels, a third material loaded, another order.
  std::ofstream(dir_ / "other.json")
      << R"({"name": "other", "technology": "polyjet", "resolution_dpi": [84.67, 84.67], "layer_mm": 0.3,
             "build_volume_mm": [200, 200, 200], "model_materials": ["VeroYellow", "VeroWhitePlus", "VeroCyan"],
             "source": "test"})";
  const Result r =
      run_spec2fab("export -q " + (dir_ / "run" / "tree.json").string() + " --printer " +
               (dir_ / "other.json").string() + " --out " + (dir_ / "exported").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string report = read(dir_ / "exported" / "export.json");
  EXPECT_THAT(report, HasSubstr("\"other\""));
  for (const char* name : {"print/slices/manifest.json", "print/VeroCyan.stl",
                           "print/VeroWhitePlus.stl", "preview/render.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ / "exported" / name)) << name;
  }
  EXPECT_EQ(fs::is_regular_file(dir_ / "exported" / "print/model.3mf"), SPEC2FAB_WITH_LIB3MF);
  EXPECT_FALSE(fs::exists(dir_ / "exported" / "print" / "VeroYellow.stl"));  // loaded, not used
  const std::string manifest = read(dir_ / "exported" / "print" / "slices" / "manifest.json");
  EXPECT_THAT(manifest, HasSubstr("\"layers\": 167"));  // 50 mm / 0.3 mm
  EXPECT_THAT(manifest, HasSubstr("VeroYellow"));

  // A printer without the tree's materials: one line, exit 2, nothing written.
  std::ofstream(dir_ / "white.json")
      << R"({"name": "white-only", "technology": "polyjet", "resolution_dpi": [63.5, 63.5], "layer_mm": 0.4,
             "build_volume_mm": [200, 200, 200], "model_materials": ["VeroWhitePlus"], "source": "test"})";
  const Result bad = run_spec2fab("export " + (dir_ / "run").string() + " --printer " +
                              (dir_ / "white.json").string() + " --out " + (dir_ / "bad").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(single_line(bad.out),
              HasSubstr("material 'VeroCyan' is not loaded in printer 'white-only'"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  // A tree without its run folder's result.json cannot know the geometry.
  fs::copy_file(dir_ / "run" / "tree.json", dir_ / "lonely_tree.json");
  const Result lonely =
      run_spec2fab("export " + (dir_ / "lonely_tree.json").string() + " --printer " +
               (dir_ / "other.json").string() + " --out " + (dir_ / "bad").string());
  EXPECT_EQ(lonely.code, 2);
  EXPECT_THAT(single_line(lonely.out), HasSubstr("result.json: file not found"));
}

}  // namespace

namespace {

// The linear RGB in an albedo.csv written by `spec2fab simulate`.
std::array<double, 3> read_albedo_csv(const fs::path& file) {
  std::istringstream in(read(file));
  std::string line;
  std::getline(in, line);  // header
  std::array<double, 3> rgb{};
  for (double& channel : rgb) {
    std::getline(in, line);
    channel = std::stod(line.substr(line.find(',') + 1));
  }
  return rgb;
}

}  // namespace

TEST_F(Cli, SimulateWritesTheObservationOfOneSimulator) {
  const std::string config_body =
      R"({"materials": ")" + (kDatasets / "materials/polyjet.json").string() +
      R"(", "printer": ")" + (dir_ / "coarse_printer.json").string() + R"(",
          "subtree": {"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": 0.2},
                                                    {"material": "VeroWhitePlus"}]},
          "simulator": {"depth_mm": 1}})";
  const fs::path config = experiment("sim", config_body);
  const Result r = run_spec2fab("simulate albedo " + config.string() + " --repeat 10 --out " +
                            (dir_ / "sim").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("per evaluation"));
  for (const char* file : {"simulation.json", "albedo.csv", "albedo.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ / "sim" / file)) << file;
  }
  const auto rgb = read_albedo_csv(dir_ / "sim" / "albedo.csv");
  EXPECT_LT(rgb[0], rgb[2]);  // cyan over white: red absorbed
  for (const std::string& arguments :
       {"simulate albedoo " + config.string(), "simulate albedo " + dir_.string() + "/none.json",
        "simulate albedo " +
            experiment("bad", config_body.substr(0, config_body.size() - 1) + R"(, "stpe_mm": 1})")
                .string()}) {
    const Result bad = run_spec2fab(arguments + " --out " + (dir_ / "bad_out").string());
    EXPECT_EQ(bad.code, 2) << arguments;
    EXPECT_THAT(single_line(bad.out), StartsWith("error: "));
    EXPECT_FALSE(fs::exists(dir_ / "bad_out"));
  }
  EXPECT_THAT(run_spec2fab("simulate albedoo " + config.string() + " --out x").out,
              HasSubstr("did you mean 'albedo'?"));
}

TEST_F(Cli, TunedRunRecordsEverySummaryAndFindsAReachableColour) {
  // The target of the first patch is what `simulate` says 0.2 mm of cyan over
  // white looks like; exhaustive search must find exactly that thickness.
  const fs::path config = experiment(
      "sim", R"({"materials": ")" + (kDatasets / "materials/polyjet.json").string() +
                 R"(", "printer": ")" + (dir_ / "coarse_printer.json").string() + R"(",
          "subtree": {"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": 0.2},
                                                    {"material": "VeroWhitePlus"}]},
          "simulator": {"depth_mm": 1}})");
  ASSERT_EQ(run_spec2fab("simulate albedo " + config.string() + " --out " + (dir_ / "sim").string()).code, 0);
  const auto rgb = read_albedo_csv(dir_ / "sim" / "albedo.csv");
  const std::string target = "[" + std::to_string(rgb[0]) + ", " + std::to_string(rgb[1]) + ", " +
                             std::to_string(rgb[2]) + "]";
  const std::string tree = R"({"type": "stratum", "depth_mm": 1,
      "shell": {"type": "column", "count": [2, 1], "child": {"type": "layered", "layers": [
          {"material": "VeroCyan", "thickness_mm": {"value": 0.5, "min": 0, "max": 0.5, "step": 0.05}},
          {"material": "VeroWhitePlus"}]}},
      "core": {"type": "layered", "material": "VeroWhitePlus"}})";
  auto tuner = [](const std::string& name, const std::string& node, const std::string& goal) {
    return R"({"name": ")" + name + R"(", "node": ")" + node +
           R"(", "simulator": {"type": "albedo", "depth_mm": 1}, "metric": {"type": "ciede2000"},
              "goal": {"type": "albedo", )" + goal + R"(}, "optimizer": {"type": "exhaustive"}})";
  };
  std::string body = valid_body(tree);
  const std::string tuning =
      R"(, "tuners": [)" + tuner("exact", "shell/0", R"("linear_rgb": )" + target) + ", " +
      tuner("pale", "shell/1", R"("srgb": [0.7, 0.95, 0.95])") +
      R"(], "network": {"type": "grid4", "width": 2},
          "schedule": [{"name": "patches", "mode": "parallel"}])";
  body.insert(body.find(R"(}, "materials")"), tuning);
  const fs::path file = experiment("tuned", body);
  // validate shows what the schedule will cost: 11 thicknesses and the start, per tuner.
  EXPECT_THAT(run_spec2fab("validate " + file.string()).out,
              HasSubstr("  tuning:     2 tuner run(s) in 1 phase(s), 24 error evaluations planned\n"));
  const Result one = run_spec2fab("run -q " + file.string() + " --threads 1 --out " + (dir_ / "t1").string());
  ASSERT_EQ(one.code, 0) << one.out;
  ASSERT_EQ(run_spec2fab("run -q " + file.string() + " --threads 2 --out " + (dir_ / "t2").string()).code, 0);
  for (const char* name : {"result.json", "tree.json", "convergence.csv", "preview/convergence.png"}) {
    EXPECT_EQ(read(dir_ / "t1" / name), read(dir_ / "t2" / name)) << name;
  }
  const auto result = nlohmann::json::parse(read(dir_ / "t1" / "result.json"));
  EXPECT_EQ(result["spec2fab_version"], SPEC2FAB_PROJECT_VERSION);
  const auto& runs = result["tuning"]["tuner_runs"];
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0]["tuner"], "exact");
  EXPECT_EQ(runs[1]["tuner"], "pale");
  for (const auto& run : runs) EXPECT_EQ(run["evaluations"], 12);  // 11 thicknesses + the start
  EXPECT_LT(result["tuning"]["tuners"][0]["final_error"].get<double>(), 1e-3);  // target from 6-digit CSV
  const std::string convergence = read(dir_ / "t1" / "convergence.csv");
  EXPECT_THAT(convergence, StartsWith("phase,sweep,tuner,iteration,evaluations,error,best_error\n"));
  EXPECT_THAT(convergence, HasSubstr("patches,0,exact,"));
  // The exact patch (column 0) found the 0.2 mm the target was simulated at.
  const auto tuned = nlohmann::json::parse(read(dir_ / "t1" / "tree.json"));
  EXPECT_DOUBLE_EQ(tuned["shell"]["children"][0]["layers"][0]["thickness_mm"]["value"].get<double>(), 0.2);
}

TEST_F(Cli, FemTunersMayNotRunInParallel) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_TETGEN);  // validate meshes the beam
  // An FEM tuner's simulator reads every tet's material from the whole tree,
  // so beside another tuner of a parallel phase it would see that tuner's
  // trial values as they change: its result would depend on timing.
  auto body = [](const char* mode) { return two_fem_tuners_body(mode, "cholesky", ""); };
  const Result parallel = run_spec2fab("-q validate " + experiment("parallel", body("parallel")).string());
  EXPECT_EQ(parallel.code, 2) << parallel.out;
  EXPECT_THAT(single_line(parallel.out),
              HasSubstr("/goal/schedule/0/mode: tuners 'near' and 'far' cannot run in parallel: the fem simulator of "
                        "'near' reads the whole tree"));
  const Result serial = run_spec2fab("-q validate " + experiment("serial", body("serial")).string());
  EXPECT_EQ(serial.code, 0) << serial.out;
}

TEST_F(Cli, TunerMistakesAreCaughtByValidate) {
  const std::string tree = R"({"type": "layered", "layers": [
      {"material": "VeroCyan", "thickness_mm": {"value": 0.1, "min": 0, "max": 0.5, "step": 0.05}},
      {"material": "VeroWhitePlus"}]})";
  const std::string parts = R"("simulator": {"type": "albedo"}, "metric": {"type": "ciede2000"},
      "goal": {"type": "albedo", "srgb": [0.5, 0.5, 0.5]}, "optimizer": {"type": "exhaustive"})";
  struct Case {
    std::string tuning, expected;
  };
  const std::vector<Case> cases = {
      {R"(, "tuners": [{"node": "shell", )" + parts + "}]", "/goal/tuners/0/node: no node 'shell'"},
      {R"(, "tuners": [{"simulator": {"type": "albedo"}, "metric": {"type": "ciede2000"},
          "goal": {"type": "albedo", "srgb": [0.5, 0.5, 0.5]}, "optimizer": {"type": "annealing", "coolng": 0.9}}])",
       "coolng: unknown key"},
      {R"(, "tuners": [{)" + parts + R"(}], "schedule": [{"tuners": ["tuner1"]}])",
       "/goal/schedule/0/tuners: no tuner 'tuner1'; did you mean 'tuner0'?"},
      {R"(, "tuners": [{)" + parts + R"(}], "schedule": [{"coupling": "error_diffusion"}])",
       "error_diffusion needs a grid4 or grid8 network"},
      {R"(, "tuners": [{)" + parts + R"(}], "network": {"type": "grid4", "width": 2})",
       "/goal/network/width: 1 tuners do not fill rows of 2"},
      {R"(, "tuners": [{)" + parts + R"(}], "network": {"type": "grid6", "width": 1})",
       "/goal/network/type: unknown network 'grid6'; did you mean 'grid4'? (known: grid4, grid8, none)"},
      {R"(, "tuners": [{)" + parts + R"(}], "schedule": [{"coupling": "error_difusion"}])",
       "/goal/schedule/0/coupling: unknown coupling 'error_difusion'; did you mean 'error_diffusion'? "
       "(known: error_diffusion, none, texture_shadow)"},
      {R"(, "tuners": [{)" + parts + R"(}], "network": {"type": "grid4", "width": 1},
          "schedule": [{"coupling": "error_diffusion", "mode": "parallel"}])",
       "/goal/schedule/0/mode: error_diffusion depends on the order: its phase must be serial"},
      {R"(, "tuners": [{)" + parts + R"(}, {)" + parts + R"(}], "schedule": [{"mode": "parallel"}])",
       "/goal/schedule/0/mode: tuners 'tuner0' and 'tuner1' cannot run in parallel: their subtrees overlap"},
  };
  for (const Case& c : cases) {
    std::string body = valid_body(tree);
    body.insert(body.find(R"(}, "materials")"), c.tuning);
    const Result r = run_spec2fab("validate " + experiment("bad", body).string());
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_THAT(single_line(r.out), HasSubstr(c.expected));
  }
}

TEST_F(Cli, ErrorDiffusionLowersTheLowPassColourErrorOfAnAlbedoPrint) {
  // A goal image of linear blends between the two extreme printable colours
  // of one ink over white (so every pixel is a mixture diffusion can make):
  // 48 columns across 6 printable stacks. Nearest-stack quantisation bands;
  // diffusion must come closer once both are blurred (what the eye sees).
  auto albedo_of = [&](const std::string& thickness) {
    const fs::path config = experiment(
        "sim_" + thickness,
        R"({"materials": ")" + (kDatasets / "materials/polyjet.json").string() +
            R"(", "printer": ")" + (dir_ / "coarse_printer.json").string() + R"(",
            "subtree": {"type": "layered", "layers": [{"material": "VeroCyan", "thickness_mm": )" +
            thickness + R"(}, {"material": "VeroWhitePlus"}]}, "simulator": {"depth_mm": 0.2}})");
    EXPECT_EQ(run_spec2fab("simulate albedo " + config.string() + " --out " +
                       (dir_ / ("sim_" + thickness)).string())
                  .code,
              0);
    return read_albedo_csv(dir_ / ("sim_" + thickness) / "albedo.csv");
  };
  const auto white = albedo_of("0"), cyan = albedo_of("0.135");
  const int width = 48, height = 6;
  std::string ppm = "P6\n" + std::to_string(width) + " " + std::to_string(height) + "\n255\n";
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double t = (x + 0.5) / width;
      for (int c = 0; c < 3; ++c) {
        const double linear = (1 - t) * white[c] + t * cyan[c];
        const double encoded =
            linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
        ppm += static_cast<char>(std::lround(255 * encoded));
      }
    }
  }
  std::ofstream(dir_ / "gradient.ppm", std::ios::binary) << ppm;
  std::string body = valid_body(kTree, R"(, "output": {"slices": false, "stl": false, "3mf": false, "render": false})", "albedo");
  const std::string goal = R"({"image": ")" + (dir_ / "gradient.ppm").string() +
                           R"(", "columns": [48, 6], "inks": ["VeroCyan"], "layer_step_mm": 0.027, "max_ink_mm": 0.135})";
  body.replace(body.find(R"({"tree": )"), std::string(R"({"tree": )").size() + std::string(kTree).size() + 1,
               goal);
  const Result r = run_spec2fab("run -q " + experiment("gradient", body).string() + " --out " +
                            (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out << body;
  const auto albedo = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["albedo"];
  const double diffused = albedo["low_pass_delta_e00"].get<double>();
  const double nearest = albedo["low_pass_delta_e00_nearest_only"].get<double>();
  std::printf("low-pass dE00: diffused %.3f, nearest only %.3f\n", diffused, nearest);
  EXPECT_LT(diffused, 0.7 * nearest) << "diffused " << diffused << ", nearest only " << nearest;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "run" / "preview" / "goal_vs_achieved.png"));
}

TEST_F(Cli, SimulateRunsTheSubsurfaceSimulator) {
  const Result r = run_spec2fab("simulate subsurface " +
                            (kDatasets / "simulations/subsurface_white_over_cyan.json").string() +
                            " --out " + (dir_ / "sim").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(dir_ / "sim" / "profile.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "radius_mm,r,g,b");
  std::vector<std::array<double, 4>> rows;
  while (std::getline(in, line)) {
    std::array<double, 4> row{};
    std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &row[0], &row[1], &row[2], &row[3]);
    rows.push_back(row);
  }
  ASSERT_EQ(rows.size(), 400u);
  EXPECT_GT(rows[0][1], 0);
  // Light that reaches the cyan below loses its red: far from the beam, red is weaker than blue.
  EXPECT_LT(rows[100][1], rows[100][3]);
}

TEST_F(Cli, SimulateRunsTheCausticSimulator) {
  const Result r = run_spec2fab("simulate caustics " +
                            (kDatasets / "simulations/caustics_dome.json").string() +
                            " --repeat 1 --out " + (dir_ / "sim").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "sim" / "image.png"));
  const auto simulation = nlohmann::json::parse(read(dir_ / "sim" / "simulation.json"));
  EXPECT_EQ(simulation["produces"], "image");
  const auto values = simulation["values"].get<std::vector<double>>();
  ASSERT_EQ(values.size(), 240u * 240u);
  // The dome converges the light: its 900 mm² of beam all land on the 30 mm
  // receiver (less what the bilinear splat drops off its edge pixels), and
  // the centre is brighter than the incident irradiance.
  double sum = 0;
  for (double v : values) sum += v;
  const double pixel_area = (30.0 / 240) * (30.0 / 240);
  EXPECT_NEAR(sum * pixel_area, 900.0, 1.0);
  EXPECT_GT(values[120 * 240 + 120], 1.2);
}

// A coarse printer with clear material only, for the caustic translators.
static void write_clear_printer(const fs::path& file) {
  std::ofstream(file) << R"({"name": "coarse-clear", "technology": "polyjet", "resolution_dpi": [63.5, 63.5],
      "layer_mm": 0.4, "build_volume_mm": [200, 200, 200], "model_materials": ["VeroClear", "Agilus30Clear"],
      "source": "test"})";
}

// A smooth-caustics experiment on the 60 x 60 x 8 mm board casting the ring
// image, on the clear printer at `printer`: `goal_keys` follow the image in
// the goal, L-BFGS for `evaluations`, and the print's switches `output`.
static std::string board_caustics_body(const std::string& name, const std::string& goal_keys, int evaluations,
                                       const std::string& output, const fs::path& printer) {
  return R"({"name": ")" + name + R"(", "translator": "smooth_caustics",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(", )" + goal_keys + R"(},
          "optimizer": {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": )" + std::to_string(evaluations) + R"(},
          "output": )" + output + R"(,
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + printer.string() + R"("})";
}

// A PNG's width and height, from its IHDR chunk (bytes 16–23, big-endian).
static std::array<int, 2> png_size(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::array<unsigned char, 24> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  if (!in) return {0, 0};
  const auto word = [&](size_t at) {
    return static_cast<int>((head[at] << 24) | (head[at + 1] << 16) | (head[at + 2] << 8) | head[at + 3]);
  };
  return {word(16), word(20)};
}

// A binary STL holds an 84-byte header and count, then 50 bytes a triangle.
static std::uintmax_t binary_stl_size(std::uintmax_t triangles) { return 84 + 50 * triangles; }

// ADMesh (Debian's admesh) finds every edge of the file shared by a facet
// on each side, one part, and nothing to fix: closed, consistently
// oriented, no degenerate facets.
static void expect_admesh_clean(const fs::path& stl) {
  const Result r = run_command("admesh " + stl.string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto original = [&](const std::string& label) {
    const size_t at = r.out.find(label);
    if (at == std::string::npos) return std::string("missing");
    std::istringstream line(r.out.substr(r.out.find(':', at) + 1));
    std::string value;
    line >> value;
    return value;
  };
  EXPECT_EQ(original("Total disconnected facets"), "0") << r.out;
  EXPECT_EQ(original("Number of parts"), "1") << r.out;
  for (const char* label : {"Degenerate facets", "Edges fixed", "Facets removed", "Facets added", "Facets reversed",
                            "Backwards edges", "Normals fixed"})
    EXPECT_EQ(original(label), "0") << label << "\n" << r.out;
}

// caustic_check (tools/caustic_check.cpp, its own tracer) on an STL, as JSON.
static nlohmann::json caustic_check(const fs::path& stl, const fs::path& goal, const std::string& options) {
  const Result r = run_command(std::string(SPEC2FAB_CAUSTIC_CHECK_PATH) + " --stl " + stl.string() + " --goal " +
                               goal.string() + " " + options);
  EXPECT_EQ(r.code, 0) << r.out;
  return r.code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::object();
}

TEST_F(Cli, SmoothCausticsTunesTheSurfaceAndReportsImageErrors) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  const std::string body =
      R"({"name": "lens", "translator": "smooth_caustics",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(",
                   "material": "Agilus30Clear",
                   "control": [6, 6], "image_size": [48, 48], "rays": [96, 96], "distance_mm": 60},
          "optimizer": {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 15},
          "compare_optimizers": [{"type": "spsa", "iterations": 5, "c": 0.01, "seed": 3}],
          "output": {"slices": false, "stl": true, "3mf": false, "render": false},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
  write_clear_printer(dir_ / "clear_printer.json");
  const fs::path file = experiment("lens", body);
  const Result r = run_spec2fab("run -q " + file.string() + " --threads 2 --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  // The same files for one thread; the start's wall times are in timing.json.
  ASSERT_EQ(run_spec2fab("run -q " + file.string() + " --threads 1 --out " + (dir_ / "t1").string()).code, 0);
  for (const char* name :
       {"result.json", "tree.json", "print/surface.stl", "preview/surface_stl_traced.png", "preview/print_traced.png"})
    EXPECT_EQ(read(dir_ / "run" / name), read(dir_ / "t1" / name)) << name;
  EXPECT_GT(nlohmann::json::parse(read(dir_ / "t1" / "timing.json"))["start_seconds"]["transport"].get<double>(), 0.0);
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  const auto& caustics = result["caustics"];
  // The reported image is the one the tuner ended at: its RMSE squared is
  // the tuner's final image MSE.
  const double final_mse = result["tuning"]["phases"][0]["sum_final_error"].get<double>();
  EXPECT_NEAR(std::pow(caustics["rmse"].get<double>(), 2), final_mse, 1e-9 * final_mse);
  // L-BFGS on the tracer's derivative lowers the error from the flat start,
  // and the picture looks more like the goal.
  EXPECT_LT(caustics["rmse"].get<double>(), 0.95 * caustics["initial_rmse"].get<double>());
  EXPECT_GT(caustics["ssim"].get<double>(), caustics["initial_ssim"].get<double>());
  // No refractive_index given: the material's, from the library (Agilus30Clear: 1.48).
  EXPECT_EQ(caustics["refractive_index"].get<double>(), 1.48);
  EXPECT_EQ(caustics["aperture"], "rectangle");
  EXPECT_EQ(result["tuning"]["tuner_runs"][0]["optimizer"], "nlopt");
  // SPSA ran first from the same start, for the comparison, and ended
  // higher than L-BFGS on the tracer's derivative.
  ASSERT_EQ(caustics["optimizers"].size(), 2u);
  EXPECT_EQ(caustics["optimizers"][1]["optimizer"], "spsa");
  EXPECT_EQ(caustics["optimizers"][1]["initial_error"], caustics["optimizers"][0]["initial_error"]);
  EXPECT_EQ(caustics["optimizers"][0]["final_error"], result["tuning"]["phases"][0]["sum_final_error"]);
  EXPECT_LT(caustics["optimizers"][0]["final_error"].get<double>(),
            caustics["optimizers"][1]["final_error"].get<double>());
  // The smooth slab STL holds the tuned surface (meshed finer than the
  // simulator's mesh) and, traced back with rays, casts about the image
  // the smooth estimator simulated.
  EXPECT_LT(caustics["surface_stl"]["largest_height_error_mm"].get<double>(), 1e-4);
  EXPECT_LT(caustics["surface_stl"]["traced_relative_rmse_vs_simulated"].get<double>(), 0.25);
  // 6 × 6 control points, 3 mesh vertices per span simulated, 6 printed:
  // a 31 × 31 top grid, two wall triangles and one bottom fan triangle per
  // rim edge.
  EXPECT_EQ(caustics["surface_stl"]["triangles"], 2 * 30 * 30 + 3 * 4 * 30);
  // The print writer "stl" wrote it beside the material's and lists it.
  const nlohmann::json& stls = result["fabrication"]["files"]["stl"];
  EXPECT_NE(std::find(stls.begin(), stls.end(), "print/surface.stl"), stls.end()) << stls;
  EXPECT_EQ(result["files"]["print"]["stl"], stls);
  EXPECT_EQ(caustics["start"]["method"], "optimal transport");
  expect_admesh_clean(dir_ / "run/print/surface.stl");
  // An independent tracer (tools/caustic_check) sees the print cast the
  // goal better than a flat board of the same size does.
  const std::string setup = "--distance 60 --image 48 48 --index 1.48";
  const fs::path goal = kDatasets / "images/caustic_ring_120.png";
  const auto printed = caustic_check(dir_ / "run/print/surface.stl", goal, setup);
  const auto flat = caustic_check(kDatasets / "meshes/board_60x60x8.stl", goal, setup);
  EXPECT_GT(printed["ssim"].get<double>(), flat["ssim"].get<double>() + 0.1);
  EXPECT_LT(printed["relative_rmse"].get<double>(), 0.9 * flat["relative_rmse"].get<double>());
  EXPECT_EQ(flat["light_off_receiver"].get<double>(), 0.0);
  // The run's headline is that tracer's figure for the file (the same rays,
  // 16 per pixel along each axis), beside the estimator's, and says whether
  // they agree.
  const auto& headline = result["headline"];
  EXPECT_NEAR(headline["ssim"].get<double>(), printed["ssim"].get<double>(), 1e-8) << headline;
  EXPECT_NEAR(headline["relative_rmse"].get<double>(), printed["relative_rmse"].get<double>(), 1e-8);
  EXPECT_EQ(headline["rays"], printed["rays"]);
  EXPECT_EQ(headline["rays"], 48 * 16 * 48 * 16);
  EXPECT_EQ(headline["simulated_ssim"], caustics["ssim"]);
  EXPECT_NEAR(headline["ssim_difference"].get<double>(),
              caustics["ssim"].get<double>() - headline["ssim"].get<double>(), 1e-12);
  const bool agree = std::abs(headline["ssim_difference"].get<double>()) <= 0.02;
  EXPECT_EQ(headline["agreement"].get<std::string>().starts_with("agree within 0.02"), agree) << headline;
  // Why not, where they differ: the facet estimator on the file's facets.
  EXPECT_EQ(headline.contains("printed_facets_ssim"), !agree) << headline;
  EXPECT_EQ(png_size(dir_ / "run/preview/print_traced.png"), (std::array<int, 2>{2 * 48 + 8, 48}));
  EXPECT_EQ(fs::file_size(dir_ / "run/print/surface.stl"),
            binary_stl_size(caustics["surface_stl"]["triangles"].get<std::uintmax_t>()));
  // Goal | simulated, 48 px each with an 8 px gap; the 6 x 6 heights at 40 px each.
  EXPECT_EQ(png_size(dir_ / "run/preview/goal_vs_simulated.png"), (std::array<int, 2>{2 * 48 + 8, 48}));
  EXPECT_EQ(png_size(dir_ / "run/preview/height_map.png"), (std::array<int, 2>{240, 240}));
  EXPECT_EQ(png_size(dir_ / "run/preview/convergence.png"), (std::array<int, 2>{800, 500}));
  EXPECT_EQ(png_size(dir_ / "run/preview/optimizer_comparison.png"), (std::array<int, 2>{800, 500}));
  EXPECT_EQ(png_size(dir_ / "run/preview/surface_stl_traced.png"), (std::array<int, 2>{2 * 48 + 8, 48}));
  const auto tree = nlohmann::json::parse(read(dir_ / "run" / "tree.json"));
  EXPECT_EQ(tree["type"], "bspline");
  EXPECT_EQ(tree["heights_mm"].size(), 36u);
}

// Under a point light 300 mm above the board (goal.light_distance_mm), the
// smooth slab still casts the ring: caustic_check, its light from the same
// point, sees the print beat a flat board; facet caustics refuse the light.
TEST_F(Cli, SmoothCausticsUnderAPointLight) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  write_clear_printer(dir_ / "clear_printer.json");
  const auto body = [&](const std::string& translator, const std::string& extra) {
    return R"({"name": "led", "translator": ")" + translator + R"(",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(",
                   "image_size": [48, 48], "distance_mm": 60, "light_distance_mm": 300)" + extra + R"(},
          "optimizer": {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 15},
          "output": {"slices": false, "stl": true, "3mf": false, "render": false},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
  };
  const Result r = run_spec2fab("run -q " + experiment("led", body("smooth_caustics", R"(, "control": [12, 12])")).string() +
                                " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  EXPECT_EQ(result["caustics"]["start"]["method"], "optimal transport");
  EXPECT_LT(result["caustics"]["rmse"].get<double>(), result["caustics"]["initial_rmse"].get<double>());
  const std::string setup = "--distance 60 --image 48 48 --point 30 30 308";
  const fs::path goal = kDatasets / "images/caustic_ring_120.png";
  const auto printed = caustic_check(dir_ / "run/print/surface.stl", goal, setup);
  const auto flat = caustic_check(kDatasets / "meshes/board_60x60x8.stl", goal, setup);
  EXPECT_GT(printed["ssim"].get<double>(), flat["ssim"].get<double>() + 0.1) << printed << flat;
  EXPECT_LT(printed["relative_rmse"].get<double>(), 0.7 * flat["relative_rmse"].get<double>()) << printed << flat;
  EXPECT_LT(printed["light_off_receiver"].get<double>(), 0.5 * flat["light_off_receiver"].get<double>());

  const Result facets = run_spec2fab("validate " + experiment("facets", body("facet_caustics", "")).string());
  EXPECT_EQ(facets.code, 2);
  EXPECT_THAT(single_line(facets.out), HasSubstr("/goal/light_distance_mm: facet caustics give every facet"));
}

// goal.max_slope holds the shaped face: the transport start asks for more
// than 0.02 here, and the print's top triangles all stay within it.
TEST_F(Cli, SmoothCausticsHoldTheSurfaceToMaxSlope) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  write_clear_printer(dir_ / "clear_printer.json");
  const std::string body = board_caustics_body(
      "gentle", R"("control": [12, 12], "image_size": [48, 48], "distance_mm": 200, "max_slope": 0.02)", 15,
      R"({"slices": false, "stl": true, "3mf": false, "render": false})", dir_ / "clear_printer.json");
  const Result r = run_spec2fab("run -q " + experiment("gentle", body).string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto limit = nlohmann::json::parse(read(dir_ / "run" / "result.json"))["caustics"]["slope_limit"];
  EXPECT_GT(limit["start"]["steepest_control_slope_before"].get<double>(), 0.02);
  EXPECT_GT(limit["start"]["controls_moved"].get<int>(), 0);
  EXPECT_LE(limit["final"]["steepest_control_slope"].get<double>(), 0.02 + 1e-9);
  // L-BFGS saw the limit as a penalty and kept near it: the end barely moves.
  EXPECT_LT(limit["final"]["largest_move_mm"].get<double>(), 0.01) << limit;
  // The file's top triangles (normals facing up), read back as written.
  const std::string stl = read(dir_ / "run/print/surface.stl");
  ASSERT_GT(stl.size(), 84u);
  uint32_t count = 0;
  std::memcpy(&count, stl.data() + 80, 4);
  ASSERT_EQ(stl.size(), 84 + 50 * static_cast<size_t>(count));
  int tops = 0;
  double steepest = 0;
  for (uint32_t t = 0; t < count; ++t) {
    float v[9];
    std::memcpy(v, stl.data() + 84 + 50 * static_cast<size_t>(t) + 12, sizeof v);
    const Eigen::Vector3d a(v[0], v[1], v[2]), b(v[3], v[4], v[5]), c(v[6], v[7], v[8]);
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.z() < 0.5 * n.norm()) continue;  // walls and the bottom
    ++tops;
    steepest = std::max({steepest, std::abs(n.x() / n.z()), std::abs(n.y() / n.z())});
  }
  EXPECT_GT(tops, 1000);
  EXPECT_LE(steepest, 0.02 + 1e-4);
  EXPECT_GT(steepest, 0.005);  // the surface is shaped, not flat
}

TEST_F(Cli, NoStlWritesNoSurfaceStlEither) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  // print/surface.stl is a print file like the materials' STLs: "stl": false
  // leaves it out too (it was written whatever the switch said).
  write_clear_printer(dir_ / "clear_printer.json");
  const std::string body = board_caustics_body(
      "nostl", R"("control": [8, 8], "image_size": [32, 32], "distance_mm": 200)", 3,
      R"({"slices": false, "stl": false, "3mf": false, "render": false})", dir_ / "clear_printer.json");
  const Result r = run_spec2fab("run -q " + experiment("nostl", body).string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "run/print/surface.stl"));
  EXPECT_FALSE(fs::exists(dir_ / "run/preview/surface_stl_traced.png"));
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  EXPECT_FALSE(result["caustics"].contains("surface_stl"));
  EXPECT_FALSE(result["files"].contains("print"));
}

/// The light a point source 108 mm up over (0, 0) puts on the square
/// [low, high]² at height z: I cos / r² by a 600² midpoint sum. A function,
/// not a lambda: a lambda is implicitly constexpr, and GCC evaluated this
/// sum at compile time (17 s of the file's 42).
double light_on(double z, double low, double high) {
  constexpr int kSteps = 600;
  double sum = 0;
  for (int j = 0; j < kSteps; ++j)
    for (int i = 0; i < kSteps; ++i) {
      const double x = low + (i + 0.5) * (high - low) / kSteps, y = low + (j + 0.5) * (high - low) / kSteps;
      const double r2 = x * x + y * y + (108 - z) * (108 - z);
      sum += (108 - z) / (r2 * std::sqrt(r2));
    }
  return sum * (high - low) * (high - low) / (kSteps * kSteps);
}

TEST_F(Cli, CausticCheckSeesAFlatBoardPassTheBeamUnchanged) {
  // The checker's own optics: a flat slab under vertical light lights the
  // receiver below it uniformly (16 × 16 rays per pixel, the pixels'
  // strata aligned with the board), all of its light; a disc stop passes
  // π/4 of it, on the disc. A uniform goal, written here as a PGM.
  const fs::path uniform = dir_ / "uniform.pgm";
  {
    std::ofstream out(uniform, std::ios::binary);
    out << "P5 4 4 255\n" << std::string(16, static_cast<char>(255));
  }
  const fs::path board = kDatasets / "meshes/board_60x60x8.stl";
  const auto plain = caustic_check(board, uniform, "--distance 100 --image 24 24 --index 1.5");
  EXPECT_NEAR(plain["ssim"].get<double>(), 1.0, 1e-9);
  EXPECT_LT(plain["relative_rmse"].get<double>(), 1e-9);
  EXPECT_EQ(plain["light_off_receiver"].get<double>(), 0.0);
  EXPECT_EQ(plain["triangles"], 48);
  // Light sloping 0.2 along x (its cross-section at the board's top the
  // footprint) lands 21.055 mm further on (1.055 mm refracted through the
  // 8 mm board, 20 mm below): off the receiver but for the light within
  // 1.055 mm of the far side, which meets that wall from inside beyond the
  // critical angle and is turned back.
  const auto oblique = caustic_check(board, uniform, "--distance 100 --image 24 24 --light 0.2 0 -1");
  const double refracted = 8 * std::tan(std::asin(0.2 / std::sqrt(1.04) / 1.5));
  EXPECT_NEAR(oblique["light_off_receiver"].get<double>(), (refracted + 20 - refracted) / 60, 0.002);
  const auto disc = caustic_check(board, uniform, "--distance 100 --image 24 24 --aperture disc");
  EXPECT_EQ(disc["light_off_receiver"].get<double>(), 0.0);
  EXPECT_LT(disc["ssim"].get<double>(), 0.9);  // the corners stay dark
  // A point light 100 mm above the board's top, over its corner (0, 0),
  // through a board of index 1: of the light crossing the footprint 1 mm
  // above the board (z = 9), the 60 mm receiver 100 mm under it (z = -100)
  // catches what the inverse-square law puts there. Both integrals of
  // I cos / r² by midpoint sums.
  const auto point = caustic_check(board, uniform, "--distance 100 --image 24 24 --index 1 --point 0 0 108");
  const double caught = light_on(-100, 0, 60) / light_on(9, 0, 60);
  EXPECT_NEAR(point["light_off_receiver"].get<double>(), 1 - caught, 2e-3) << point;
  EXPECT_GT(1 - caught, 0.3);  // the light spreads: most of it falls beside the receiver
  // Bad input: one line, exit 2.
  const Result missing = run_command(std::string(SPEC2FAB_CAUSTIC_CHECK_PATH) + " --stl " + (dir_ / "none.stl").string() +
                                     " --goal " + uniform.string() + " --distance 10");
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(single_line(missing.out), HasSubstr("cannot open"));
}

// A slab's flat bottom fanned from its centre to a fine rim (as caustic STLs
// may close a height field) has triangles 20 times wider than the top's:
// caustic_check enters them once per tile of the plane they cross, so that
// their boxes do not swell the hierarchy. Under oblique light the bottom
// bends every ray, so a ray that slipped between the tiles would land
// elsewhere: the fanned board must cast the gridded one's image exactly.
TEST_F(Cli, CausticCheckTracesAFannedBottomLikeAGriddedOne) {
  const fs::path uniform = dir_ / "uniform.pgm";
  {
    std::ofstream out(uniform, std::ios::binary);
    out << "P5 4 4 255\n" << std::string(16, static_cast<char>(255));
  }
  // 60 x 60 x 8 mm: a 40 x 40 grid on top, a fan of 160 triangles below.
  const fs::path fanned = dir_ / "fanned_board.stl";
  {
    std::ofstream out(fanned);
    constexpr int kSide = 40;
    constexpr double kStep = 60.0 / kSide, kTop = 8;
    struct Point {
      double x, y, z;
      Point operator+(const Point& o) const { return {x + o.x, y + o.y, z + o.z}; }
    };
    const auto facet = [&](const Point& a, const Point& b, const Point& c) {
      out << "facet normal 0 0 0\nouter loop\n";
      for (const Point* p : {&a, &b, &c}) out << "vertex " << p->x << " " << p->y << " " << p->z << "\n";
      out << "endloop\nendfacet\n";
    };
    out << "solid fanned\n";
    for (int j = 0; j < kSide; ++j)
      for (int i = 0; i < kSide; ++i) {
        const Point p00{i * kStep, j * kStep, kTop}, p10{(i + 1) * kStep, j * kStep, kTop};
        const Point p11{(i + 1) * kStep, (j + 1) * kStep, kTop}, p01{i * kStep, (j + 1) * kStep, kTop};
        facet(p00, p10, p11);
        facet(p00, p11, p01);
      }
    std::vector<Point> rim;  // counter-clockwise from above
    for (int i = 0; i < kSide; ++i) rim.push_back({i * kStep, 0, 0});
    for (int i = 0; i < kSide; ++i) rim.push_back({60, i * kStep, 0});
    for (int i = 0; i < kSide; ++i) rim.push_back({60 - i * kStep, 60, 0});
    for (int i = 0; i < kSide; ++i) rim.push_back({0, 60 - i * kStep, 0});
    const Point centre{30, 30, 0}, up{0, 0, kTop};
    for (size_t k = 0; k < rim.size(); ++k) {
      const Point &a = rim[k], &b = rim[(k + 1) % rim.size()];
      facet(centre, b, a);  // the bottom, facing down
      facet(a, b, b + up);  // the side, facing out
      facet(a, b + up, a + up);
    }
    out << "endsolid fanned\n";
  }
  const fs::path board = kDatasets / "meshes/board_60x60x8.stl";
  for (const std::string light : {"0 0 -1", "0.2 0.1 -1"}) {
    const std::string setup = "--distance 100 --image 24 24 --index 1.5 --light " + light;
    const auto gridded = caustic_check(board, uniform, setup);
    const auto fan = caustic_check(fanned, uniform, setup);
    EXPECT_EQ(fan["triangles"], 2 * 40 * 40 + 3 * 160);
    for (const char* key : {"ssim", "relative_rmse", "light_off_receiver"})
      EXPECT_NEAR(fan[key].get<double>(), gridded[key].get<double>(), 1e-9) << key << ", light " << light;
  }
}

// caustic_check is the run's independent path: it includes the standard
// library, OpenCV, oneTBB and its own header, never one of Spec2Fab's (its
// CMake target has no Spec2Fab include directory; this also catches a
// relative path).
TEST_F(Cli, CausticCheckIncludesNothingOfSpec2Fab) {
  const fs::path folder = kDatasets.parent_path() / "tools" / "caustic_check";
  int sources = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string extension = entry.path().extension().string();
    if (extension != ".h" && extension != ".cpp") continue;
    ++sources;
    std::ifstream in(entry.path());
    for (std::string line; std::getline(in, line);) {
      const size_t first = line.find_first_not_of(" \t");
      if (first == std::string::npos || line.compare(first, 8, "#include") != 0) continue;
      const size_t open = line.find_first_of("<\"", first);
      const size_t close = open == std::string::npos ? open : line.find_first_of(">\"", open + 1);
      ASSERT_NE(close, std::string::npos) << entry.path() << ": " << line;
      const std::string name = line.substr(open + 1, close - open - 1);
      const bool standard = line[open] == '<' && name.find('/') == std::string::npos;
      const bool allowed = standard || name.starts_with("opencv2/") || name.starts_with("tbb/") ||
                           (line[open] == '"' && name == "caustic_check.h");
      EXPECT_TRUE(allowed) << entry.path().filename() << ": " << line;
    }
  }
  EXPECT_EQ(sources, 3);  // the library, its header, its command line
}

// A print turned upside down with a filter on the face the light leaves by
// (caustics_texture's window): a flat board, mirrored, its left half (x < 30)
// black. Straight light passes straight through, so the right half is lit
// and, seen from behind the receiver, lands on the image's left half: the
// goal exactly, carrying the half of the light the filter lets through.
TEST_F(Cli, CausticCheckTracesAMirroredBoardThroughItsExitFilter) {
  const fs::path left_half = dir_ / "left_half.pgm";
  {
    std::ofstream out(left_half, std::ios::binary);
    out << "P5 4 4 255\n";
    for (int row = 0; row < 4; ++row) out << std::string(2, static_cast<char>(255)) << std::string(2, '\0');
  }
  const fs::path filter = dir_ / "filter.txt";
  std::ofstream(filter) << "2 1\n0 1\n";
  const fs::path board = kDatasets / "meshes/board_60x60x8.stl";
  const std::string setup = "--distance 100 --image 4 4 --mirror-z --exit-filter " + filter.string();
  const auto behind = caustic_check(board, left_half, setup + " --from-behind");
  EXPECT_NEAR(behind["absorbed"].get<double>(), 0.5, 1e-12) << behind;
  EXPECT_NEAR(behind["light_off_receiver"].get<double>(), 0.0, 1e-12) << behind;
  EXPECT_LT(behind["relative_rmse"].get<double>(), 1e-9) << behind;
  EXPECT_GT(behind["ssim"].get<double>(), 0.999) << behind;
  // From the slab's side the lit half is on the right: far from the goal.
  const auto in_front = caustic_check(board, left_half, setup);
  EXPECT_GT(in_front["relative_rmse"].get<double>(), 1.0) << in_front;
}

// caustic_check with --reflect: the flat board as a mirror under light 20
// degrees off vertical casts the even goal exactly on a receiver 100 mm
// above its bottom, moved by (100 - 8) tan 20 mm (every ray lands in the
// pixel its stratum maps to); without --reflect the light goes through
// the board to a receiver below, where the tilt moves it further (108 tan
// 20 mm, less in the board) than the offset given: an unlit strip.
TEST_F(Cli, CausticCheckReflectsOffAMirrorPrint) {
  const fs::path even = dir_ / "even.pgm";
  {
    std::ofstream out(even, std::ios::binary);
    out << "P5 4 4 255\n" << std::string(16, static_cast<char>(200));
  }
  const fs::path board = kDatasets / "meshes/board_60x60x8.stl";
  const double a = 20 * M_PI / 180;
  const std::string setup = fmt::format("--distance 100 --image 4 4 --light {:.17g} 0 {:.17g} --receiver-offset {:.17g} 0",
                                        std::sin(a), -std::cos(a), 92 * std::tan(a));
  const auto mirror = caustic_check(board, even, setup + " --reflect");
  EXPECT_LT(mirror["relative_rmse"].get<double>(), 1e-6) << mirror;
  EXPECT_NEAR(mirror["light_off_receiver"].get<double>(), 0.0, 1e-6) << mirror;
  const auto lens = caustic_check(board, even, setup);
  EXPECT_GT(lens["relative_rmse"].get<double>(), 0.05) << lens;
}

// A mirror (goal.surface "mirror"): light 20 degrees off vertical, the
// receiver 100 mm above; the print casts the ring better than the flat
// board under caustic_check --reflect, which is the run's headline. Light
// that would pass through the receiver on its way down is refused.
TEST_F(Cli, SmoothCausticsMirrorCastsTheGoalOnAReceiverAbove) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  const auto body = [&](double degrees) {
    return R"({"name": "mirror", "translator": "smooth_caustics",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(",
                   "surface": "mirror", "light_angle_deg": )" + std::to_string(degrees) + R"(,
                   "control": [12, 12], "image_size": [48, 48], "rays": [96, 96], "distance_mm": 100},
          "optimizer": {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 15},
          "output": {"slices": false, "stl": true, "3mf": false, "render": false},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
  };
  write_clear_printer(dir_ / "clear_printer.json");
  const Result refused = run_spec2fab("validate " + experiment("steep", body(10)).string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(single_line(refused.out), HasSubstr("/goal/light_angle_deg: a mirror's receiver 100 mm above"));
  EXPECT_THAT(single_line(refused.out), HasSubstr("at least 16.7 degrees"));
  const Result r = run_spec2fab("run -q " + experiment("mirror", body(20)).string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  const auto& caustics = result["caustics"];
  EXPECT_EQ(caustics["surface"], "mirror");
  EXPECT_GT(caustics["ssim"].get<double>(), caustics["initial_ssim"].get<double>() - 1e-9);
  const double a = 20 * M_PI / 180;
  const std::string setup =
      fmt::format("--distance 100 --image 48 48 --reflect --from-behind --light {:.17g} 0 {:.17g} --receiver-offset {:.17g} 0",
                  std::sin(a), -std::cos(a), 100 * std::tan(a));
  const fs::path goal = kDatasets / "images/caustic_ring_120.png";
  const auto printed = caustic_check(dir_ / "run/print/surface.stl", goal, setup);
  const auto flat = caustic_check(kDatasets / "meshes/board_60x60x8.stl", goal, setup);
  EXPECT_GT(printed["ssim"].get<double>(), flat["ssim"].get<double>() + 0.1) << printed << flat;
  const auto& headline = result["headline"];
  EXPECT_NEAR(headline["ssim"].get<double>(), printed["ssim"].get<double>(), 1e-8) << headline;
  EXPECT_EQ(headline["simulated_ssim"], caustics["ssim"]);
  expect_admesh_clean(dir_ / "run/print/surface.stl");
}

TEST_F(Cli, FacetCausticsRefuseADiscApertureInOneLine) {
  // Every facet takes an equal share of the light: a round stop would starve the corners.
  const std::string body =
      R"({"name": "facets", "translator": "facet_caustics",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(",
                   "facets": [12, 12], "aperture": "disc"},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
  write_clear_printer(dir_ / "clear_printer.json");
  const Result r = run_spec2fab("validate " + experiment("facets", body).string());
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(single_line(r.out), HasSubstr("/goal/aperture: facet caustics give every facet an equal share"));
}

// Facet caustics with planar facets (the paper's tree) and with
// micro-lenses (the default): every facet reaches its kernel; the lenses,
// which also spread their light like their kernels, cast the goal better
// under the independent tracer; both prints are closed 2-manifolds.
TEST_F(Cli, FacetCausticsAimsEveryFacetAtItsKernelAndLensesSpreadItLikeTheKernels) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  write_clear_printer(dir_ / "clear_printer.json");
  const fs::path goal = kDatasets / "images/caustic_ring_120.png";
  const auto run = [&](const std::string& facet) {
    const std::string body =
        R"({"name": "facets", "translator": "facet_caustics",
            "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
            "goal": {"image": ")" + goal.string() + R"(", "facet": ")" + facet + R"(", "lens_subdivisions": 8,
                     "facets": [12, 12], "image_size": [48, 48], "rays": [144, 144], "distance_mm": 200, "max_slope": 0.5,
                     "min_height_mm": 2, "start_height_mm": 5, "targets": "kernels",
                     "assignment_sweeps": 20, "print_check_rays": [576, 576]},
            "swap_optimizer": {"type": "annealing", "iterations": 5, "schedule_iterations": 100,
                               "swap_probability": 1, "initial_temperature": 1, "cooling": 0.95},
            "output": {"slices": false, "stl": true, "3mf": false, "render": false},
            "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
            "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
    const Result r = run_spec2fab("run -q " + experiment(facet, body).string() + " --out " + (dir_ / facet).string());
    EXPECT_EQ(r.code, 0) << r.out;
    return r.code == 0 ? nlohmann::json::parse(read(dir_ / facet / "result.json")) : nlohmann::json::object();
  };
  const auto result = run("plane");
  ASSERT_TRUE(result.contains("caustics"));
  const auto& caustics = result["caustics"];
  EXPECT_EQ(caustics["kernels"]["count"], 144);
  // Every plane reaches its kernel to a fraction of a pixel (1.25 mm here).
  EXPECT_LT(caustics["aim"]["max_miss_mm"].get<double>(), 0.3);
  // The traced facets cast the goal far better than the flat start.
  EXPECT_LT(caustics["rmse"].get<double>(), 0.8 * caustics["initial_rmse"].get<double>());
  EXPECT_GT(caustics["ssim"].get<double>(), caustics["initial_ssim"].get<double>());
  // Roughness before every sweep and after the last; swaps were accepted
  // (it changed), and the last value is the surface the facets were aimed for.
  const auto& energies = caustics["assignment"]["roughness_mm2_per_sweep"];
  ASSERT_EQ(energies.size(), 21u);
  EXPECT_NE(energies.front(), energies.back());
  EXPECT_EQ(caustics["assignment"]["roughness_mm2_final"], energies.back());
  EXPECT_EQ(caustics["assignment"]["roughness_mm2_start"], energies.front());
  // Both phases ran: 20 swap sweeps counted, one aiming run per facet recorded.
  EXPECT_EQ(result["tuning"]["phases"][0]["tuner_runs"], 20 * 144);
  EXPECT_EQ(result["tuning"]["phases"][1]["tuner_runs"], 144);
  EXPECT_EQ(result["tuning"]["tuner_runs"].back()["optimizer"], "nlopt");
  // Goal | kernels | simulated, 48 px each; the 12 x 12 facet heights at 20 px each.
  EXPECT_EQ(png_size(dir_ / "plane/preview/goal_vs_simulated.png"), (std::array<int, 2>{3 * 48 + 2 * 8, 48}));
  EXPECT_EQ(png_size(dir_ / "plane/preview/height_map.png"), (std::array<int, 2>{240, 240}));
  EXPECT_GT(fs::file_size(dir_ / "plane/print/surface.stl"), binary_stl_size(2 * 144));  // facets and walls
  expect_admesh_clean(dir_ / "plane/print/surface.stl");
  EXPECT_EQ(nlohmann::json::parse(read(dir_ / "plane" / "tree.json"))["children"][0]["type"], "plane");

  const auto lensed = run("lens");
  ASSERT_TRUE(lensed.contains("caustics"));
  EXPECT_EQ(nlohmann::json::parse(read(dir_ / "lens" / "tree.json"))["children"][0]["type"], "paraboloid");
  // Centroid and spread (mm) within a fraction of a pixel of the kernels'.
  EXPECT_LT(lensed["caustics"]["aim"]["max_miss_mm"].get<double>(), 0.3);
  expect_admesh_clean(dir_ / "lens/print/surface.stl");
  const std::string setup = "--distance 200 --image 48 48 --rays 576 576";
  const auto planes = caustic_check(dir_ / "plane/print/surface.stl", goal, setup);
  const auto lenses = caustic_check(dir_ / "lens/print/surface.stl", goal, setup);
  ASSERT_TRUE(planes.contains("ssim") && lenses.contains("ssim"));
  EXPECT_GT(lenses["ssim"].get<double>(), planes["ssim"].get<double>() + 0.1) << planes << lenses;
  EXPECT_LT(lenses["rmse"].get<double>(), planes["rmse"].get<double>()) << planes << lenses;
  // Each run's headline is that tracer's figure for its file, beside the
  // simulated one, and the trace as the simulator's bilinear splat would
  // blur it (which smooths the facets' speckle: it scores higher).
  for (const auto& [run_result, checked] : {std::pair{&result, &planes}, std::pair{&lensed, &lenses}}) {
    const auto& headline = (*run_result)["headline"];
    EXPECT_NEAR(headline["ssim"].get<double>(), (*checked)["ssim"].get<double>(), 1e-8) << headline;
    EXPECT_EQ(headline["rays"], 576 * 576);
    EXPECT_EQ(headline["simulated_ssim"], (*run_result)["caustics"]["ssim"]);
    if (std::abs(headline["ssim_difference"].get<double>()) > 0.02)
      EXPECT_GT(headline["splatted_ssim"].get<double>(), headline["ssim"].get<double>()) << headline;
    else
      EXPECT_FALSE(headline.contains("splatted_ssim")) << headline;
    EXPECT_FALSE(headline["agreement"].get<std::string>().empty());
  }
}

// Lenses aimed where optimal transport sends their squares' light
// ("targets": "transport", the default): one aim phase, no kernels; they
// meet within 0.01 mm, so they print as one height field refined where the
// light spreads, a closed 2-manifold that casts the ring far better than
// the flat board under caustic_check, the run's headline. Refinement asks
// for those lenses.
TEST_F(Cli, FacetCausticsAimAtTheTransportAndPrintOneHeightField) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  write_clear_printer(dir_ / "clear_printer.json");
  const fs::path goal = kDatasets / "images/caustic_ring_120.png";
  const auto body = [&](const std::string& targets, int facets, int subdivisions) {
    return R"({"name": "facets", "translator": "facet_caustics",
            "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
            "goal": {"image": ")" + goal.string() + R"(", "targets": ")" + targets + R"(",
                     "facets": [)" + std::to_string(facets) + ", " + std::to_string(facets) + R"(],
                     "lens_subdivisions": )" + std::to_string(subdivisions) + R"(, "lens_refinement_levels": 1,
                     "image_size": [48, 48], "rays": [144, 144], "distance_mm": 200,
                     "min_height_mm": 2, "start_height_mm": 5, "print_check_rays": [576, 576]},
            "output": {"slices": false, "stl": true, "3mf": false, "render": false},
            "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
            "printer": ")" + (dir_ / "clear_printer.json").string() + R"("})";
  };
  const Result refused = run_spec2fab("validate " + experiment("kernels", body("kernels", 24, 2)).string());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(single_line(refused.out), HasSubstr("/goal/lens_refinement_levels: refines lenses aimed at the transport"));
  const Result r = run_spec2fab("run -q " + experiment("transport", body("transport", 120, 1)).string() + " --out " +
                                (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  const auto& caustics = result["caustics"];
  EXPECT_EQ(caustics["targets"], "transport");
  EXPECT_FALSE(caustics.contains("kernels"));
  ASSERT_EQ(result["tuning"]["phases"].size(), 1u);
  EXPECT_EQ(result["tuning"]["phases"][0]["tuner_runs"], 120 * 120);
  // Centroid and spread within a fraction of a pixel (1.25 mm) of the transport's.
  EXPECT_LT(caustics["aim"]["max_miss_mm"].get<double>(), 0.3);
  // 120 x 120 lenses meet within the 0.01 mm a print bridges and print as
  // one height field.
  EXPECT_LT(caustics["stitch"]["max_step_mm"].get<double>(), 0.01);
  EXPECT_TRUE(caustics["print_mesh"].get<std::string>().starts_with("one height field")) << caustics["print_mesh"];
  EXPECT_GT(caustics["ssim"].get<double>(), caustics["initial_ssim"].get<double>() + 0.1);
  expect_admesh_clean(dir_ / "run/print/surface.stl");
  const std::string setup = "--distance 200 --image 48 48 --rays 576 576";
  const auto printed = caustic_check(dir_ / "run/print/surface.stl", goal, setup);
  const auto flat = caustic_check(kDatasets / "meshes/board_60x60x8.stl", goal, setup);
  EXPECT_GT(printed["ssim"].get<double>(), flat["ssim"].get<double>() + 0.1) << printed << flat;
  EXPECT_NEAR(result["headline"]["ssim"].get<double>(), printed["ssim"].get<double>(), 1e-8);
  // 24 x 24 lenses are farther from the transport's map (each one's map is
  // affine): steps over 0.01 mm, so each lens is its own grid with walls,
  // and the walls where lenses meet within a rounding leave no degenerate
  // facet.
  const Result walls = run_spec2fab("run -q " + experiment("walls", body("transport", 24, 2)).string() + " --out " +
                                    (dir_ / "walls").string());
  ASSERT_EQ(walls.code, 0) << walls.out;
  const auto walled = nlohmann::json::parse(read(dir_ / "walls" / "result.json"))["caustics"];
  EXPECT_GT(walled["stitch"]["max_step_mm"].get<double>(), 0.01);
  EXPECT_EQ(walled["print_mesh"], "2 x 2 cells per facet, walls between facets");
  expect_admesh_clean(dir_ / "walls/print/surface.stl");
}

TEST_F(Cli, CausticsTextureTunesTheTextureThenTheBottomFaceThroughItsShadow) {
  SPEC2FAB_SKIP_UNLESS(SPEC2FAB_WITH_NLOPT);
  std::ofstream(dir_ / "ink_printer.json") << R"({"name": "coarse-inks", "technology": "polyjet",
      "resolution_dpi": [63.5, 63.5], "layer_mm": 0.4, "build_volume_mm": [200, 200, 200],
      "model_materials": ["VeroClear", "VeroCyan", "VeroWhitePlus"], "source": "test"})";
  const auto run = [&](const std::string& name, bool compensate) {
    const std::string body =
        R"({"name": ")" + name + R"(", "translator": "caustics_texture",
            "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
            "goal": {"image": ")" + (kDatasets / "images/caustic_ring_120.png").string() + R"(",
                     "texture": ")" + (kDatasets / "images/texture_s2f_64.png").string() + R"(",
                     "texture_columns": [8, 8], "inks": ["VeroCyan", "VeroWhitePlus"], "layer_step_mm": 0.1,
                     "max_ink_mm": [0.1, 0.3], "control": [6, 6], "image_size": [48, 48], "rays": [96, 96],
                     "distance_mm": 60, "min_thickness_mm": 2, "start_thickness_mm": 6,
                     "compensate_texture": )" + (compensate ? "true" : "false") + R"(},
            "optimizer": {"type": "nlopt", "algorithm": "LD_LBFGS", "max_evaluations": 15},
            "output": {"slices": false, "stl": true, "3mf": false, "render": false},
            "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
            "printer": ")" + (dir_ / "ink_printer.json").string() + R"("})";
    const Result r = run_spec2fab("run -q " + experiment(name, body).string() + " --out " + (dir_ / name).string());
    EXPECT_EQ(r.code, 0) << r.out;
    return r.code == 0 ? nlohmann::json::parse(read(dir_ / name / "result.json")) : nlohmann::json::object();
  };
  const auto result = run("window", true);
  ASSERT_TRUE(result.contains("caustics"));
  const auto& texture = result["texture"];
  const auto& caustics = result["caustics"];
  // Two phases: one run per texture column, then one for the bottom face.
  ASSERT_EQ(result["tuning"]["phases"].size(), 2u);
  EXPECT_EQ(result["tuning"]["phases"][0]["name"], "texture");
  EXPECT_EQ(result["tuning"]["phases"][0]["tuner_runs"], 64);
  EXPECT_EQ(result["tuning"]["phases"][1]["tuner_runs"], 1);
  EXPECT_NEAR(texture["thickness_mm"].get<double>(), 0.4, 1e-12);
  // The picture has clear ground and white letters: the texture's shadow varies.
  EXPECT_LT(texture["transmittance"]["min"].get<double>(), 0.8 * texture["transmittance"]["max"].get<double>());
  // The caustic phase tuned against what the print casts: the reported
  // error of the cast image is the tuner's own final error (exit filter
  // installed, goal scaled to the light the texture lets through).
  const double final_mse = result["tuning"]["phases"][1]["sum_final_error"].get<double>();
  EXPECT_NEAR(std::pow(caustics["rmse"].get<double>(), 2), final_mse, 1e-9 * final_mse);
  EXPECT_LT(caustics["rmse"].get<double>(), 0.95 * caustics["initial_rmse"].get<double>());
  // It started from optimal transport to the goal (goal.start's default).
  EXPECT_EQ(caustics["start"]["method"], "optimal transport");
  EXPECT_GT(caustics["start"]["relief_mm"].get<double>(), 0.0);
  // Ignoring the texture, the tuner's error is not that of the cast image.
  const auto ignoring = run("ignoring", false);
  ASSERT_TRUE(ignoring.contains("caustics"));
  const double ignoring_mse = ignoring["tuning"]["phases"][1]["sum_final_error"].get<double>();
  EXPECT_GT(std::abs(std::pow(ignoring["caustics"]["rmse"].get<double>(), 2) - ignoring_mse), 1e-3 * ignoring_mse);
  EXPECT_EQ(ignoring["caustics"]["initial_rmse"], caustics["initial_rmse"]);
  // surface.stl: the clear slab in print coordinates — flat top at the
  // board's top (z = 8), shaped bottom no thinner than 2 mm — and traced
  // back through the texture it casts the simulated image.
  const auto& stl = caustics["surface_stl"];
  EXPECT_NEAR(stl["z_range_mm"][1].get<double>(), 8.0, 1e-9);
  EXPECT_GE(stl["z_range_mm"][0].get<double>(), -1e-9);
  EXPECT_LE(stl["z_range_mm"][0].get<double>(), 6.0 + 1e-9);
  EXPECT_LT(stl["largest_height_error_mm"].get<double>(), 1e-4);
  // The simulation's 2 rays per pixel pitch are noisy; the check traces 8.
  EXPECT_LT(stl["traced_relative_rmse_vs_simulated"].get<double>(), 0.6);
  EXPECT_EQ(fs::file_size(dir_ / "window/print/surface.stl"), binary_stl_size(stl["triangles"].get<std::uintmax_t>()));
  expect_admesh_clean(dir_ / "window/print/surface.stl");
  // The headline: caustic_check traces the file upside down, through the
  // texture's transmittance, and the inks take about the light their mean
  // transmittance says (the light leaves through the cells unevenly).
  const auto& headline = result["headline"];
  EXPECT_NEAR(headline["absorbed"].get<double>(), 1 - texture["transmittance"]["mean"].get<double>(), 0.05) << headline;
  EXPECT_GT(headline["absorbed"].get<double>(), 0.05) << headline;
  EXPECT_EQ(headline["simulated_ssim"], caustics["ssim"]);
  // The simulator traces rays here: where the two differ, the file traced
  // again at its ray count, splatted as it splats, and the simulator's own
  // rays estimator run on the file's mesh (finer than the tuner's).
  const bool differ = std::abs(headline["ssim_difference"].get<double>()) > 0.02;
  EXPECT_EQ(headline.contains("splatted_ssim"), differ) << headline;
  EXPECT_EQ(headline.contains("printed_rays_ssim"), differ) << headline;
  if (headline.contains("printed_rays_ssim") &&
      std::abs(headline["printed_rays_ssim"].get<double>() - headline["ssim"].get<double>()) <= 0.02) {
    EXPECT_THAT(headline["agreement"].get<std::string>(), HasSubstr("coarser mesh (16 x 16 vertices, 3 per control span)"))
        << headline;
  }
  EXPECT_EQ(png_size(dir_ / "window/preview/print_traced.png"), (std::array<int, 2>{2 * 48 + 8, 48}));
  // Texture: goal | printed | transmittance, 8 columns at 32 px each.
  EXPECT_EQ(png_size(dir_ / "window/preview/texture.png"), (std::array<int, 2>{3 * 256 + 2 * 8, 256}));
  EXPECT_EQ(png_size(dir_ / "window/preview/goal_vs_simulated.png"), (std::array<int, 2>{2 * 48 + 8, 48}));
  // The texture piece reports as the albedo translator does.
  EXPECT_EQ(texture["error_diffusion"], true);
  EXPECT_EQ(texture["columns"], nlohmann::json::array({8, 8}));
  const auto tree = nlohmann::json::parse(read(dir_ / "window" / "tree.json"));
  EXPECT_EQ(tree["type"], "plane");
  EXPECT_EQ(tree["above"]["type"], "column");
  EXPECT_EQ(tree["below"]["type"], "bspline");
  // Seen from the room (above the top face) the picture reads right: its
  // lower half, blue waves, lies at low y, so the columns there carry the
  // cyan; its upper half (dark ground, pale letters) at high y carries little.
  double cyan_low_y = 0, cyan_high_y = 0;
  const auto& columns = tree["above"]["children"];
  ASSERT_EQ(columns.size(), 64u);
  for (size_t k = 0; k < 64; ++k) {
    const auto& layer = columns[k]["below"]["layers"][0];
    ASSERT_EQ(layer["material"], "VeroCyan");
    const auto& thickness = layer["thickness_mm"];
    (k / 8 < 4 ? cyan_low_y : cyan_high_y) += thickness.is_object() ? thickness["value"].get<double>() : thickness.get<double>();
  }
  EXPECT_GT(cyan_low_y, 2 * cyan_high_y + 0.1) << cyan_low_y << " " << cyan_high_y;
}

TEST_F(Cli, SubsurfaceChessboardTunesEveryColumnAndReportsProfileErrors) {
  const std::string body =
      R"({"name": "board", "translator": "subsurface",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/board_60x60x8.stl").string() + R"(", "uv": "planar"},
          "goal": {"media": ["marble", "skimmilk"], "columns": [2, 2], "layers": 2,
                   "materials": ["VeroWhitePlus", "VeroCyan"], "thickness_steps": [1, 2],
                   "radius_mm": 8, "samples": 128},
          "output": {"slices": false, "stl": false, "3mf": false, "render": false},
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (dir_ / "coarse_printer.json").string() + R"("})";
  const Result r = run_spec2fab("run -q " + experiment("board", body).string() + " --out " + (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.out;
  const auto result = nlohmann::json::parse(read(dir_ / "run" / "result.json"));
  const auto& s = result["subsurface"];
  EXPECT_EQ(s["stacks"].size(), 4u);
  // Diagonal squares hold the same medium and reach the same stack and error.
  EXPECT_EQ(s["stacks"][0]["layers"], s["stacks"][3]["layers"]);
  EXPECT_EQ(s["stacks"][1]["layers"], s["stacks"][2]["layers"]);
  EXPECT_GT(s["profile_rms_per_mm2"]["mean"].get<double>(), 0);
  EXPECT_EQ(s["branch_and_bound"]["exhaustive_candidates_per_column"].get<double>(), 16);
  EXPECT_LE(s["branch_and_bound"]["fraction_of_exhaustive"]["max"].get<double>(), 1);
  for (const char* file : {"convergence.png", "profiles.png", "appearance.png"}) {
    EXPECT_TRUE(fs::is_regular_file(dir_ / "run" / "preview" / file)) << file;
  }
}

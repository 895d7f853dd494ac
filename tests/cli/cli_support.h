#pragma once
// Shared by the CLI tests: running the spec2fab command and a fixture with a
// fresh folder per test.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace spec2fab_cli_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

struct Result {
  int code;
  std::string out;  // stdout and stderr
};

/// Runs a shell command line, stderr with stdout.
inline Result run_command(const std::string& line) {
  const std::string command = line + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline Result run_spec2fab(const std::string& arguments) {
  // Appended, not `path + " " + arguments`: GCC 12 warns falsely (-Warray-bounds)
  // on that temporary once inlined.
  std::string command = SPEC2FAB_CLI_PATH;
  command += ' ';
  command += arguments;
  return run_command(command);
}

const fs::path kDatasets = SPEC2FAB_DATASETS_DIR;

// An experiment of two FEM tuners on the 100 x 10 x 10 mm beam (clamped at
// x = 0, 1 N down on the end face): a plane at x = 50, each half's material
// VeroWhitePlus or DM9860 tuned by exhaustive search to a goal tip
// deflection, both in one phase of `mode` (serial or parallel), on the FEM's
// `linear_solver`. `output` is the experiment's output section, or "".
inline std::string two_fem_tuners_body(const std::string& mode, const std::string& linear_solver,
                                       const std::string& output) {
  auto tuner = [&](const std::string& name, const std::string& node) {
    return R"({"name": ")" + name + R"(", "node": ")" + node + R"(",
        "simulator": {"type": "fem", "max_tet_volume_mm3": 5, "nonlinear": false, "linear_solver": ")" +
           linear_solver + R"(",
                      "fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}],
                      "loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 0, -1]}],
                      "probes": [[100, 5, 5]]},
        "metric": {"type": "shape_mse"},
        "goal": {"type": "deformed_shape", "points": [[100, 5, 5]], "targets": [[100, 5, 3]]},
        "optimizer": {"type": "exhaustive"}})";
  };
  const std::string choice =
      R"({"type": "layered", "material": {"value": "VeroWhitePlus", "choices": ["VeroWhitePlus", "DM9860"]}})";
  return R"({"name": "two_fem_tuners", "translator": "tree",
          "geometry": {"mesh": ")" + (kDatasets / "meshes/beam_100x10x10.stl").string() + R"(", "uv": "planar"},
          "goal": {"tree": {"type": "plane", "axis": "x", "offset_mm": 50, "below": )" + choice + R"(, "above": )" +
         choice + R"(},
                   "tuners": [)" + tuner("near", "below") + ", " + tuner("far", "above") + R"(],
                   "schedule": [{"name": "both", "mode": ")" + mode + R"("}]},)" +
         (output.empty() ? std::string() : R"("output": )" + output + ",") + R"(
          "materials": ")" + (kDatasets / "materials/polyjet.json").string() + R"(",
          "printer": ")" + (kDatasets / "printers/objet500_connex_flex.json").string() + R"(", "seed": 1})";
}

inline std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// report.html's JSON block `id` ("spec2fab-data", "spec2fab-timing")
/// parsed; null when absent.
inline nlohmann::json page_block(const std::string& page, const std::string& id) {
  const std::string open = R"(<script type="application/json" id=")" + id + R"(">)";
  const size_t start = page.find(open);
  if (start == std::string::npos) return nullptr;
  const size_t from = start + open.size();
  return nlohmann::json::parse(page.substr(from, page.find("</script>", from) - from));
}

/// report.html with its copy of timing.json emptied: the one block a rerun
/// may change.
inline std::string without_timing_block(std::string page) {
  const std::string open = R"(<script type="application/json" id="spec2fab-timing">)";
  const size_t start = page.find(open);
  if (start == std::string::npos) return page;
  const size_t from = start + open.size();
  return page.erase(from, page.find("</script>", from) - from);
}

/// Every file under `folder` but timing.json (wall times), by relative path;
/// report.html without its timing block.
inline std::map<std::string, std::string> files_of(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (!entry.is_regular_file() || entry.path().filename() == "timing.json") continue;
    std::string bytes = read(entry.path());
    if (entry.path().filename() == "report.html") bytes = without_timing_block(std::move(bytes));
    files[fs::relative(entry.path(), folder).string()] = std::move(bytes);
  }
  return files;
}

/// Every file of `expected` is in `out`, byte for byte, and nothing else;
/// `how` names the run in failures.
inline void expect_same_files(const std::map<std::string, std::string>& expected, const fs::path& out,
                              const std::string& how) {
  const std::map<std::string, std::string> got = files_of(out);
  ASSERT_EQ(got.size(), expected.size()) << how;
  for (const auto& [name, bytes] : expected) {
    const auto found = got.find(name);
    ASSERT_NE(found, got.end()) << name << " missing " << how;
    EXPECT_TRUE(found->second == bytes) << name << " differs " << how;
  }
}

class Cli : public ::testing::Test {
 protected:
  Cli()
      : dir_(fs::temp_directory_path() /
             ("spec2fab_cli_" + std::to_string(getpid()) + "_" +
              ::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // Runs fabricate at the printer's resolution: a coarse printer (0.4 mm
    // voxels) keeps them fast; the shipped printers would print 2e9 voxels.
    std::ofstream(dir_ / "coarse_printer.json") << kCoarsePrinter;
  }
  static constexpr const char* kCoarsePrinter =
      R"({"name": "coarse", "technology": "polyjet", "resolution_dpi": [63.5, 63.5], "layer_mm": 0.4,
          "build_volume_mm": [200, 200, 200], "model_materials": ["VeroCyan", "VeroWhitePlus"],
          "print_time": {"source": "test: the jetting model's defaults"}, "source": "test"})";
  ~Cli() override { fs::remove_all(dir_); }

  // Writes an experiment whose paths point into datasets/.
  fs::path experiment(const std::string& name, const std::string& body) {
    const fs::path file = dir_ / (name + ".json");
    std::ofstream(file) << body;
    return file;
  }
  std::string valid_body(const std::string& tree, const std::string& extra = "",
                         const std::string& translator = "tree") {
    return R"({"translator": ")" + translator + R"(", "geometry": {"mesh": ")" +
           (kDatasets / "meshes/sphere_r25.obj").string() +
           R"(", "uv": "mesh"}, "goal": {"tree": )" + tree + R"(}, "materials": ")" +
           (kDatasets / "materials/polyjet.json").string() + R"(", "printer": ")" +
           (dir_ / "coarse_printer.json").string() + "\"" + extra + "}";
  }
  static std::string single_line(const std::string& s) {
    EXPECT_EQ(std::count(s.begin(), s.end(), '\n'), 1) << s;
    return s;
  }

  fs::path dir_;
};

}  // namespace spec2fab_cli_test

// The spec2fab command as users run it: exit codes, one-line errors, no
// partial output, byte-identical results for any thread count.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

struct Result {
  int code;
  std::string out;  // stdout and stderr
};

Result spec2fab(const std::string& arguments) {
  const std::string command = std::string(SPEC2FAB_CLI_PATH) + " " + arguments + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  while (size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) out.append(buffer.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

const fs::path kDatasets = SPEC2FAB_DATASETS_DIR;

class Cli : public ::testing::Test {
 protected:
  Cli() : dir_(fs::temp_directory_path() / ("spec2fab_cli_" + std::to_string(getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~Cli() override { fs::remove_all(dir_); }

  // Writes an experiment whose paths point into datasets/.
  fs::path experiment(const std::string& name, const std::string& body) {
    const fs::path file = dir_ / (name + ".json");
    std::ofstream(file) << body;
    return file;
  }
  std::string valid_body(const std::string& tree, const std::string& extra = "",
                         const std::string& translator = "tree") {
    return R"({"translator": ")" + translator + R"(", "geometry": {"mesh": ")" + (kDatasets / "meshes/sphere_r25.obj").string() +
           R"(", "uv": "mesh"}, "goal": {"tree": )" + tree + R"(}, "materials": ")" +
           (kDatasets / "materials/polyjet.json").string() + R"(", "printer": ")" +
           (kDatasets / "printers/objet500_connex.json").string() + "\"" + extra + "}";
  }
  static std::string single_line(const std::string& s) {
    EXPECT_EQ(std::count(s.begin(), s.end(), '\n'), 1) << s;
    return s;
  }

  fs::path dir_;
};

const char* kTree = R"({"type": "stratum", "depth_mm": 1, "shell": {"type": "layered", "material": "VeroCyan"}, "core": {"type": "layered", "material": "VeroWhitePlus"}})";

TEST_F(Cli, HelpAnswersForEveryCommand) {
  for (const char* command : {"--help", "run --help", "validate --help", "list --help"}) {
    const Result r = spec2fab(command);
    EXPECT_EQ(r.code, 0) << command;
    EXPECT_THAT(r.out, HasSubstr("Usage")) << command;
  }
}

TEST_F(Cli, ValidateAcceptsShippedExperiments) {
  for (const auto& entry : fs::directory_iterator(kDatasets / "experiments")) {
    const Result r = spec2fab("validate " + entry.path().string());
    EXPECT_EQ(r.code, 0) << entry.path() << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr(": ok"));
  }
}

TEST_F(Cli, ListShowsNodesTranslatorsMaterialsAndPrinters) {
  const Result r = spec2fab("list");
  EXPECT_EQ(r.code, 0);
  for (const char* name : {"stratum", "column", "voxel", "bspline", "plane", "layered", "tree",
                           "VeroCyan", "objet500_connex.json", "j750.json"}) {
    EXPECT_THAT(r.out, HasSubstr(name));
  }
  const Result verbose = spec2fab("list node --verbose");
  EXPECT_THAT(verbose.out, HasSubstr("depth_mm"));
  EXPECT_THAT(verbose.out, HasSubstr("example:"));
  EXPECT_EQ(spec2fab("list nodez").code, 2);
  const Result bad_flag = spec2fab("run --threads 0 x.json");
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
      {valid_body(kTree, "", "albedo"), "/translator: unknown translator 'albedo'"},
  };
  for (const Case& c : cases) {
    const fs::path file = experiment("bad", c.body);
    for (const std::string& command : {"validate " + file.string(),
                                      "run " + file.string() + " --out " + (dir_ / "out").string()}) {
      const Result r = spec2fab(command);
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
  const Result r = spec2fab("validate " + experiment("open", body).string());
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(single_line(r.out), HasSubstr("open.obj: not closed: 3 boundary edges"));
}

std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(Cli, RunWritesFolderIdenticalForAnyThreadCount) {
  const fs::path file = experiment("det", valid_body(kTree));
  const Result one = spec2fab("run -q " + file.string() + " --threads 1 --out " + (dir_ / "t1").string());
  const Result two = spec2fab("run -q " + file.string() + " --threads 2 --out " + (dir_ / "t2").string());
  ASSERT_EQ(one.code, 0) << one.out;
  ASSERT_EQ(two.code, 0) << two.out;
  int compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_ / "t1")) {
    if (!entry.is_regular_file() || entry.path().filename() == "timing.json") continue;
    const fs::path other = dir_ / "t2" / fs::relative(entry.path(), dir_ / "t1");
    EXPECT_EQ(read(entry.path()), read(other)) << entry.path();
    ++compared;
  }
  EXPECT_GE(compared, 5);  // result.json, tree.json, three previews
  // No staging folder is left behind.
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr("partial")));
  }
}

TEST_F(Cli, TreeJsonRunsAgainAsAGoal) {
  // tree.json is a tree in the experiment format: feeding it back gives the same tree.
  const fs::path first = experiment("first", valid_body(kTree));
  ASSERT_EQ(spec2fab("run -q " + first.string() + " --out " + (dir_ / "a").string()).code, 0);
  const std::string tree = read(dir_ / "a" / "tree.json");
  const fs::path second = experiment("second", valid_body(tree));
  ASSERT_EQ(spec2fab("run -q " + second.string() + " --out " + (dir_ / "b").string()).code, 0);
  EXPECT_EQ(read(dir_ / "b" / "tree.json"), tree);
}

}  // namespace
